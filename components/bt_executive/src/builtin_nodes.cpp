// Built-in controls, decorators and actions. Semantics follow Stüde §5.2.1 (Sequence = Alg. 5.1, Fallback =
// Alg. 5.2, memoryless and reactive at the root) and BehaviorTree.CPP v4 for the node kinds the thesis leaves out
// (memory, parallel, async). Deliberate differences are listed in the README ("Semantics").
#include <algorithm>

#include "cairn/bt_executive/factory.hpp"

namespace cairn::bt {
namespace {

/// A duration port given as a literal must not be negative: a load error (file:line) instead of a node that
/// silently finishes or fails at once. Values from the blackboard are only known at run time.
Input<int> durationInput(const NodeConfig& c, const char* port) {
  Input<int> in = c.input<int>(port);
  int ms = 0;
  if (in.isLiteral() && in.get(ms) && ms < 0)
    throw PortError("port '" + std::string(port) + "' must not be negative, got " + std::to_string(ms));
  return in;
}

// ================================================================================================== controls
/// Sequence (Stüde Alg. 5.1 with BT.CPP's resumption at the running child) and SequenceWithMemory.
class SequenceNode : public ControlNode {
 public:
  SequenceNode(const NodeConfig& c, bool memory) : ControlNode(c), memory_(memory) {}

 protected:
  NodeStatus tick() override {
    if (status() != NodeStatus::RUNNING && !(memory_ && idx_ > 0)) skipped_ = 0;
    setStatus(NodeStatus::RUNNING);
    const std::size_t n = children_.size();
    while (idx_ < n) {
      const NodeStatus s = children_[idx_]->executeTick();
      switch (s) {
        case NodeStatus::RUNNING: return s;
        case NodeStatus::FAILURE:
          if (memory_) {
            haltChildren(idx_);  // keep idx_: the next tick retries the failed child
          } else {
            haltChildren();
            idx_ = 0;
          }
          return s;
        case NodeStatus::SKIPPED: ++skipped_; [[fallthrough]];
        case NodeStatus::SUCCESS: ++idx_; break;
        case NodeStatus::IDLE: reportError("child returned IDLE"); return NodeStatus::FAILURE;
      }
    }
    const bool all_skipped = skipped_ == n;
    haltChildren();
    idx_ = 0;
    skipped_ = 0;
    return all_skipped ? NodeStatus::SKIPPED : NodeStatus::SUCCESS;
  }
  void halt() override {
    idx_ = 0;
    skipped_ = 0;
    ControlNode::halt();
  }

 private:
  bool memory_;
  std::size_t idx_ = 0, skipped_ = 0;
};

/// Fallback (Stüde Alg. 5.2).
class FallbackNode : public ControlNode {
 public:
  using ControlNode::ControlNode;

 protected:
  NodeStatus tick() override {
    if (status() != NodeStatus::RUNNING) skipped_ = 0;
    setStatus(NodeStatus::RUNNING);
    const std::size_t n = children_.size();
    while (idx_ < n) {
      const NodeStatus s = children_[idx_]->executeTick();
      switch (s) {
        case NodeStatus::RUNNING: return s;
        case NodeStatus::SUCCESS:
          haltChildren();
          idx_ = 0;
          return s;
        case NodeStatus::SKIPPED: ++skipped_; [[fallthrough]];
        case NodeStatus::FAILURE: ++idx_; break;
        case NodeStatus::IDLE: reportError("child returned IDLE"); return NodeStatus::FAILURE;
      }
    }
    const bool all_skipped = skipped_ == n;
    haltChildren();
    idx_ = 0;
    skipped_ = 0;
    return all_skipped ? NodeStatus::SKIPPED : NodeStatus::FAILURE;
  }
  void halt() override {
    idx_ = 0;
    skipped_ = 0;
    ControlNode::halt();
  }

 private:
  std::size_t idx_ = 0, skipped_ = 0;
};

/// ReactiveSequence / ReactiveFallback: every tick restarts at the first child. Unlike BehaviorTree.CPP (issue
/// #1031), the RUNNING child is halted *before* a different child starts running: the control registers it with
/// the context while ticking an earlier child, and the first node below that starts (TreeNode::aboutToRun())
/// halts it. Synchronous conditions in front of the running child therefore do not disturb it.
class ReactiveNode : public ControlNode {
 public:
  ReactiveNode(const NodeConfig& c, bool sequence) : ControlNode(c), sequence_(sequence) {}

