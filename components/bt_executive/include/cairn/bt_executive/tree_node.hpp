// Node base classes, ports and the per-tree context shared by all nodes.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "cairn/bt_executive/blackboard.hpp"
#include "cairn/bt_executive/scheduler.hpp"
#include "cairn/bt_executive/script.hpp"
#include "cairn/bt_executive/status.hpp"

namespace cairn::bt {

class TreeNode;

// ---------------------------------------------------------------------------------------------------- ports
enum class PortDirection : std::uint8_t { Input, Output, InOut };

struct PortInfo {
  std::string name;
  PortDirection direction = PortDirection::Input;
  const TypeInfo* type = nullptr;
  std::optional<std::string> default_value;  ///< literal or "{key}"; no default on an input port = required
  std::string description;
  bool is_script = false;  ///< the literal is a script, parsed and bound at load (Script, ScriptCondition)
  bool literal_is_key = false;  ///< a literal names a blackboard key ("key" == "{key}"; SetBlackboard output_key)
};
using PortList = std::vector<PortInfo>;

template <class T>
PortInfo InputPort(std::string name, std::string description = {}) {
  return PortInfo{std::move(name), PortDirection::Input, &typeInfo<T>(), std::nullopt, std::move(description)};
}
template <class T>
PortInfo InputPortWithDefault(std::string name, std::string default_value, std::string description = {}) {
  return PortInfo{std::move(name), PortDirection::Input, &typeInfo<T>(), std::move(default_value),
                  std::move(description)};
}
template <class T>
PortInfo OutputPort(std::string name, std::string description = {}) {
  return PortInfo{std::move(name), PortDirection::Output, &typeInfo<T>(), std::nullopt, std::move(description)};
}
template <class T>
PortInfo BidirectionalPort(std::string name, std::string description = {}) {
  return PortInfo{std::move(name), PortDirection::InOut, &typeInfo<T>(), std::nullopt, std::move(description)};
}
inline PortInfo ScriptPort(std::string name, std::string description = {}) {
  PortInfo p = InputPort<std::string>(std::move(name), std::move(description));
  p.is_script = true;
  return p;
}

/// A port error found while constructing a node (the loader adds file:line).
struct PortError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// How one port of one node instance is connected: a converted-at-load literal or a blackboard entry.
struct PortBinding {
  const PortInfo* info = nullptr;
  bool has_literal = false;
  std::string literal;
  std::shared_ptr<EntryBase> entry;
  std::shared_ptr<Script> script;  ///< for script ports: parsed and bound by the loader
};

/// Read side of a port, bound once at construction. get() does no string lookup.
template <class T>
class Input {
 public:
  Input() = default;
  bool get(T& out) const {
    if (typed_) return typed_->tryGet(out);
    if (entry_) {
      if constexpr (std::is_same_v<T, Value>) {
        return entry_->getValue(out);
      } else {
        Value v;
        return entry_->getValue(v) && fromValue(v, out);
      }
    }
    if (has_literal_) {
      out = literal_;
      return true;
    }
    return false;
  }
  std::optional<T> get() const {
    T v{};
    if (get(v)) return v;
    return std::nullopt;
  }
  bool connected() const { return typed_ || entry_ || has_literal_; }
  bool isLiteral() const { return has_literal_; }
  EntryBase* entry() const { return entry_; }

  static Input fromBinding(const PortBinding& b) {
    Input in;
    if (b.entry) {
      in.keep_ = b.entry;
      in.entry_ = b.entry.get();
      in.typed_ = dynamic_cast<TypedEntry<T>*>(b.entry.get());
      if (!in.typed_ && !(kScriptType<T> && b.entry->type().script_type))
        throw PortError("port '" + b.info->name + "' expects " + typeName<T>() + " but blackboard entry has type " +
                        b.entry->type().name);
    } else if (b.has_literal) {
      if constexpr (Convert<T>::available) {
        try {
          in.literal_ = Convert<T>::fromString(b.literal);
        } catch (const ConversionError& e) {
          throw PortError("port '" + b.info->name + "': " + e.what());
        }
        in.has_literal_ = true;
      } else {
        throw PortError("port '" + b.info->name + "' of type " + typeName<T>() + " cannot take a literal");
      }
    }
    return in;
  }

 private:
  T literal_{};
  bool has_literal_ = false;
  TypedEntry<T>* typed_ = nullptr;
  EntryBase* entry_ = nullptr;
  std::shared_ptr<EntryBase> keep_;
};

/// Write side of a port.
template <class T>
class Output {
 public:
  Output() = default;
  /// Returns false if the port is not connected or the value does not fit the entry.
  bool set(const T& v) const {
    if (typed_) {
      typed_->set(v);
      return true;
    }
    if (entry_) {
      if constexpr (kScriptType<T>) return entry_->setValue(toValue(v));
    }
    return false;
  }
  bool connected() const { return entry_ != nullptr; }
  EntryBase* entry() const { return entry_; }

