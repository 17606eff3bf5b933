#include "cairn/bt_executive/tree_node.hpp"

namespace cairn::bt {

// ------------------------------------------------------------------------------------------ TreeContext
TreeContext::TreeContext() : default_scheduler_(std::make_unique<SteadyScheduler>()) {
  scheduler_ = default_scheduler_.get();
}

void TreeContext::setScheduler(Scheduler* s) { scheduler_ = s ? s : default_scheduler_.get(); }

std::size_t TreeContext::addObserver(TransitionObserver obs) {
  observers_.push_back(std::move(obs));
  observed_ = true;
  return observers_.size() - 1;
}

void TreeContext::removeObserver(std::size_t handle) {
  if (handle < observers_.size()) observers_[handle] = nullptr;
  observed_ = false;
  for (auto& o : observers_) observed_ = observed_ || static_cast<bool>(o);
}

void TreeContext::emit(const TreeNode& n, NodeStatus old_s, NodeStatus new_s) {
  const TransitionEvent ev{n.uid(), n.path(), old_s, new_s, now(), step_};
  for (auto& o : observers_)
    if (o) o(ev);
}

void TreeContext::reportError(const TreeNode& n, std::string msg) {
  if (errors_.size() < 1000) errors_.push_back(n.path() + ": " + msg);
  if (error_handler_) error_handler_(RuntimeErrorEvent{n.uid(), n.path(), std::move(msg)});
}

void TreeContext::runPreemptions() {
  // Halt in registration order (outermost reactive control first); each entry is cleared so that it is halted
  // once even if several nodes below start in the same tick.
  for (auto& n : preempt_) {
    if (n) {
      TreeNode* victim = n;
      n = nullptr;
      victim->haltNode();
    }
  }
}

// ------------------------------------------------------------------------------------------ NodeConfig
const PortBinding* NodeConfig::binding(std::string_view port) const {
  for (const auto& b : ports)
    if (b.info && b.info->name == port) return &b;
  return nullptr;
}

const PortBinding* NodeConfig::requireBinding(std::string_view port, const TypeInfo* t) const {
  const PortBinding* b = binding(port);
  if (!b) throw std::logic_error("node " + id + " has no port '" + std::string(port) + "'");
  if (b->info->type->index != t->index)
    throw std::logic_error("port '" + std::string(port) + "' of " + id + " is declared as " + b->info->type->name +
                           " but read as " + t->name);
  return b;
}

std::shared_ptr<Script> NodeConfig::script(std::string_view port) const {
  const PortBinding* b = binding(port);
  if (!b) throw std::logic_error("node " + id + " has no port '" + std::string(port) + "'");
  if (b->script) return b->script;
  if (!b->has_literal) throw PortError("script port '" + std::string(port) + "' must be a literal script");
  try {
    auto s = std::make_shared<Script>(Script::parse(b->literal, enums));
    s->bind(*blackboard);
    return s;
  } catch (const ScriptError& e) {
    throw PortError("script '" + std::string(port) + "', column " + std::to_string(e.column) + ": " + e.what());
  }
}

// ------------------------------------------------------------------------------------------ TreeNode
TreeNode::TreeNode(const NodeConfig& config) : config_(config) {
  for (auto& s : config_.pre) has_conditions_ = has_conditions_ || static_cast<bool>(s);
  for (auto& s : config_.post) has_conditions_ = has_conditions_ || static_cast<bool>(s);
  if (!config_.context) throw std::logic_error("NodeConfig without TreeContext");
}

TreeNode::~TreeNode() = default;

std::string TreeNode::validateChildren() const { return {}; }

void TreeNode::setStatus(NodeStatus s) {
  if (s == status_) return;
  const NodeStatus old = status_;
  status_ = s;
  if (config_.context->observed()) config_.context->emit(*this, old, s);
}

std::optional<NodeStatus> TreeNode::checkPreconditions() {
  // BehaviorTree.CPP v4 order: _failureIf, _successIf, _skipIf (only when not RUNNING), then _while.
  auto eval = [&](PreCond c, bool& out) -> bool {
    std::string err;
    if (!config_.pre[static_cast<int>(c)]->evaluateBool(out, &err)) {
      reportError("precondition: " + err);
      return false;
    }
    return true;
  };
  if (status_ != NodeStatus::RUNNING) {
    static constexpr std::pair<PreCond, NodeStatus> kChecks[] = {{PreCond::FailureIf, NodeStatus::FAILURE},
                                                                 {PreCond::SuccessIf, NodeStatus::SUCCESS},
                                                                 {PreCond::SkipIf, NodeStatus::SKIPPED}};
    for (auto [c, result] : kChecks) {
      if (!config_.pre[static_cast<int>(c)]) continue;
      bool b = false;
      if (!eval(c, b)) return NodeStatus::FAILURE;
      if (b) return result;
    }
  }
  if (config_.pre[static_cast<int>(PreCond::While)]) {
    bool b = false;
    if (!eval(PreCond::While, b)) {
      if (status_ == NodeStatus::RUNNING) haltNode();
      return NodeStatus::FAILURE;
    }
    if (!b) {
      if (status_ == NodeStatus::RUNNING) haltNode();
      return NodeStatus::SKIPPED;
    }
  }
  return std::nullopt;
}

void TreeNode::runPostcondition(PostCond c) {
  const auto& s = config_.post[static_cast<int>(c)];
  if (!s) return;
  Value v;
  std::string err;
  if (!s->evaluate(v, &err)) reportError("postcondition: " + err);
}

NodeStatus TreeNode::executeTick() {
  if (has_conditions_) {
    if (auto pre = checkPreconditions()) {
      setStatus(*pre);
      return *pre;
    }
  }
  const NodeStatus s = tick();
  if (has_conditions_) {
    if (s == NodeStatus::SUCCESS) runPostcondition(PostCond::OnSuccess);
    if (s == NodeStatus::FAILURE) runPostcondition(PostCond::OnFailure);
    if (isCompleted(s)) runPostcondition(PostCond::Post);
  }
  setStatus(s);
  return s;
}

void TreeNode::haltNode() {
  if (status_ == NodeStatus::IDLE) return;
  const bool was_running = status_ == NodeStatus::RUNNING;
  halt();
  if (was_running && has_conditions_) runPostcondition(PostCond::OnHalted);
  setStatus(NodeStatus::IDLE);
}

// ------------------------------------------------------------------------------------------ leaves
std::string SyncActionNode::validateChildren() const {
  return children_.empty() ? std::string() : "an action or condition takes no children";
}

NodeStatus SyncActionNode::tick() {
  const NodeStatus s = onTick();
  if (s == NodeStatus::RUNNING || s == NodeStatus::IDLE) {
    reportError("synchronous node returned " + std::string(toString(s)));
    return NodeStatus::FAILURE;
  }
  return s;
}

std::string StatefulActionNode::validateChildren() const {
  return children_.empty() ? std::string() : "an action takes no children";
}

NodeStatus StatefulActionNode::tick() {
  if (status() == NodeStatus::RUNNING) {
    const NodeStatus s = onRunning();
    if (s == NodeStatus::IDLE) {
      reportError("onRunning() returned IDLE");
      return NodeStatus::FAILURE;
    }
    return s;
  }
  aboutToRun();  // halt preempted reactive siblings before this action starts (issue #1031)
  const NodeStatus s = onStart();
  if (s == NodeStatus::IDLE) {
    reportError("onStart() returned IDLE");
    return NodeStatus::FAILURE;
  }
  return s;
}

void StatefulActionNode::halt() {
  if (status() == NodeStatus::RUNNING) onHalted();
}

NodeStatus EventActionNode::onStart() {
  const std::uint64_t run = run_.fetch_add(1) + 1;
  result_.store(NodeStatus::IDLE);
  return start(run);
}

NodeStatus EventActionNode::onRunning() {
  const NodeStatus r = result_.load();
  return r == NodeStatus::IDLE ? NodeStatus::RUNNING : r;
}

void EventActionNode::onHalted() {
  run_.fetch_add(1);
  cancel();
}

bool EventActionNode::complete(std::uint64_t run, NodeStatus result) {
  if (run != run_.load() || !isCompleted(result)) return false;
  result_.store(result);
  scheduler().requestTick();
  return true;
}

// ------------------------------------------------------------------------------------------ inner nodes
std::string ControlNode::validateChildren() const {
  return children_.empty() ? "a control node needs at least one child" : std::string();
}

void ControlNode::haltChildren(std::size_t from) {
  for (std::size_t i = from; i < children_.size(); ++i) children_[i]->haltNode();
}

std::string DecoratorNode::validateChildren() const {
  return children_.size() == 1 ? std::string() : "a decorator needs exactly one child";
}

}  // namespace cairn::bt