 protected:
  NodeStatus tick() override {
    setStatus(NodeStatus::RUNNING);
    const std::size_t n = children_.size();
    const NodeStatus stop = sequence_ ? NodeStatus::FAILURE : NodeStatus::SUCCESS;
    std::size_t skipped = 0;
    for (std::size_t i = 0; i < n; ++i) {
      TreeNode* running = running_ < n && running_ != i && children_[running_]->status() == NodeStatus::RUNNING
                              ? children_[running_]
                              : nullptr;
      if (running) context().pushPreemption(running);
      const NodeStatus s = children_[i]->executeTick();
      if (running) context().popPreemption();
      if (s == NodeStatus::RUNNING) {
        for (std::size_t j = 0; j < n; ++j)
          if (j != i) haltChild(j);  // resets completed children; the old running child is already halted
        running_ = i;
        return s;
      }
      if (s == stop) {
        haltChildren();
        running_ = kNone;
        return s;
      }
      if (s == NodeStatus::SKIPPED) {
        haltChild(i);
        ++skipped;
      }
      if (s == NodeStatus::IDLE) {
        reportError("child returned IDLE");
        return NodeStatus::FAILURE;
      }
    }
    haltChildren();
    running_ = kNone;
    if (skipped == n) return NodeStatus::SKIPPED;
    return sequence_ ? NodeStatus::SUCCESS : NodeStatus::FAILURE;
  }
  void halt() override {
    running_ = kNone;
    ControlNode::halt();
  }

 private:
  static constexpr std::size_t kNone = static_cast<std::size_t>(-1);
  bool sequence_;
  std::size_t running_ = kNone;
};

/// Parallel with success/failure thresholds (negative = children + value + 1, BT.CPP convention).
class ParallelNode : public ControlNode {
 public:
  explicit ParallelNode(const NodeConfig& c)
      : ControlNode(c), success_in_(c.input<int>("success_count")), failure_in_(c.input<int>("failure_count")) {}
  static PortList providedPorts() {
    return {InputPortWithDefault<int>("success_count", "-1", "children that must succeed (-1: all)"),
            InputPortWithDefault<int>("failure_count", "1", "failures that make the node fail")};
  }
  // Literal thresholds that cannot fit the children are a load error (file:line); before, the first tick failed
  // with a run-time warning. Thresholds from the blackboard, and skipped children, are checked when ticked.
  std::string validateChildren() const override {
    if (std::string err = ControlNode::validateChildren(); !err.empty()) return err;
    const int n = static_cast<int>(children_.size());
    int succ = -1, fail = 1;
    if (success_in_.isLiteral()) success_in_.get(succ);
    if (failure_in_.isLiteral()) failure_in_.get(fail);
    const int succ_thr = succ < 0 ? n + succ + 1 : succ;
    const int fail_thr = fail < 0 ? n + fail + 1 : fail;
    if (succ_thr > n || succ_thr <= 0 || fail_thr <= 0)
      return "Parallel thresholds success_count=" + std::to_string(succ) + " failure_count=" + std::to_string(fail) +
             " do not fit " + std::to_string(n) + " children";
    return {};
  }

 protected:
  NodeStatus tick() override {
    const int n = static_cast<int>(children_.size());
    if (status() != NodeStatus::RUNNING) reset();
    setStatus(NodeStatus::RUNNING);
    int succ_cfg = -1, fail_cfg = 1;
    success_in_.get(succ_cfg);
    failure_in_.get(fail_cfg);
    if (done_.size() != children_.size()) done_.assign(children_.size(), 0);
    for (int i = 0; i < n; ++i) {
      if (done_[static_cast<std::size_t>(i)]) continue;
      const NodeStatus s = children_[static_cast<std::size_t>(i)]->executeTick();
      if (s == NodeStatus::SUCCESS) ++success_;
      else if (s == NodeStatus::FAILURE) ++failure_;
      else if (s == NodeStatus::SKIPPED) ++skipped_;
      if (s != NodeStatus::RUNNING) done_[static_cast<std::size_t>(i)] = 1;
      const int active = n - skipped_;
      const int succ_thr = succ_cfg < 0 ? active + succ_cfg + 1 : succ_cfg;
      const int fail_thr = fail_cfg < 0 ? active + fail_cfg + 1 : fail_cfg;
      if (skipped_ == n) return finish(NodeStatus::SKIPPED);
      if (succ_thr > active || succ_thr <= 0 || fail_thr <= 0) {
        reportError("Parallel thresholds success_count=" + std::to_string(succ_cfg) + " failure_count=" +
                    std::to_string(fail_cfg) + " do not fit " + std::to_string(active) + " children");
        return finish(NodeStatus::FAILURE);
      }
      if (success_ >= succ_thr) return finish(NodeStatus::SUCCESS);
      if (failure_ >= fail_thr || active - failure_ < succ_thr) return finish(NodeStatus::FAILURE);
    }
    return NodeStatus::RUNNING;
  }
  void halt() override {
    reset();
    ControlNode::halt();
  }

 private:
  NodeStatus finish(NodeStatus s) {
    haltChildren();
    reset();
    return s;
  }
  void reset() {
    std::fill(done_.begin(), done_.end(), 0);
    success_ = failure_ = skipped_ = 0;
  }
  Input<int> success_in_, failure_in_;
  std::vector<std::uint8_t> done_;
  int success_ = 0, failure_ = 0, skipped_ = 0;
};

/// IfThenElse: child 0 is evaluated once; then the chosen branch runs to completion (not reactive).
class IfThenElseNode : public ControlNode {
 public:
  using ControlNode::ControlNode;
  std::string validateChildren() const override {
    return children_.size() == 2 || children_.size() == 3 ? std::string() : "IfThenElse needs 2 or 3 children";
  }