  static Output fromBinding(const PortBinding& b) {
    Output out;
    if (b.has_literal)
      throw PortError("output port '" + b.info->name + "' must be a blackboard key in braces, got '" + b.literal + "'");
    if (b.entry) {
      out.keep_ = b.entry;
      out.entry_ = b.entry.get();
      out.typed_ = dynamic_cast<TypedEntry<T>*>(b.entry.get());
      if (!out.typed_ && !(kScriptType<T> && b.entry->type().script_type))
        throw PortError("port '" + b.info->name + "' expects " + typeName<T>() + " but blackboard entry has type " +
                        b.entry->type().name);
    }
    return out;
  }

 private:
  TypedEntry<T>* typed_ = nullptr;
  EntryBase* entry_ = nullptr;
  std::shared_ptr<EntryBase> keep_;
};

// ---------------------------------------------------------------------------------------------------- events
/// One status change of one node (the observability event stream).
struct TransitionEvent {
  std::uint32_t uid;
  std::string_view path;
  NodeStatus old_status;
  NodeStatus new_status;
  TimePoint time;
  std::uint64_t step;  ///< root tick counter (1 = first tick)
};
using TransitionObserver = std::function<void(const TransitionEvent&)>;

/// Run-time errors that do not stop the tree (a script failing at tick time makes its node fail).
struct RuntimeErrorEvent {
  std::uint32_t uid;
  std::string_view path;
  std::string message;
};

enum class PreCond : std::uint8_t { FailureIf = 0, SuccessIf, SkipIf, While };
enum class PostCond : std::uint8_t { OnSuccess = 0, OnFailure, Post, OnHalted };

/// Per-tree state shared by every node: clock/scheduler, step counter, observers, reactive preemption stack.
class TreeContext {
 public:
  TreeContext();
  Scheduler& scheduler() { return *scheduler_; }
  void setScheduler(Scheduler* s);
  TimePoint now() const { return scheduler_->now(); }
  std::uint64_t step() const { return step_; }
  void setStep(std::uint64_t s) { step_ = s; }

  std::size_t addObserver(TransitionObserver obs);
  void removeObserver(std::size_t handle);
  /// Drops every observer and the error handler (the tree is being destroyed).
  void clearObservers() {
    observers_.clear();
    observed_ = false;
    error_handler_ = nullptr;
  }
  void setErrorHandler(std::function<void(const RuntimeErrorEvent&)> h) { error_handler_ = std::move(h); }
  bool observed() const { return observed_; }
  void emit(const TreeNode& n, NodeStatus old_s, NodeStatus new_s);
  void reportError(const TreeNode& n, std::string msg);
  const std::vector<std::string>& errors() const { return errors_; }

  /// Reactive controls register their RUNNING child here before ticking a different child. The first node below
  /// that starts running on its own (calls TreeNode::aboutToRun()) halts those children first, so at most one
  /// child of a reactive control is ever RUNNING (BehaviorTree.CPP issue #1031).
  void pushPreemption(TreeNode* running_child) { preempt_.push_back(running_child); }
  void popPreemption() { preempt_.pop_back(); }
  void runPreemptions();

 private:
  Scheduler* scheduler_;
  std::unique_ptr<Scheduler> default_scheduler_;
  std::uint64_t step_ = 0;
  std::vector<TransitionObserver> observers_;
  bool observed_ = false;
  std::function<void(const RuntimeErrorEvent&)> error_handler_;
  std::vector<std::string> errors_;
  std::vector<TreeNode*> preempt_;
};

/// Everything a node needs at construction. Built by the XML loader (or by hand in tests).
struct NodeConfig {
  std::string id;    ///< registration ID (e.g. "Sequence")
  std::string name;  ///< instance name
  std::string path;  ///< trace path
  std::uint32_t uid = 0;
  std::string location;  ///< "file:line" for error messages
  std::shared_ptr<Blackboard> blackboard;
  TreeContext* context = nullptr;
  std::vector<PortBinding> ports;
  std::array<std::shared_ptr<Script>, 4> pre{};
  std::array<std::shared_ptr<Script>, 4> post{};
  const ScriptEnums* enums = nullptr;

  const PortBinding* binding(std::string_view port) const;
  template <class T>
  Input<T> input(std::string_view port) const {
    const PortBinding* b = requireBinding(port, &typeInfo<T>());
    return Input<T>::fromBinding(*b);
  }
  template <class T>
  Output<T> output(std::string_view port) const {
    const PortBinding* b = requireBinding(port, &typeInfo<T>());
    return Output<T>::fromBinding(*b);
  }
  /// The bound script of a script port (parsed+bound now if the loader did not).
  std::shared_ptr<Script> script(std::string_view port) const;

 private:
  const PortBinding* requireBinding(std::string_view port, const TypeInfo* t) const;
};

// ---------------------------------------------------------------------------------------------------- nodes
class TreeNode {
 public:
  explicit TreeNode(const NodeConfig& config);
  virtual ~TreeNode();
  TreeNode(const TreeNode&) = delete;
  TreeNode& operator=(const TreeNode&) = delete;

