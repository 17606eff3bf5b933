// The component container: loads components by class name into one process and serves
// <container>/_container/load_node, unload_node and list_nodes (composition_interfaces) over DDS. The container's
// node has a read-only parameter `pid` (its process id), so monitors can find the process of a container.
#ifndef CAIRN_CONTAINER_HPP
#define CAIRN_CONTAINER_HPP

#include <chrono>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "cairn/component.hpp"
#include "cairn/node.hpp"

namespace cairn {

struct LoadRequest {
  LoadRequest() = default;
  LoadRequest(std::string cls, std::string name) : class_name(std::move(cls)), node_name(std::move(name)) {}
  std::string class_name;
  std::string node_name;  ///< empty: derived from the class name (Talker -> talker)
  std::string node_namespace = "/";
  std::map<std::string, ParameterValue> parameters;
  std::map<std::string, std::string> remaps;
  std::map<std::string, QoSOverride> qos_overrides;
  bool use_intra_process = true;
  /// Restart with the original launch parameters: take the parameters, remaps, QoS overrides and intra-process
  /// setting of the last successful load of the same node (fqn) in this container, overlaid by the ones given here
  /// (class: empty means the remembered one). Over DDS: extra argument `restore_parameters: true` of load_node.
  bool restore_parameters = false;
  /// The sender already checked the parameters against the class (`cairn launch` validates the whole spec, dry-run
  /// constructions included, before it starts anything), so the container skips its own dry-run construction.
  /// Over DDS: extra argument `parameters_validated: true` of load_node.
  bool parameters_validated = false;
};

/// Error text of a restore_parameters load when this container never loaded that node (e.g. it was just
/// respawned and its supervisor has not reloaded it yet); a caller may retry later.
inline constexpr const char* kNothingToRestore = "nothing to restore";

struct LoadResult {
  bool ok = false;
  std::string error;
  std::string full_node_name;
  uint64_t unique_id = 0;
};

class ComponentManager {
 public:
  struct Options {
    std::chrono::milliseconds load_timeout{10000};
  };
  ComponentManager(std::shared_ptr<Context> ctx, Executor& exec, const std::string& name, ComponentLoader& loader,
                   Options opts);
  ComponentManager(std::shared_ptr<Context> ctx, Executor& exec, const std::string& name, ComponentLoader& loader)
      : ComponentManager(std::move(ctx), exec, name, loader, Options{}) {}
  ~ComponentManager();

  /// Constructs the component (at most load_timeout; a constructor that throws or hangs gives an error and
  /// leaves the container serving its other components).
  LoadResult load(const LoadRequest& req);
  std::optional<std::string> unload(uint64_t id);
  std::vector<std::pair<uint64_t, std::string>> list() const;
  /// The component object (for tests and in-process tools); null if no such id.
  std::shared_ptr<void> get(uint64_t id) const;
  /// What the node `fqn` was last loaded with (kept after unload, so a restart can restore it).
  std::optional<LoadRequest> remembered(const std::string& fqn) const;
  const std::string& name() const { return name_; }

 private:
  struct Loaded {
    std::string fqn;
    std::string class_name;
    std::shared_ptr<void> object;
  };
  std::shared_ptr<Context> ctx_;
  Executor& exec_;
  std::string name_;
  ComponentLoader& loader_;
  Options opts_;
  std::unique_ptr<Node> node_;
  mutable std::mutex mu_;
  uint64_t next_id_ = 1;
  std::map<uint64_t, Loaded> loaded_;
  std::map<std::string, LoadRequest> remembered_;  ///< fqn -> effective request of its last successful load
  std::vector<std::thread> workers_;
};

/// "Talker" / "cairn_demo::Talker" / "ScanMatcherNode" -> "talker" / "talker" / "scan_matcher_node"
std::string default_node_name(const std::string& class_name);

/// After a component was constructed and destroyed in the dry-run context `dry`: the one-line error for the
/// first parameter it was given but never declared, "params.<name>: <class> (<fqn>) has no such parameter
/// (declared: a, b)", or nullopt. Launch validation and the container's load_node both refuse such loads.
std::optional<std::string> unknown_parameter_error(const Context& dry, const std::string& class_name,
                                                   const std::string& fqn);

/// Runs `cairn container --name N [--threads K] [--load-timeout S]` until SIGINT/SIGTERM. Returns the exit code.
int run_container_main(int argc, char** argv);

}  // namespace cairn

#endif  // CAIRN_CONTAINER_HPP