 protected:
  NodeStatus tick() override {
    setStatus(NodeStatus::RUNNING);
    if (branch_ == 0) {
      const NodeStatus c = children_[0]->executeTick();
      if (c == NodeStatus::RUNNING) return c;
      if (c == NodeStatus::SUCCESS) {
        branch_ = 1;
      } else if (c == NodeStatus::FAILURE && children_.size() == 3) {
        branch_ = 2;
      } else {
        haltChildren();
        return c == NodeStatus::SKIPPED ? NodeStatus::SKIPPED : NodeStatus::FAILURE;
      }
    }
    const NodeStatus s = children_[branch_]->executeTick();
    if (s == NodeStatus::RUNNING) return s;
    haltChildren();
    branch_ = 0;
    return s;
  }
  void halt() override {
    branch_ = 0;
    ControlNode::halt();
  }

 private:
  std::size_t branch_ = 0;
};

/// WhileDoElse: the condition is re-evaluated every tick; the branch that is no longer selected is halted before
/// the other one is ticked.
class WhileDoElseNode : public ControlNode {
 public:
  using ControlNode::ControlNode;
  std::string validateChildren() const override {
    return children_.size() == 2 || children_.size() == 3 ? std::string() : "WhileDoElse needs 2 or 3 children";
  }

 protected:
  NodeStatus tick() override {
    setStatus(NodeStatus::RUNNING);
    const NodeStatus c = children_[0]->executeTick();
    if (c == NodeStatus::RUNNING) return c;
    if (c == NodeStatus::SKIPPED) {
      haltChildren();
      return c;
    }
    NodeStatus s;
    if (c == NodeStatus::SUCCESS) {
      if (children_.size() == 3) haltChild(2);
      s = children_[1]->executeTick();
    } else {
      haltChild(1);
      s = children_.size() == 3 ? children_[2]->executeTick() : NodeStatus::FAILURE;
    }
    if (s != NodeStatus::RUNNING) haltChildren();
    return s;
  }
};

/// SwitchN: N cases + default child; compares the `variable` entry with case_1..case_N (numbers numerically,
/// enum names by value, strings textually). A change of case halts the running child before the new one ticks.
template <int N>
class SwitchNode : public ControlNode {
 public:
  explicit SwitchNode(const NodeConfig& c) : ControlNode(c), var_(c.input<Value>("variable")) {
    for (int i = 1; i <= N; ++i) cases_.push_back(c.input<std::string>("case_" + std::to_string(i)));
  }
  static PortList providedPorts() {
    PortList p{InputPort<Value>("variable", "value to switch on")};
    for (int i = 1; i <= N; ++i) p.push_back(InputPort<std::string>("case_" + std::to_string(i)));
    return p;
  }
  std::string validateChildren() const override {
    return children_.size() == N + 1 ? std::string()
                                     : "Switch" + std::to_string(N) + " needs " + std::to_string(N + 1) +
                                           " children (" + std::to_string(N) + " cases and a default)";
  }

 protected:
  NodeStatus tick() override {
    setStatus(NodeStatus::RUNNING);
    std::size_t match = N;
    Value v;
    if (var_.get(v)) {
      for (std::size_t k = 0; k < cases_.size(); ++k) {
        if (cases_[k].get(case_buf_) && matches(v, case_buf_)) {
          match = k;
          break;
        }
      }
    }
    if (running_ != kNone && running_ != match) haltChild(running_);
    const NodeStatus s = children_[match]->executeTick();
    if (s == NodeStatus::RUNNING) {
      running_ = match;
    } else {
      haltChildren();
      running_ = kNone;
    }
    return s;
  }
  void halt() override {
    running_ = kNone;
    ControlNode::halt();
  }

 private:
  bool matches(const Value& v, const std::string& c) const {
    if (v.index() == 4) return std::get<std::string>(v) == c;
    Value cv = parseLiteral(c);
    if (cv.index() == 4 && config().enums) {
      auto it = config().enums->find(c);
      if (it != config().enums->end()) cv = Value(it->second);
    }
    if (v.index() == 1) return cv.index() == 1 && std::get<bool>(cv) == std::get<bool>(v);
    double a = v.index() == 2 ? double(std::get<std::int64_t>(v)) : v.index() == 3 ? std::get<double>(v) : 0.0;
    if (cv.index() == 2) return a == double(std::get<std::int64_t>(cv));
    if (cv.index() == 3) return a == std::get<double>(cv);
    return false;
  }
  static constexpr std::size_t kNone = static_cast<std::size_t>(-1);
  Input<Value> var_;
  std::vector<Input<std::string>> cases_;
  std::string case_buf_;
  std::size_t running_ = kNone;
};

// ================================================================================================ decorators
class InverterNode : public DecoratorNode {
 public:
  using DecoratorNode::DecoratorNode;

