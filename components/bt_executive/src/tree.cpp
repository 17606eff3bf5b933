#include "cairn/bt_executive/tree.hpp"

namespace cairn::bt {

Tree::Tree() : context_(std::make_unique<TreeContext>()) {}
Tree::~Tree() {
  if (root_ && context_) {
    // Halt running async nodes so that they cancel their timers/requests before the scheduler goes away. Observers
    // may already be gone, so the final halt is not reported.
    context_->clearObservers();
    try {
      root_->haltNode();
    } catch (...) {
    }
  }
}
Tree::Tree(Tree&& o) noexcept
    : context_(std::move(o.context_)), blackboards_(std::move(o.blackboards_)), nodes_(std::move(o.nodes_)),
      root_(o.root_), id_(std::move(o.id_)) {
  o.root_ = nullptr;
}
Tree& Tree::operator=(Tree&& o) noexcept {
  if (this != &o) {
    if (root_ && context_) {
      context_->clearObservers();
      root_->haltNode();
    }
    context_ = std::move(o.context_);
    blackboards_ = std::move(o.blackboards_);
    nodes_ = std::move(o.nodes_);
    root_ = o.root_;
    id_ = std::move(o.id_);
    o.root_ = nullptr;
  }
  return *this;
}

NodeStatus Tree::tickOnce() {
  if (!root_) return NodeStatus::FAILURE;
  context_->setStep(context_->step() + 1);
  return root_->executeTick();
}

void Tree::haltTree() {
  if (root_) root_->haltNode();
}

TreeNode* Tree::addNode(std::unique_ptr<TreeNode> n) {
  nodes_.push_back(std::move(n));
  return nodes_.back().get();
}

TreeNode* Tree::findByPath(std::string_view path) const {
  for (const auto& n : nodes_)
    if (n->path() == path) return n.get();
  return nullptr;
}

NodeStatus runUntilComplete(Tree& tree, ManualScheduler& sched, std::size_t max_ticks) {
  tree.setScheduler(&sched);
  NodeStatus s = NodeStatus::IDLE;
  for (std::size_t k = 0; k < max_ticks; ++k) {
    sched.takeTickRequest();
    sched.fireDueTimers();
    s = tree.tickOnce();
    if (s != NodeStatus::RUNNING) return s;
    if (sched.takeTickRequest()) continue;
    auto t = sched.nextTimer();
    if (!t) return s;  // nothing can wake the tree any more
    if (*t > sched.now()) sched.advanceTo(*t);
  }
  return s;
}

}  // namespace cairn::bt
