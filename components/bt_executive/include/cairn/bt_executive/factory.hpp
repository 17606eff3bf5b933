// Registry of node types (built-ins are registered by the constructor) and their port manifests.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <type_traits>
#include <vector>

#include "cairn/bt_executive/script.hpp"
#include "cairn/bt_executive/tree_node.hpp"

namespace cairn::bt {

struct NodeManifest {
  std::string id;
  NodeKind kind = NodeKind::Action;
  PortList ports;
  std::string description;
  int min_children = 0;
  int max_children = 0;  ///< -1 = unlimited
  std::function<std::unique_ptr<TreeNode>(const NodeConfig&)> create;

  const PortInfo* port(std::string_view name) const;
};

template <class T>
concept HasProvidedPorts = requires { { T::providedPorts() } -> std::convertible_to<PortList>; };

class NodeFactory {
 public:
  /// Registers every built-in control, decorator and action (see README "Node catalogue").
  NodeFactory();

  void registerManifest(NodeManifest m);

  /// Registers a node class constructible from `const NodeConfig&`, with an optional static providedPorts().
  template <class T>
  void registerNodeType(std::string id, std::string description = {}) {
    NodeManifest m;
    m.id = std::move(id);
    m.description = std::move(description);
    if constexpr (HasProvidedPorts<T>) m.ports = T::providedPorts();
    if constexpr (std::is_base_of_v<ConditionNode, T>) {
      m.kind = NodeKind::Condition;
    } else if constexpr (std::is_base_of_v<ControlNode, T>) {
      m.kind = NodeKind::Control;
      m.min_children = 1;
      m.max_children = -1;
    } else if constexpr (std::is_base_of_v<DecoratorNode, T>) {
      m.kind = NodeKind::Decorator;
      m.min_children = 1;
      m.max_children = 1;
    } else {
      m.kind = NodeKind::Action;
    }
    m.create = [](const NodeConfig& c) -> std::unique_ptr<TreeNode> { return std::make_unique<T>(c); };
    registerManifest(std::move(m));
  }

  /// Synchronous action from a functor (no ports). `fn` must return SUCCESS or FAILURE.
  void registerSimpleAction(std::string id, std::function<NodeStatus()> fn);
  void registerSimpleCondition(std::string id, std::function<bool()> fn);

  /// Identifiers usable in scripts as integer constants (BT.CPP "scripting enums").
  void registerScriptEnum(std::string name, std::int64_t value) { enums_[std::move(name)] = value; }
  const ScriptEnums& scriptEnums() const { return enums_; }

  const NodeManifest* find(std::string_view id) const;
  std::vector<const NodeManifest*> manifests() const;

 private:
  std::map<std::string, NodeManifest, std::less<>> manifests_;
  ScriptEnums enums_;
};

/// The `<TreeNodesModel>` XML of every registered node (for Groot2 and `cairn bt model`).
std::string writeTreeNodesModel(const NodeFactory& factory, bool include_builtins = false);

}  // namespace cairn::bt
