#include "cairn/container.hpp"

#include <unistd.h>

#include <cctype>
#include <future>
#include <iostream>

#include "cairn/launch.hpp"
#include "cairn/parameter_msgs.hpp"
#include "composition_interfaces/srv/ListNodes.hpp"
#include "composition_interfaces/srv/LoadNode.hpp"
#include "composition_interfaces/srv/UnloadNode.hpp"

namespace cairn {

using composition_interfaces::srv::ListNodes_Request;
using composition_interfaces::srv::ListNodes_Response;
using composition_interfaces::srv::LoadNode_Request;
using composition_interfaces::srv::LoadNode_Response;
using composition_interfaces::srv::UnloadNode_Request;
using composition_interfaces::srv::UnloadNode_Response;

std::string default_node_name(const std::string& class_name) {
  std::string base = class_name.substr(class_name.rfind(':') == std::string::npos ? 0 : class_name.rfind(':') + 1);
  std::string out;
  for (std::size_t i = 0; i < base.size(); ++i) {
    const char c = base[i];
    if (std::isupper(static_cast<unsigned char>(c))) {
      if (i > 0 && !std::isupper(static_cast<unsigned char>(base[i - 1]))) out += '_';
      out += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    } else {
      out += c;
    }
  }
  return out;
}

std::optional<std::string> unknown_parameter_error(const Context& dry, const std::string& class_name,
                                                   const std::string& fqn) {
  const auto unused = dry.unused_parameters();
  if (unused.empty()) return std::nullopt;
  const auto& first = unused.front();  // the one dry-run node; its first unknown name
  std::string declared;
  for (const auto& d : first.declared) declared += (declared.empty() ? "" : ", ") + d;
  return "params." + first.names.front() + ": " + class_name + " (" + fqn + ") has no such parameter (declared: " +
         declared + ")";
}

namespace {
struct UnknownParameter : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

LoadRequest from_msg(const LoadNode_Request& r) {
  LoadRequest out;
  out.class_name = r.plugin_name;
  out.node_name = r.node_name;
  out.node_namespace = r.node_namespace.empty() ? "/" : r.node_namespace;
  for (const auto& p : r.parameters) out.parameters[p.name] = from_parameter_msg(p.value);
  for (const auto& rule : r.remap_rules) {
    const auto pos = rule.find(":=");
    if (pos != std::string::npos) out.remaps[rule.substr(0, pos)] = rule.substr(pos + 2);
  }
  for (const auto& p : r.extra_arguments) {
    const auto v = from_parameter_msg(p.value);
    if (p.name == "use_intra_process_comms" && std::holds_alternative<bool>(v)) {
      out.use_intra_process = std::get<bool>(v);
    } else if (p.name == "restore_parameters" && std::holds_alternative<bool>(v)) {
      out.restore_parameters = std::get<bool>(v);
    } else if (p.name == "parameters_validated" && std::holds_alternative<bool>(v)) {
      out.parameters_validated = std::get<bool>(v);
    } else if (p.name.rfind("qos:", 0) == 0 && std::holds_alternative<std::string>(v)) {
      // qos:<topic>:<key> = value
      const auto last = p.name.rfind(':');
      out.qos_overrides[p.name.substr(4, last - 4)].set(p.name.substr(last + 1), std::get<std::string>(v));
    }
  }
  return out;
}
}  // namespace

ComponentManager::ComponentManager(std::shared_ptr<Context> ctx, Executor& exec, const std::string& name,
                                   ComponentLoader& loader, Options opts)
    : ctx_(std::move(ctx)), exec_(exec), name_(name), loader_(loader), opts_(opts) {
  NodeOptions no(name, &exec);
  no.context = ctx_;
  node_ = std::make_unique<Node>(no);
  node_->declare_parameter<int64_t>("pid", static_cast<int64_t>(getpid()),
                                    ParameterDescriptor{"process id of this container (for CPU/RAM monitors)", {}, {}, true});
  node_->create_deferred_service<LoadNode_Request, LoadNode_Response>(
      "~/_container/load_node", [this](const LoadNode_Request& req, std::function<void(LoadNode_Response)> reply) {
        // construct off the executor thread: a slow constructor must not stall the container
        std::lock_guard l(mu_);
        workers_.emplace_back([this, req, reply = std::move(reply)] {
          LoadNode_Response resp;
          const LoadResult r = load(from_msg(req));
          resp.success = r.ok;
          resp.error_message = r.error;
          resp.full_node_name = r.full_node_name;
          resp.unique_id = r.unique_id;
          reply(resp);
        });
      });
  node_->create_service<UnloadNode_Request, UnloadNode_Response>(
      "~/_container/unload_node", [this](const UnloadNode_Request& req, UnloadNode_Response& resp) {
        auto err = unload(req.unique_id);
        resp.success = !err;
        resp.error_message = err.value_or("");
      });
  node_->create_service<ListNodes_Request, ListNodes_Response>(
      "~/_container/list_nodes", [this](const ListNodes_Request&, ListNodes_Response& resp) {
        for (const auto& [id, fqn] : list()) {
          resp.unique_ids.push_back(id);
          resp.full_node_names.push_back(fqn);
        }
      });
}

ComponentManager::~ComponentManager() {
  std::vector<std::thread> workers;
  {
    std::lock_guard l(mu_);
    workers.swap(workers_);
  }
  for (auto& w : workers) w.join();
  node_.reset();
  std::map<uint64_t, Loaded> loaded;
  {
    std::lock_guard l(mu_);
    loaded.swap(loaded_);
  }
  loaded.clear();  // components are destroyed here, newest last
}

LoadResult ComponentManager::load(const LoadRequest& requested) {
  LoadResult res;
  // One spelling of the namespace ("robot" and "/robot/" are "/robot") for names, duplicates and restores.
  LoadRequest given = requested;
  try {
    given.node_namespace = normalize_namespace(requested.node_namespace);
  } catch (const std::exception& e) {
    res.error = e.what();
    return res;
  }
  LoadRequest req = given;
  if (given.restore_parameters) {
    const std::string name = given.node_name.empty() ? default_node_name(given.class_name) : given.node_name;
    const std::string fqn = (given.node_namespace == "/" ? "" : given.node_namespace) + "/" + name;
    const auto old = remembered(fqn);
    if (!old) {
      res.error = std::string(kNothingToRestore) + ": " + fqn + " was never loaded in container " + name_;
      CAIRN_WARN(node_->logger(), "load " << fqn << ": " << res.error);
      return res;
    }
    if (!given.class_name.empty() && given.class_name != old->class_name) {
      res.error = "cannot restore " + fqn + " as " + given.class_name + ": it was loaded as " + old->class_name;
      return res;
    }
    req = *old;
    for (const auto& [k, v] : given.parameters) req.parameters[k] = v;
    for (const auto& [k, v] : given.remaps) req.remaps[k] = v;
    for (const auto& [k, v] : given.qos_overrides) req.qos_overrides[k] = v;
    req.restore_parameters = false;
  }
  const ComponentFactory* factory = nullptr;
  try {
    factory = &loader_.factory(req.class_name);
  } catch (const std::exception& e) {
    res.error = e.what();
    CAIRN_ERROR(node_->logger(), "load " << req.class_name << ": " << res.error);
    return res;
  }
  NodeOptions no(req.node_name.empty() ? default_node_name(req.class_name) : req.node_name, &exec_);
  no.namespace_ = req.node_namespace;
  no.context = ctx_;
  no.parameter_overrides = req.parameters;
  no.remaps = req.remaps;
  no.qos_overrides = req.qos_overrides;
  no.use_intra_process = req.use_intra_process;
  const std::string fqn = (no.namespace_ == "/" ? "" : no.namespace_) + "/" + no.name;
  {
    std::lock_guard l(mu_);
    for (const auto& [id, c] : loaded_) {
      if (c.fqn == fqn) {
        res.error = "a node named " + fqn + " is already loaded in container " + name_;
        return res;
      }
    }
  }
  // The constructor runs on its own thread so that one that hangs is reported after load_timeout
  // instead of blocking the container forever.
  auto state = std::make_shared<std::promise<std::shared_ptr<void>>>();
  auto fut = state->get_future();
  std::thread([state, factory, no, class_name = req.class_name, fqn, check = !req.parameters_validated] {
    try {
      if (check && !no.parameter_overrides.empty()) {
        // Parameters the component does not declare are refused, as by launch validation: a dry run first
        // (no DDS), which also finds them in components that never read them. Loads from `cairn launch` skip it:
        // the spec's validation did the same dry run before anything started.
        NodeOptions dry = no;
        dry.executor = nullptr;
        dry.context = Context::create(ContextOptions{-1, true});
        (*factory)(dry).reset();
        if (auto err = unknown_parameter_error(*dry.context, class_name, fqn)) throw UnknownParameter(*err);
      }
      state->set_value((*factory)(no));
    } catch (...) {
      state->set_exception(std::current_exception());
    }
  }).detach();
  if (fut.wait_for(opts_.load_timeout) != std::future_status::ready) {
    res.error = "component " + req.class_name + " (" + fqn + ") did not finish constructing within " +
                std::to_string(opts_.load_timeout.count()) + " ms";
    CAIRN_ERROR(node_->logger(), res.error);
    return res;
  }
  std::shared_ptr<void> obj;
  try {
    obj = fut.get();
  } catch (const UnknownParameter& e) {
    res.error = e.what();
    CAIRN_ERROR(node_->logger(), "load " << fqn << ": " << res.error);
    return res;
  } catch (const std::exception& e) {
    res.error = "component " + req.class_name + " (" + fqn + ") failed to construct: " + e.what();
    CAIRN_ERROR(node_->logger(), res.error);
    return res;
  } catch (...) {
    res.error = "component " + req.class_name + " (" + fqn + ") failed to construct: unknown exception";
    CAIRN_ERROR(node_->logger(), res.error);
    return res;
  }
  std::lock_guard l(mu_);
  res.ok = true;
  res.unique_id = next_id_++;
  res.full_node_name = fqn;
  loaded_[res.unique_id] = Loaded{fqn, req.class_name, std::move(obj)};
  remembered_[fqn] = req;
  CAIRN_INFO(node_->logger(), "loaded " << req.class_name << " as " << fqn << " (id " << res.unique_id << ")");
  return res;
}

std::optional<std::string> ComponentManager::unload(uint64_t id) {
  std::shared_ptr<void> obj;
  std::string fqn;
  {
    std::lock_guard l(mu_);
    auto it = loaded_.find(id);
    if (it == loaded_.end()) return "no component with id " + std::to_string(id) + " in container " + name_;
    obj = std::move(it->second.object);
    fqn = it->second.fqn;
    loaded_.erase(it);
  }
  obj.reset();  // destroys the component: its entities are disabled and removed first
  CAIRN_INFO(node_->logger(), "unloaded " << fqn << " (id " << id << ")");
  return std::nullopt;
}

std::shared_ptr<void> ComponentManager::get(uint64_t id) const {
  std::lock_guard l(mu_);
  auto it = loaded_.find(id);
  return it == loaded_.end() ? nullptr : it->second.object;
}

std::optional<LoadRequest> ComponentManager::remembered(const std::string& fqn) const {
  std::lock_guard l(mu_);
  auto it = remembered_.find(fqn);
  if (it == remembered_.end()) return std::nullopt;
  return it->second;
}

std::vector<std::pair<uint64_t, std::string>> ComponentManager::list() const {
  std::lock_guard l(mu_);
  std::vector<std::pair<uint64_t, std::string>> out;
  for (const auto& [id, c] : loaded_) out.emplace_back(id, c.fqn);
  return out;
}

int run_container_main(int argc, char** argv) {
  std::string name;
  std::size_t threads = 1;
  double load_timeout = 10.0;
  try {
    for (int i = 0; i < argc; ++i) {
      const std::string a = argv[i];
      auto value = [&](const char* what) -> std::string {
        if (i + 1 >= argc) throw OptionError(std::string("missing value after ") + what);
        return argv[++i];
      };
      if (a == "--name") {
        name = value("--name");
      } else if (a == "--threads") {  // the range of a launch spec's container.threads
        threads = static_cast<std::size_t>(option_number("--threads", value("--threads"), 1, 64, true));
      } else if (a == "--load-timeout") {  // the range of a launch spec's load_timeout
        load_timeout = option_number("--load-timeout", value("--load-timeout"), 0.1, 3600);
      } else if (a == "-h" || a == "--help") {
        std::cout << "usage: cairn container --name NAME [--threads 1..64] [--load-timeout 0.1..3600 s]\n";
        return 0;
      } else {
        throw OptionError("unknown argument '" + a + "'");
      }
    }
    if (name.empty()) throw OptionError("--name is required");
  } catch (const OptionError& e) {
    std::cerr << "cairn: container: " << e.what() << "\n";
    return 2;
  }
  Executor::install_signal_handlers();
  auto ctx = Context::default_context();
  Executor exec(Executor::Options{threads});
  ComponentLoader loader;
  ComponentManager mgr(ctx, exec, name, loader,
                       ComponentManager::Options{std::chrono::milliseconds(static_cast<int64_t>(load_timeout * 1000))});
  CAIRN_INFO(Logger(name), "container ready (domain " << ctx->domain_id() << ", " << threads << " thread"
                                                      << (threads == 1 ? "" : "s") << ")");
  exec.spin();
  CAIRN_INFO(Logger(name), "shutting down");
  return 0;
}

}  // namespace cairn
