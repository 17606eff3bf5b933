// A loaded tree: owns its nodes, blackboard scopes and context.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "cairn/bt_executive/blackboard.hpp"
#include "cairn/bt_executive/scheduler.hpp"
#include "cairn/bt_executive/tree_node.hpp"

namespace cairn::bt {

class Tree {
 public:
  Tree();
  ~Tree();
  Tree(Tree&&) noexcept;
  Tree& operator=(Tree&&) noexcept;

  /// One root tick (advances the step counter first, so events of the first tick carry step 1).
  NodeStatus tickOnce();
  /// Halts every running node and resets the tree to IDLE.
  void haltTree();

  TreeNode* root() const { return root_; }
  /// ID of the <BehaviorTree> this tree was instantiated from (set by the loader).
  const std::string& id() const { return id_; }
  void setId(std::string id) { id_ = std::move(id); }
  NodeStatus status() const { return root_ ? root_->status() : NodeStatus::IDLE; }
  const std::vector<std::unique_ptr<TreeNode>>& nodes() const { return nodes_; }
  TreeNode* findByPath(std::string_view path) const;
  std::shared_ptr<Blackboard> rootBlackboard() const { return blackboards_.empty() ? nullptr : blackboards_.front(); }
  const std::vector<std::shared_ptr<Blackboard>>& blackboards() const { return blackboards_; }
  TreeContext& context() const { return *context_; }
  /// The scheduler must outlive the tree; nullptr restores the internal steady-clock scheduler.
  void setScheduler(Scheduler* s) { context_->setScheduler(s); }
  std::size_t addObserver(TransitionObserver obs) { return context_->addObserver(std::move(obs)); }
  void removeObserver(std::size_t h) { context_->removeObserver(h); }

  // Construction (loader / hand-built trees in tests).
  TreeNode* addNode(std::unique_ptr<TreeNode> n);
  void setRoot(TreeNode* r) { root_ = r; }
  void addBlackboard(std::shared_ptr<Blackboard> bb) { blackboards_.push_back(std::move(bb)); }

 private:
  std::unique_ptr<TreeContext> context_;
  std::vector<std::shared_ptr<Blackboard>> blackboards_;
  std::vector<std::unique_ptr<TreeNode>> nodes_;
  TreeNode* root_ = nullptr;
  std::string id_;
};

/// Event-driven loop on a ManualScheduler: tick; while RUNNING, tick again at once if a tick was requested, else
/// jump the clock to the next timer and tick. Stops after `max_ticks` ticks or when nothing can wake the tree.
/// This is the loop the runtime executive runs with real timers and events.
NodeStatus runUntilComplete(Tree& tree, ManualScheduler& sched, std::size_t max_ticks = 10000);

}  // namespace cairn::bt