  /// Ticks the node: preconditions, tick(), postconditions, status update.
  NodeStatus executeTick();
  /// Halts a RUNNING node (and its running descendants) and resets any non-IDLE node to IDLE.
  void haltNode();

  NodeStatus status() const { return status_; }
  const std::string& name() const { return config_.name; }
  const std::string& id() const { return config_.id; }
  const std::string& path() const { return config_.path; }
  std::uint32_t uid() const { return config_.uid; }
  const NodeConfig& config() const { return config_; }
  virtual NodeKind kind() const = 0;
  const std::vector<TreeNode*>& children() const { return children_; }
  /// Called by the loader / builder; controls and decorators check the count in validateChildren().
  virtual void addChild(TreeNode* child) { children_.push_back(child); }
  /// Empty if the number of children is acceptable, else a message.
  virtual std::string validateChildren() const;

 protected:
  virtual NodeStatus tick() = 0;
  /// Called by haltNode() while the node is not IDLE; status() still shows the old status.
  virtual void halt() {}
  void setStatus(NodeStatus s);
  TreeContext& context() const { return *config_.context; }
  Scheduler& scheduler() const { return config_.context->scheduler(); }
  /// A node that is about to start RUNNING on its own (an async action's start, a Delay, ...) calls this first:
  /// it halts the RUNNING children of reactive ancestors that are being preempted.
  void aboutToRun() const { config_.context->runPreemptions(); }
  /// Reports a non-fatal run-time error (the node should then return FAILURE).
  void reportError(std::string msg) const { config_.context->reportError(*this, std::move(msg)); }

  std::vector<TreeNode*> children_;

 private:
  std::optional<NodeStatus> checkPreconditions();
  void runPostcondition(PostCond c);
  NodeConfig config_;
  NodeStatus status_ = NodeStatus::IDLE;
  bool has_conditions_ = false;
};

/// Leaf that completes within the tick (SUCCESS/FAILURE). Returning RUNNING is reported as an error -> FAILURE.
class SyncActionNode : public TreeNode {
 public:
  using TreeNode::TreeNode;
  NodeKind kind() const override { return NodeKind::Action; }
  std::string validateChildren() const override;

 protected:
  NodeStatus tick() final;
  virtual NodeStatus onTick() = 0;
};

/// Condition leaf: SUCCESS or FAILURE, never RUNNING (Stüde §5.2.1).
class ConditionNode : public SyncActionNode {
 public:
  using SyncActionNode::SyncActionNode;
  NodeKind kind() const override { return NodeKind::Condition; }
};

/// Async action with explicit state (BehaviorTree.CPP's StatefulActionNode): onStart on the first tick,
/// onRunning on later ticks while RUNNING, onHalted when halted while RUNNING. It is meant to be driven by
/// executor events: start a request in onStart, return RUNNING, and have the event call requestTick().
class StatefulActionNode : public TreeNode {
 public:
  using TreeNode::TreeNode;
  NodeKind kind() const override { return NodeKind::Action; }
  std::string validateChildren() const override;

 protected:
  virtual NodeStatus onStart() = 0;
  virtual NodeStatus onRunning() = 0;
  virtual void onHalted() = 0;

 private:
  NodeStatus tick() final;
  void halt() final;
};

/// Async action completed from outside the tree: start() sends a request (message, service call, goal) and
/// returns RUNNING; the reply handler, on any thread, calls complete(run, SUCCESS|FAILURE), which stores the
/// result and asks the scheduler for a tick. Replies of a halted or earlier run are ignored (by `run` id).
class EventActionNode : public StatefulActionNode {
 public:
  using StatefulActionNode::StatefulActionNode;
  /// Thread-safe. Returns false if `run` is not the current run (stale reply).
  bool complete(std::uint64_t run, NodeStatus result);
  std::uint64_t currentRun() const { return run_.load(); }

 protected:
  /// Starts the work of run `run`; return RUNNING (or SUCCESS/FAILURE if it completed synchronously).
  virtual NodeStatus start(std::uint64_t run) = 0;
  /// Cancels the work of the current run (halt).
  virtual void cancel() {}

 private:
  NodeStatus onStart() final;
  NodeStatus onRunning() final;
  void onHalted() final;
  std::atomic<std::uint64_t> run_{0};
  std::atomic<NodeStatus> result_{NodeStatus::IDLE};
};

class ControlNode : public TreeNode {
 public:
  using TreeNode::TreeNode;
  NodeKind kind() const override { return NodeKind::Control; }
  std::string validateChildren() const override;

 protected:
  void halt() override { haltChildren(); }
  void haltChildren(std::size_t from = 0);
  void haltChild(std::size_t i) { children_[i]->haltNode(); }
};

class DecoratorNode : public TreeNode {
 public:
  using TreeNode::TreeNode;
  NodeKind kind() const override { return NodeKind::Decorator; }
  std::string validateChildren() const override;

 protected:
  TreeNode& child() const { return *children_.front(); }
  void halt() override { child().haltNode(); }
  void resetChild() { child().haltNode(); }
};

}  // namespace cairn::bt