 protected:
  NodeStatus tick() override {
    const NodeStatus s = child().executeTick();
    if (s == NodeStatus::SUCCESS || s == NodeStatus::FAILURE) {
      resetChild();
      return s == NodeStatus::SUCCESS ? NodeStatus::FAILURE : NodeStatus::SUCCESS;
    }
    return s;
  }
};

class ForceNode : public DecoratorNode {
 public:
  ForceNode(const NodeConfig& c, NodeStatus forced) : DecoratorNode(c), forced_(forced) {}

 protected:
  NodeStatus tick() override {
    const NodeStatus s = child().executeTick();
    if (isCompleted(s)) {
      resetChild();
      return forced_;
    }
    return s;
  }

 private:
  NodeStatus forced_;
};

/// RetryUntilSuccessful (num_attempts) and Repeat (num_cycles). Finite counts loop within the tick while the
/// child completes synchronously (BT.CPP); -1 (forever) yields RUNNING after every completed cycle so a tick
/// always terminates.
class LoopNode : public DecoratorNode {
 public:
  LoopNode(const NodeConfig& c, bool retry)
      : DecoratorNode(c), retry_(retry), count_in_(c.input<int>(retry ? "num_attempts" : "num_cycles")) {}

 protected:
  NodeStatus tick() override {
    setStatus(NodeStatus::RUNNING);
    int n = 1;
    count_in_.get(n);
    const NodeStatus repeat_on = retry_ ? NodeStatus::FAILURE : NodeStatus::SUCCESS;
    while (n < 0 || count_ < n) {
      const NodeStatus s = child().executeTick();
      if (s == NodeStatus::RUNNING) return s;
      resetChild();
      if (s == NodeStatus::SKIPPED) {
        count_ = 0;
        return s;
      }
      if (s != repeat_on) {
        count_ = 0;
        return s;
      }
      ++count_;
      if (n < 0) {
        aboutToRun();
        return NodeStatus::RUNNING;
      }
    }
    count_ = 0;
    return retry_ ? NodeStatus::FAILURE : NodeStatus::SUCCESS;
  }
  void halt() override {
    count_ = 0;
    DecoratorNode::halt();
  }

 private:
  bool retry_;
  Input<int> count_in_;
  int count_ = 0;
};

class TimeoutNode : public DecoratorNode {
 public:
  explicit TimeoutNode(const NodeConfig& c) : DecoratorNode(c), msec_(durationInput(c, "msec")) {}
  static PortList providedPorts() { return {InputPort<int>("msec", "timeout in milliseconds")}; }

 protected:
  NodeStatus tick() override {
    if (status() != NodeStatus::RUNNING) {
      int ms = 0;
      msec_.get(ms);
      deadline_ = scheduler().now() + std::chrono::milliseconds(ms);
      timer_ = scheduler().wakeUpAt(deadline_);
      armed_ = true;
    }
    if (scheduler().now() >= deadline_) {
      disarm();
      child().haltNode();
      return NodeStatus::FAILURE;
    }
    const NodeStatus s = child().executeTick();
    if (s != NodeStatus::RUNNING) {
      disarm();
      resetChild();
    }
    return s;
  }
  void halt() override {
    disarm();
    DecoratorNode::halt();
  }

 private:
  void disarm() {
    if (armed_) scheduler().cancelTimer(timer_);
    armed_ = false;
  }
  Input<int> msec_;
  TimePoint deadline_{};
  Scheduler::TimerId timer_ = 0;
  bool armed_ = false;
};

class DelayNode : public DecoratorNode {
 public:
  explicit DelayNode(const NodeConfig& c) : DecoratorNode(c), msec_(durationInput(c, "delay_msec")) {}
  static PortList providedPorts() { return {InputPort<int>("delay_msec", "delay before ticking the child")}; }

 protected:
  NodeStatus tick() override {
    if (status() != NodeStatus::RUNNING) {
      int ms = 0;
      msec_.get(ms);
      deadline_ = scheduler().now() + std::chrono::milliseconds(ms);
      waiting_ = ms > 0;
      if (waiting_) timer_ = scheduler().wakeUpAt(deadline_);
    }
    if (waiting_) {
      if (scheduler().now() < deadline_) {
        aboutToRun();
        return NodeStatus::RUNNING;
      }
      waiting_ = false;
    }
    const NodeStatus s = child().executeTick();
    if (s != NodeStatus::RUNNING) resetChild();
    return s;
  }
  void halt() override {
    if (waiting_) scheduler().cancelTimer(timer_);
    waiting_ = false;
    DecoratorNode::halt();
  }

 private:
  Input<int> msec_;
  TimePoint deadline_{};
  Scheduler::TimerId timer_ = 0;
  bool waiting_ = false;
};

class KeepRunningUntilFailureNode : public DecoratorNode {
 public:
  using DecoratorNode::DecoratorNode;

