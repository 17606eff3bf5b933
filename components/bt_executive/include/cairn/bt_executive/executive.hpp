// Runtime-agnostic executive: the state machine and status protocol the executive component wraps.
// The component owns an Executive, implements Scheduler on its executor, calls tick() from a periodic timer and
// after Scheduler::requestTick(), maps the start/stop/switch service to start()/stop()/switchTree(), and publishes
// statusJson() (snapshot, e.g. 1 Hz and on demand) and eventsJson() (transitions since the last call) on topics.
// `cairn bt watch` in another process parses the snapshot with parseStatusJson() and renders it with renderTree().
#pragma once

#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "cairn/bt_executive/factory.hpp"
#include "cairn/bt_executive/tree.hpp"

namespace cairn::bt {

class Executive {
 public:
  enum class State { Empty, Ready, Running, Finished, Stopped };

  /// Both must outlive the executive.
  Executive(const NodeFactory& factory, Scheduler& scheduler);
  ~Executive();

  /// Loads `file` (tree `tree_id`, or the file's main tree). On a LoadError the current tree is kept and the error
  /// rethrown. A running tree is halted first; the new tree is Ready.
  void load(const std::string& file, const std::string& tree_id = {});
  /// Another tree of the same file (halts the current one).
  void switchTree(const std::string& tree_id);
  /// Ready/Finished/Stopped -> Running (a finished or stopped tree restarts from IDLE). False without a tree.
  bool start();
  /// Halts the tree (async actions are cancelled) -> Stopped.
  void stop();
  /// One root tick if Running; the tree's result moves the state to Finished when it is no longer RUNNING.
  NodeStatus tick();

  State state() const { return state_; }
  NodeStatus lastStatus() const { return last_; }
  const std::string& treeId() const { return tree_id_; }
  const std::string& file() const { return file_; }
  Tree* tree() { return tree_.get(); }

  /// {"tree":..,"file":..,"state":..,"step":..,"status":..,"nodes":[{"uid":0,"path":"..","status":".."},..]}
  std::string statusJson() const;
  /// {"tree":..,"events":[{"step":..,"t_ns":..,"uid":..,"from":"..","to":".."},..]}; clears the buffer.
  std::string eventsJson();
  /// Transitions buffered since the last eventsJson() (bounded; the oldest are dropped beyond `capacity`).
  void setEventCapacity(std::size_t capacity) { capacity_ = capacity; }

 private:
  struct Event {
    std::uint64_t step;
    std::int64_t t_ns;
    std::uint32_t uid;
    NodeStatus from, to;
  };
  void attach();
  const NodeFactory& factory_;
  Scheduler& scheduler_;
  std::unique_ptr<Tree> tree_;
  std::string file_, tree_id_;
  State state_ = State::Empty;
  NodeStatus last_ = NodeStatus::IDLE;
  std::vector<Event> events_;
  std::size_t capacity_ = 100000;
  std::size_t dropped_ = 0;
};

std::string_view toString(Executive::State s);

/// Parsed status snapshot (for a remote `cairn bt watch`).
struct StatusSnapshot {
  std::string tree, state;
  std::uint64_t step = 0;
  std::vector<std::string> paths;
  std::vector<NodeStatus> statuses;
};
/// Parses statusJson(); throws std::runtime_error on malformed input.
StatusSnapshot parseStatusJson(std::string_view json);

}  // namespace cairn::bt
