// Loader for BehaviorTree.CPP v4 XML (BTCPP_format="4"): several <BehaviorTree> per file, <include>,
// <TreeNodesModel>, SubTree remapping and _autoremap. Every error carries file:line.
#pragma once

#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "cairn/bt_executive/factory.hpp"
#include "cairn/bt_executive/tree.hpp"

namespace cairn::bt {

struct LoadError : std::runtime_error {
  LoadError(std::string file_, int line_, const std::string& msg)
      : std::runtime_error(file_ + ":" + std::to_string(line_) + ": " + msg), file(std::move(file_)), line(line_),
        message(msg) {}
  std::string file;
  int line;
  std::string message;
};

struct LoadOptions {
  /// Tree to instantiate; empty: the root's main_tree_to_execute, else the only tree of the main file.
  std::string main_tree;
  /// Root scope to use (entries declared there keep their types); a fresh one if null.
  std::shared_ptr<Blackboard> blackboard;
};

Tree loadTreeFromFile(const NodeFactory& factory, const std::string& path, const LoadOptions& options = {});
Tree loadTreeFromText(const NodeFactory& factory, std::string_view xml, const LoadOptions& options = {},
                      const std::string& filename = "<text>");

/// IDs of the <BehaviorTree> elements of a file (and its includes), in document order.
std::vector<std::string> listTreeIds(const std::string& path);

}  // namespace cairn::bt