 protected:
  NodeStatus tick() override {
    const NodeStatus s = child().executeTick();
    if (s == NodeStatus::SUCCESS) {
      resetChild();
      aboutToRun();
      return NodeStatus::RUNNING;
    }
    if (s == NodeStatus::FAILURE) resetChild();
    return s;
  }
};

class RunOnceNode : public DecoratorNode {
 public:
  explicit RunOnceNode(const NodeConfig& c) : DecoratorNode(c), then_skip_(c.input<bool>("then_skip")) {}
  static PortList providedPorts() {
    return {InputPortWithDefault<bool>("then_skip", "true", "after the first run return SKIPPED (else the result)")};
  }

 protected:
  NodeStatus tick() override {
    if (done_) {
      bool skip = true;
      then_skip_.get(skip);
      return skip ? NodeStatus::SKIPPED : result_;
    }
    const NodeStatus s = child().executeTick();
    if (isCompleted(s)) {
      done_ = true;
      result_ = s;
      resetChild();
    }
    return s;
  }

 private:
  Input<bool> then_skip_;
  bool done_ = false;
  NodeStatus result_ = NodeStatus::IDLE;
};

/// The SubTree node: one trace segment whose only child is the subtree's root.
class SubTreeNode : public DecoratorNode {
 public:
  using DecoratorNode::DecoratorNode;
  NodeKind kind() const override { return NodeKind::SubTree; }

 protected:
  NodeStatus tick() override {
    const NodeStatus s = child().executeTick();
    return s;
  }
};

/// Precondition (BT.CPP v4): evaluates `if` when the child is not running; false -> the `else` status.
class PreconditionNode : public DecoratorNode {
 public:
  explicit PreconditionNode(const NodeConfig& c) : DecoratorNode(c), if_(c.script("if")) {
    const PortBinding* e = c.binding("else");
    std::string txt = e && e->has_literal ? e->literal : "FAILURE";
    auto st = statusFromString(txt);
    if (!st || (*st != NodeStatus::SUCCESS && *st != NodeStatus::FAILURE && *st != NodeStatus::SKIPPED))
      throw PortError("Precondition: else must be SUCCESS, FAILURE or SKIPPED, got '" + txt + "'");
    else_ = *st;
  }
  static PortList providedPorts() {
    return {ScriptPort("if", "condition"),
            InputPortWithDefault<std::string>("else", "FAILURE", "status when the condition is false")};
  }

 protected:
  NodeStatus tick() override {
    if (child().status() != NodeStatus::RUNNING) {
      bool b = false;
      if (!if_->evaluateBool(b, &err_)) {
        reportError("Precondition: " + err_);
        return NodeStatus::FAILURE;
      }
      if (!b) return else_;
    }
    const NodeStatus s = child().executeTick();
    if (isCompleted(s)) resetChild();
    return s;
  }

 private:
  std::shared_ptr<Script> if_;
  NodeStatus else_ = NodeStatus::FAILURE;
  std::string err_;
};

/// ParallelAll (BT.CPP v4): runs every child to completion; FAILURE if at least max_failures failed.
class ParallelAllNode : public ControlNode {
 public:
  explicit ParallelAllNode(const NodeConfig& c) : ControlNode(c), max_failures_(c.input<int>("max_failures")) {}
  static PortList providedPorts() { return {InputPortWithDefault<int>("max_failures", "1")}; }

 protected:
  NodeStatus tick() override {
    setStatus(NodeStatus::RUNNING);
    if (done_.size() != children_.size()) done_.assign(children_.size(), 0);
    std::size_t finished = 0;
    for (std::size_t i = 0; i < children_.size(); ++i) {
      if (!done_[i]) {
        const NodeStatus s = children_[i]->executeTick();
        if (s == NodeStatus::RUNNING) continue;
        done_[i] = 1;
        failures_ += s == NodeStatus::FAILURE;
        skipped_ += s == NodeStatus::SKIPPED;
      }
      ++finished;
    }
    if (finished < children_.size()) return NodeStatus::RUNNING;
    int max_f = 1;
    max_failures_.get(max_f);
    const bool all_skipped = skipped_ == children_.size();
    const NodeStatus r = all_skipped ? NodeStatus::SKIPPED
                         : failures_ >= static_cast<std::size_t>(std::max(max_f, 1)) ? NodeStatus::FAILURE
                                                                                       : NodeStatus::SUCCESS;
    halt();
    return r;
  }
  void halt() override {
    std::fill(done_.begin(), done_.end(), 0);
    failures_ = skipped_ = 0;
    ControlNode::halt();
  }

 private:
  Input<int> max_failures_;
  std::vector<std::uint8_t> done_;
  std::size_t failures_ = 0, skipped_ = 0;
};

/// Tracks writes to one blackboard entry through its sequence number (no string lookup, no copy).
struct UpdateTracker {
  EntryBase* entry = nullptr;
  std::uint64_t seen = 0;
  explicit UpdateTracker(const NodeConfig& c) {
    const PortBinding* b = c.binding("entry");
    if (!b || !b->entry) throw PortError("port 'entry' must be a blackboard key, e.g. {key}");
    entry = b->entry.get();
    seen = entry->sequence();
  }
  bool updated() {
    const std::uint64_t s = entry->sequence();
    const bool u = s != seen;
    seen = s;
    return u;
  }
};

class WasEntryUpdatedNode : public ConditionNode {
 public:
  explicit WasEntryUpdatedNode(const NodeConfig& c) : ConditionNode(c), tracker_(c) {}
  static PortList providedPorts() {
    PortInfo p = InputPort<Value>("entry", "{key} to watch");
    p.literal_is_key = true;
    return {p};
  }

