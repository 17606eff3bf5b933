// Node statuses of the behavior-tree engine: Stüde §5.2.1 (R/S/F) plus BehaviorTree.CPP v4's IDLE and SKIPPED.
#pragma once

#include <cstdint>
#include <optional>
#include <string_view>

namespace cairn::bt {

enum class NodeStatus : std::uint8_t { IDLE = 0, RUNNING, SUCCESS, FAILURE, SKIPPED };

constexpr std::string_view toString(NodeStatus s) {
  switch (s) {
    case NodeStatus::IDLE: return "IDLE";
    case NodeStatus::RUNNING: return "RUNNING";
    case NodeStatus::SUCCESS: return "SUCCESS";
    case NodeStatus::FAILURE: return "FAILURE";
    case NodeStatus::SKIPPED: return "SKIPPED";
  }
  return "?";
}

std::optional<NodeStatus> statusFromString(std::string_view s);

constexpr bool isCompleted(NodeStatus s) { return s == NodeStatus::SUCCESS || s == NodeStatus::FAILURE; }

enum class NodeKind : std::uint8_t { Action, Condition, Control, Decorator, SubTree };

constexpr std::string_view toString(NodeKind k) {
  switch (k) {
    case NodeKind::Action: return "Action";
    case NodeKind::Condition: return "Condition";
    case NodeKind::Control: return "Control";
    case NodeKind::Decorator: return "Decorator";
    case NodeKind::SubTree: return "SubTree";
  }
  return "?";
}

}  // namespace cairn::bt
