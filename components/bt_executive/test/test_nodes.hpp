// Instrumented nodes shared by the engine tests.
#pragma once

#include <algorithm>
#include <string>
#include <vector>

#include "cairn/bt_executive/factory.hpp"
#include "cairn/bt_executive/trace.hpp"
#include "cairn/bt_executive/xml_loader.hpp"

namespace cairn::bt::testing {

/// Log of what the instrumented nodes did, and how many async actions were running at the same time.
struct Journal {
  std::vector<std::string> events;
  int active = 0;
  int max_active = 0;
  void start(const std::string& n) {
    events.push_back(n + ".start");
    ++active;
    max_active = std::max(max_active, active);
  }
  void stop(const std::string& n, const char* how) {
    events.push_back(n + "." + how);
    --active;
  }
  std::size_t count(const std::string& e) const { return std::count(events.begin(), events.end(), e); }
  std::ptrdiff_t indexOf(const std::string& e) const {
    auto it = std::find(events.begin(), events.end(), e);
    return it == events.end() ? -1 : it - events.begin();
  }
};

inline Journal* g_journal = nullptr;

/// Async action: RUNNING for `ticks` onRunning calls, then `result`.
class TestAsync : public StatefulActionNode {
 public:
  explicit TestAsync(const NodeConfig& c)
      : StatefulActionNode(c), ticks_(c.input<int>("ticks")), result_(c.input<std::string>("result")) {}
  static PortList providedPorts() {
    return {InputPortWithDefault<int>("ticks", "2"), InputPortWithDefault<std::string>("result", "SUCCESS")};
  }

 protected:
  NodeStatus onStart() override {
    left_ = ticks_.get().value_or(2);
    g_journal->start(name());
    return left_ <= 0 ? finish() : NodeStatus::RUNNING;
  }
  NodeStatus onRunning() override { return --left_ <= 0 ? finish() : NodeStatus::RUNNING; }
  void onHalted() override { g_journal->stop(name(), "halt"); }

 private:
  NodeStatus finish() {
    g_journal->stop(name(), "done");
    return result_.get().value_or("SUCCESS") == "SUCCESS" ? NodeStatus::SUCCESS : NodeStatus::FAILURE;
  }
  Input<int> ticks_;
  Input<std::string> result_;
  int left_ = 0;
};

/// Condition on a boolean blackboard entry; journals each tick.
class TestCond : public ConditionNode {
 public:
  explicit TestCond(const NodeConfig& c) : ConditionNode(c), flag_(c.input<bool>("flag")) {}
  static PortList providedPorts() { return {InputPort<bool>("flag")}; }

 protected:
  NodeStatus onTick() override {
    g_journal->events.push_back(name() + ".tick");
    return flag_.get().value_or(false) ? NodeStatus::SUCCESS : NodeStatus::FAILURE;
  }

 private:
  Input<bool> flag_;
};

/// Sync action that journals its ticks and returns `result`.
class TestSync : public SyncActionNode {
 public:
  explicit TestSync(const NodeConfig& c) : SyncActionNode(c), result_(c.input<std::string>("result")) {}
  static PortList providedPorts() { return {InputPortWithDefault<std::string>("result", "SUCCESS")}; }

 protected:
  NodeStatus onTick() override {
    g_journal->events.push_back(name() + ".tick");
    std::string r;
    result_.get(r);
    return r == "FAILURE" ? NodeStatus::FAILURE : NodeStatus::SUCCESS;
  }

 private:
  Input<std::string> result_;
};

/// Typed nodes for port-type tests.
class WriteInt : public SyncActionNode {
 public:
  explicit WriteInt(const NodeConfig& c) : SyncActionNode(c), out_(c.output<int>("out")), v_(c.input<int>("value")) {}
  static PortList providedPorts() { return {OutputPort<int>("out"), InputPortWithDefault<int>("value", "7")}; }

 protected:
  NodeStatus onTick() override { return out_.set(v_.get().value_or(0)) ? NodeStatus::SUCCESS : NodeStatus::FAILURE; }

 private:
  Output<int> out_;
  Input<int> v_;
};

class ReadString : public SyncActionNode {
 public:
  explicit ReadString(const NodeConfig& c) : SyncActionNode(c), in_(c.input<std::string>("in")) {}
  static PortList providedPorts() { return {InputPort<std::string>("in")}; }

 protected:
  NodeStatus onTick() override { return in_.get() ? NodeStatus::SUCCESS : NodeStatus::FAILURE; }

 private:
  Input<std::string> in_;
};

struct Pose2 {
  double x = 0, y = 0;
};

class ReadPose : public SyncActionNode {
 public:
  explicit ReadPose(const NodeConfig& c) : SyncActionNode(c), in_(c.input<Pose2>("pose")) {}
  static PortList providedPorts() { return {InputPort<Pose2>("pose")}; }

 protected:
  NodeStatus onTick() override { return in_.get() ? NodeStatus::SUCCESS : NodeStatus::FAILURE; }

 private:
  Input<Pose2> in_;
};

inline NodeFactory makeFactory() {
  NodeFactory f;
  f.registerNodeType<TestAsync>("TestAsync");
  f.registerNodeType<TestCond>("TestCond");
  f.registerNodeType<TestSync>("TestSync");
  f.registerNodeType<WriteInt>("WriteInt");
  f.registerNodeType<ReadString>("ReadString");
  f.registerNodeType<ReadPose>("ReadPose");
  return f;
}

inline std::string wrap(const std::string& body) {
  return "<root BTCPP_format=\"4\"><BehaviorTree ID=\"Main\">" + body + "</BehaviorTree></root>";
}

/// Records the --trace lines of a tree.
struct TraceRecorder {
  std::vector<std::string> lines;
  explicit TraceRecorder(Tree& t) {
    t.addObserver([this](const TransitionEvent& e) {
      lines.push_back(formatTransition(e.step, e.path, e.old_status, e.new_status));
    });
  }
  bool has(const std::string& l) const { return std::find(lines.begin(), lines.end(), l) != lines.end(); }
};

}  // namespace cairn::bt::testing