 protected:
  NodeStatus onTick() override { return tracker_.updated() ? NodeStatus::SUCCESS : NodeStatus::FAILURE; }

 private:
  UpdateTracker tracker_;
};

class SkipUnlessUpdatedNode : public DecoratorNode {
 public:
  explicit SkipUnlessUpdatedNode(const NodeConfig& c) : DecoratorNode(c), tracker_(c) {}

 protected:
  NodeStatus tick() override {
    if (child().status() != NodeStatus::RUNNING && !tracker_.updated()) return NodeStatus::SKIPPED;
    const NodeStatus s = child().executeTick();
    if (isCompleted(s)) resetChild();
    return s;
  }

 private:
  UpdateTracker tracker_;
};

// =================================================================================================== actions
class ConstantNode : public SyncActionNode {
 public:
  ConstantNode(const NodeConfig& c, NodeStatus s) : SyncActionNode(c), s_(s) {}

 protected:
  NodeStatus onTick() override { return s_; }

 private:
  NodeStatus s_;
};

class SleepNode : public StatefulActionNode {
 public:
  explicit SleepNode(const NodeConfig& c) : StatefulActionNode(c), msec_(durationInput(c, "msec")) {}
  static PortList providedPorts() { return {InputPort<int>("msec", "duration in milliseconds")}; }

 protected:
  NodeStatus onStart() override {
    int ms = 0;
    msec_.get(ms);
    if (ms <= 0) return NodeStatus::SUCCESS;
    deadline_ = scheduler().now() + std::chrono::milliseconds(ms);
    timer_ = scheduler().wakeUpAt(deadline_);
    return NodeStatus::RUNNING;
  }
  NodeStatus onRunning() override {
    return scheduler().now() >= deadline_ ? NodeStatus::SUCCESS : NodeStatus::RUNNING;
  }
  void onHalted() override { scheduler().cancelTimer(timer_); }

 private:
  Input<int> msec_;
  TimePoint deadline_{};
  Scheduler::TimerId timer_ = 0;
};

/// SetBlackboard: value (literal converted at load to the output entry's type, or "{key}" copied) -> output_key.
class SetBlackboardNode : public SyncActionNode {
 public:
  explicit SetBlackboardNode(const NodeConfig& c) : SyncActionNode(c) {
    const PortBinding* out = c.binding("output_key");
    const PortBinding* val = c.binding("value");
    if (!out || !out->entry) throw PortError("SetBlackboard: output_key must be a blackboard key, e.g. {key}");
    out_ = out->entry;
    if (val->entry) {
      src_ = val->entry;
    } else if (val->has_literal) {
      auto proto = out_->type().make_entry(&out_->type());
      try {
        proto->setFromString(val->literal);
      } catch (const ConversionError& e) {
        throw PortError("SetBlackboard value: " + std::string(e.what()));
      }
      src_ = std::move(proto);
    } else {
      throw PortError("SetBlackboard: missing value");
    }
  }
  static PortList providedPorts() {
    PortInfo out = BidirectionalPort<Value>("output_key", "key to write: {key} or key");
    out.literal_is_key = true;
    return {InputPort<Value>("value", "literal or {key}"), out};
  }

 protected:
  NodeStatus onTick() override {
    if (out_->copyFrom(*src_)) return NodeStatus::SUCCESS;
    reportError("SetBlackboard: source is unset or has an incompatible type");
    return NodeStatus::FAILURE;
  }

 private:
  std::shared_ptr<EntryBase> out_, src_;
};

class ScriptNode : public SyncActionNode {
 public:
  explicit ScriptNode(const NodeConfig& c) : SyncActionNode(c), script_(c.script("code")) {}
  static PortList providedPorts() { return {ScriptPort("code", "script to execute")}; }

 protected:
  NodeStatus onTick() override {
    if (script_->evaluate(result_, &err_)) return NodeStatus::SUCCESS;
    reportError("script: " + err_);
    return NodeStatus::FAILURE;
  }

 private:
  std::shared_ptr<Script> script_;
  Value result_;
  std::string err_;
};

class ScriptConditionNode : public ConditionNode {
 public:
  explicit ScriptConditionNode(const NodeConfig& c) : ConditionNode(c), script_(c.script("code")) {}
  static PortList providedPorts() { return {ScriptPort("code", "boolean expression")}; }

 protected:
  NodeStatus onTick() override {
    bool b = false;
    if (script_->evaluateBool(b, &err_)) return b ? NodeStatus::SUCCESS : NodeStatus::FAILURE;
    reportError("script: " + err_);
    return NodeStatus::FAILURE;
  }

 private:
  std::shared_ptr<Script> script_;
  std::string err_;
};

class SimpleActionNode : public SyncActionNode {
 public:
  SimpleActionNode(const NodeConfig& c, std::function<NodeStatus()> fn) : SyncActionNode(c), fn_(std::move(fn)) {}

 protected:
  NodeStatus onTick() override { return fn_(); }

 private:
  std::function<NodeStatus()> fn_;
};

class SimpleConditionNode : public ConditionNode {
 public:
  SimpleConditionNode(const NodeConfig& c, std::function<bool()> fn) : ConditionNode(c), fn_(std::move(fn)) {}

 protected:
  NodeStatus onTick() override { return fn_() ? NodeStatus::SUCCESS : NodeStatus::FAILURE; }

 private:
  std::function<bool()> fn_;
};

template <class F>
NodeManifest manifest(std::string id, NodeKind kind, PortList ports, int min_c, int max_c, F create,
                      std::string description) {
  NodeManifest m;
  m.id = std::move(id);
  m.kind = kind;
  m.ports = std::move(ports);
  m.min_children = min_c;
  m.max_children = max_c;
  m.create = create;
  m.description = std::move(description);
  return m;
}

template <int N>
void registerSwitch(NodeFactory& f) {
  f.registerManifest(manifest(
      "Switch" + std::to_string(N), NodeKind::Control, SwitchNode<N>::providedPorts(), N + 1, N + 1,
      [](const NodeConfig& c) -> std::unique_ptr<TreeNode> { return std::make_unique<SwitchNode<N>>(c); },
      "ticks the child whose case matches `variable`, else the last child"));
}

}  // namespace

void registerBuiltinNodes(NodeFactory& f) {
  using C = const NodeConfig&;
  using P = std::unique_ptr<TreeNode>;
  constexpr auto K = NodeKind::Control;
  constexpr auto D = NodeKind::Decorator;
  constexpr auto A = NodeKind::Action;
  f.registerManifest(manifest("Sequence", K, {}, 1, -1, [](C c) -> P { return std::make_unique<SequenceNode>(c, false); },
                              "ticks children in order; fails at the first failure (Stüde Alg. 5.1)"));
  f.registerManifest(manifest("SequenceWithMemory", K, {}, 1, -1,
                              [](C c) -> P { return std::make_unique<SequenceNode>(c, true); },
                              "sequence that does not re-tick succeeded children after a failure"));
  f.registerManifest(manifest("Fallback", K, {}, 1, -1, [](C c) -> P { return std::make_unique<FallbackNode>(c); },
                              "ticks children in order; succeeds at the first success (Stüde Alg. 5.2)"));
  f.registerManifest(manifest("ReactiveSequence", K, {}, 1, -1,
                              [](C c) -> P { return std::make_unique<ReactiveNode>(c, true); },
                              "sequence restarted from the first child every tick"));
  f.registerManifest(manifest("ReactiveFallback", K, {}, 1, -1,
                              [](C c) -> P { return std::make_unique<ReactiveNode>(c, false); },
                              "fallback restarted from the first child every tick"));
  f.registerManifest(manifest("Parallel", K, ParallelNode::providedPorts(), 1, -1,
                              [](C c) -> P { return std::make_unique<ParallelNode>(c); },
                              "ticks all children; success/failure thresholds"));
  f.registerManifest(manifest("IfThenElse", K, {}, 2, 3, [](C c) -> P { return std::make_unique<IfThenElseNode>(c); },
                              "if child 1 succeeds tick child 2, else child 3"));
  f.registerManifest(manifest("WhileDoElse", K, {}, 2, 3,
                              [](C c) -> P { return std::make_unique<WhileDoElseNode>(c); },
                              "reactive IfThenElse"));
  registerSwitch<2>(f);
  registerSwitch<3>(f);
  registerSwitch<4>(f);
  registerSwitch<5>(f);
  registerSwitch<6>(f);

  f.registerManifest(manifest("Inverter", D, {}, 1, 1, [](C c) -> P { return std::make_unique<InverterNode>(c); },
                              "swaps SUCCESS and FAILURE"));
  f.registerManifest(manifest("ForceSuccess", D, {}, 1, 1,
                              [](C c) -> P { return std::make_unique<ForceNode>(c, NodeStatus::SUCCESS); },
                              "SUCCESS when the child completes"));
  f.registerManifest(manifest("ForceFailure", D, {}, 1, 1,
                              [](C c) -> P { return std::make_unique<ForceNode>(c, NodeStatus::FAILURE); },
                              "FAILURE when the child completes"));
  const PortList retry_ports{InputPort<int>("num_attempts", "attempts (-1: forever)")};
  f.registerManifest(manifest("RetryUntilSuccessful", D, retry_ports, 1, 1,
                              [](C c) -> P { return std::make_unique<LoopNode>(c, true); },
                              "re-ticks a failing child up to num_attempts times"));
  f.registerManifest(manifest("Retry", D, retry_ports, 1, 1, [](C c) -> P { return std::make_unique<LoopNode>(c, true); },
                              "alias of RetryUntilSuccessful"));
  f.registerManifest(manifest("Repeat", D, {InputPort<int>("num_cycles", "cycles (-1: forever)")}, 1, 1,
                              [](C c) -> P { return std::make_unique<LoopNode>(c, false); },
                              "re-ticks a succeeding child num_cycles times"));
  f.registerManifest(manifest("Timeout", D, TimeoutNode::providedPorts(), 1, 1,
                              [](C c) -> P { return std::make_unique<TimeoutNode>(c); },
                              "halts the child and fails after msec"));
  f.registerManifest(manifest("Delay", D, DelayNode::providedPorts(), 1, 1,
                              [](C c) -> P { return std::make_unique<DelayNode>(c); },
                              "waits delay_msec, then ticks the child"));
  f.registerManifest(manifest("KeepRunningUntilFailure", D, {}, 1, 1,
                              [](C c) -> P { return std::make_unique<KeepRunningUntilFailureNode>(c); },
                              "RUNNING while the child succeeds"));
  f.registerManifest(manifest("RunOnce", D, RunOnceNode::providedPorts(), 1, 1,
                              [](C c) -> P { return std::make_unique<RunOnceNode>(c); },
                              "runs the child to completion once"));
  f.registerManifest(manifest("SubTree", NodeKind::SubTree, {}, 1, 1,
                              [](C c) -> P { return std::make_unique<SubTreeNode>(c); },
                              "instance of another <BehaviorTree>"));

  f.registerManifest(manifest("Precondition", D, PreconditionNode::providedPorts(), 1, 1,
                              [](C c) -> P { return std::make_unique<PreconditionNode>(c); },
                              "ticks the child if the script `if` is true, else returns `else`"));
  f.registerManifest(manifest("ParallelAll", K, ParallelAllNode::providedPorts(), 1, -1,
                              [](C c) -> P { return std::make_unique<ParallelAllNode>(c); },
                              "runs all children to completion; FAILURE if >= max_failures failed"));
  f.registerManifest(manifest("WasEntryUpdated", NodeKind::Condition, WasEntryUpdatedNode::providedPorts(), 0, 0,
                              [](C c) -> P { return std::make_unique<WasEntryUpdatedNode>(c); },
                              "SUCCESS if the entry was written since the last tick of this node"));
  f.registerManifest(manifest("SkipUnlessUpdated", D, WasEntryUpdatedNode::providedPorts(), 1, 1,
                              [](C c) -> P { return std::make_unique<SkipUnlessUpdatedNode>(c); },
                              "SKIPPED unless the entry was written since the last run"));
  f.registerManifest(manifest("AlwaysSuccess", A, {}, 0, 0,
                              [](C c) -> P { return std::make_unique<ConstantNode>(c, NodeStatus::SUCCESS); },
                              "returns SUCCESS"));
  f.registerManifest(manifest("AlwaysFailure", A, {}, 0, 0,
                              [](C c) -> P { return std::make_unique<ConstantNode>(c, NodeStatus::FAILURE); },
                              "returns FAILURE"));
  f.registerManifest(manifest("Sleep", A, SleepNode::providedPorts(), 0, 0,
                              [](C c) -> P { return std::make_unique<SleepNode>(c); },
                              "RUNNING for msec (timer on the tree's scheduler, no thread)"));
  f.registerManifest(manifest("SetBlackboard", A, SetBlackboardNode::providedPorts(), 0, 0,
                              [](C c) -> P { return std::make_unique<SetBlackboardNode>(c); },
                              "writes value into output_key"));
  f.registerManifest(manifest("Script", A, ScriptNode::providedPorts(), 0, 0,
                              [](C c) -> P { return std::make_unique<ScriptNode>(c); },
                              "runs a script; FAILURE on a run-time script error"));
  f.registerManifest(manifest("ScriptCondition", NodeKind::Condition, ScriptConditionNode::providedPorts(), 0, 0,
                              [](C c) -> P { return std::make_unique<ScriptConditionNode>(c); },
                              "SUCCESS if the expression is true"));
}

void NodeFactory::registerSimpleAction(std::string id, std::function<NodeStatus()> fn) {
  registerManifest(manifest(std::move(id), NodeKind::Action, {}, 0, 0,
                            [fn](const NodeConfig& c) -> std::unique_ptr<TreeNode> {
                              return std::make_unique<SimpleActionNode>(c, fn);
                            },
                            ""));
}

void NodeFactory::registerSimpleCondition(std::string id, std::function<bool()> fn) {
  registerManifest(manifest(std::move(id), NodeKind::Condition, {}, 0, 0,
                            [fn](const NodeConfig& c) -> std::unique_ptr<TreeNode> {
                              return std::make_unique<SimpleConditionNode>(c, fn);
                            },
                            ""));
}

}  // namespace cairn::bt
