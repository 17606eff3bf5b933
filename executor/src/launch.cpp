#include "cairn/launch.hpp"

#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <set>
#include <sstream>
#include <thread>

#include <yaml-cpp/yaml.h>

#include "cairn/container.hpp"
#include "cairn/parameter_msgs.hpp"
#include "cairn/strict_number.hpp"
#include "composition_interfaces/srv/LoadNode.hpp"

namespace cairn {

namespace {

int line_of(const YAML::Node& n) { return n.Mark().line >= 0 ? n.Mark().line + 1 : 0; }

// A range bound in messages: shortest form ("64", "0.1", "1e+09").
std::string fmt(double v) {
  std::ostringstream o;
  o << v;
  return o.str();
}

class SpecParser {
 public:
  explicit SpecParser(std::string file) : file_(std::move(file)) {}

  [[noreturn]] void fail(const YAML::Node& n, const std::string& what) const { throw LaunchError(file_, line_of(n), what); }

  // yaml-cpp keeps both entries of a repeated key and node["key"] finds only the first: the second would be
  // silently ignored.
  void unique_keys(const YAML::Node& map, const std::string& where) const {
    std::set<std::string> seen;
    for (const auto& kv : map)
      if (!seen.insert(kv.first.as<std::string>()).second)
        fail(kv.first, where + ": duplicate key '" + kv.first.as<std::string>() + "'");
  }

  void allow_keys(const YAML::Node& map, const std::string& where, std::initializer_list<const char*> keys) const {
    unique_keys(map, where);
    for (const auto& kv : map) {
      const std::string k = kv.first.as<std::string>();
      bool ok = false;
      for (const char* a : keys) ok = ok || k == a;
      if (!ok) {
        std::string list;
        for (const char* a : keys) list += (list.empty() ? "" : ", ") + std::string(a);
        fail(kv.first, where + ": unknown key '" + k + "' (allowed: " + list + ")");
      }
    }
  }

  std::string str(const YAML::Node& n, const std::string& key) const {
    if (!n.IsScalar()) fail(n, key + ": expected a string");
    return n.Scalar();
  }

  bool boolean(const YAML::Node& n, const std::string& key) const {
    bool b;
    if (!n.IsScalar() || !YAML::convert<bool>::decode(n, b)) fail(n, key + ": expected true or false");
    return b;
  }

  double number(const YAML::Node& n, const std::string& key, double lo, double hi, bool integer = false) const {
    if (!n.IsScalar()) fail(n, key + ": expected " + (integer ? "an integer" : "a number"));
    const auto v = parse_number(n.Scalar());
    if (!v || (integer && *v != std::floor(*v)))
      fail(n, key + ": expected " + (integer ? "an integer" : "a number") + ", got '" + n.Scalar() + "'");
    if (*v < lo || *v > hi) fail(n, key + ": " + n.Scalar() + " is outside [" + fmt(lo) + ", " + fmt(hi) + "]");
    return *v;
  }

  LaunchSpec parse(const YAML::Node& root) {
    LaunchSpec spec;
    spec.file = file_;
    if (!root.IsMap()) fail(root, "a launch spec is a map with 'containers' and/or 'processes'");
    allow_keys(root, "spec", {"domain_id", "load_timeout", "containers", "processes"});
    if (root["domain_id"]) spec.domain_id = static_cast<int>(number(root["domain_id"], "domain_id", 0, 232, true));
    if (root["load_timeout"]) spec.load_timeout_s = number(root["load_timeout"], "load_timeout", 0.1, 3600);
    std::set<std::string> names, fqns;
    if (const auto cs = root["containers"]) {
      if (!cs.IsSequence()) fail(cs, "containers: expected a list");
      for (const auto& c : cs) spec.containers.push_back(container(c, names, fqns));
    }
    if (const auto ps = root["processes"]) {
      if (!ps.IsSequence()) fail(ps, "processes: expected a list");
      for (const auto& p : ps) spec.processes.push_back(process(p, names));
    }
    if (spec.containers.empty() && spec.processes.empty()) fail(root, "spec: nothing to launch (no containers, no processes)");
    // Every container is a node (/<name>), and an isolated component runs in a container <container>__<name>:
    // neither may take a name that something else has.
    for (const auto& c : spec.containers)
      for (const auto& comp : c.components) {
        for (const auto& other : spec.containers)
          if (comp.fqn() == "/" + other.name)
            throw LaunchError(file_, comp.line, "component: node name '" + comp.fqn() + "' is also container " +
                                                    other.name + "'s node name");
        if (comp.isolated && !names.insert(c.name + "__" + comp.name).second)
          throw LaunchError(file_, comp.line, "component: isolated, it runs in container '" + c.name + "__" +
                                                  comp.name + "', a name that is already taken");
      }
    return spec;
  }

  LaunchContainer container(const YAML::Node& n, std::set<std::string>& names, std::set<std::string>& fqns) {
    if (!n.IsMap()) fail(n, "containers[]: expected a map");
    allow_keys(n, "container", {"name", "threads", "components", "respawn", "respawn_delay"});
    LaunchContainer c;
    c.line = line_of(n);
    if (!n["name"]) fail(n, "container: missing 'name'");
    c.name = str(n["name"], "container.name");
    if (!valid_name(c.name)) fail(n["name"], "container.name: '" + c.name + "' is not a valid node name");
    if (!names.insert(c.name).second) fail(n["name"], "container.name: duplicate name '" + c.name + "'");
    if (n["threads"]) c.threads = static_cast<std::size_t>(number(n["threads"], "container.threads", 1, 64, true));
    respawn(n, "container", c.respawn);
    if (const auto comps = n["components"]) {
      if (!comps.IsSequence()) fail(comps, "container.components: expected a list");
      for (const auto& x : comps) c.components.push_back(component(x, fqns));
    }
    return c;
  }

  LaunchComponent component(const YAML::Node& n, std::set<std::string>& fqns) {
    if (!n.IsMap()) fail(n, "components[]: expected a map");
    allow_keys(n, "component",
               {"class", "name", "namespace", "params", "params_file", "remap", "qos", "isolated", "intra_process"});
    LaunchComponent c;
    c.line = line_of(n);
    if (!n["class"]) fail(n, "component: missing 'class'");
    c.class_name = str(n["class"], "component.class");
    c.name = n["name"] ? str(n["name"], "component.name") : default_node_name(c.class_name);
    if (!valid_name(c.name)) fail(n["name"] ? n["name"] : n, "component.name: '" + c.name + "' is not a valid node name");
    if (n["namespace"]) {
      try {  // the node's own rule ("robot", "/robot/" -> "/robot"), so fqn and remap keys match the node
        c.ns = normalize_namespace(str(n["namespace"], "component.namespace"));
      } catch (const NodeError& e) {
        fail(n["namespace"], std::string("component.namespace: ") + e.what());
      }
    }
    if (!fqns.insert(c.fqn()).second) fail(n, "component: duplicate node name '" + c.fqn() + "'");
    if (const auto p = n["params"]) {
      c.params_line = line_of(p);
      if (!p.IsMap()) fail(p, "component.params: expected a map of name: value");
      unique_keys(p, "component.params");
      for (const auto& kv : p) {
        const std::string k = kv.first.as<std::string>();
        try {
          c.params[k] = parameter_from_yaml(kv.second);
        } catch (const std::exception& e) {
          fail(kv.second, "params." + k + ": " + e.what());
        }
      }
    }
    if (const auto pf = n["params_file"]) {
      // ROS 2 parameter file: {<node fqn | /** | *>: {ros__parameters: {name: value}}}; params given inline win
      if (!c.params_line) c.params_line = line_of(pf);
      load_params_file(str(pf, "component.params_file"), c);
    }
    if (const auto r = n["remap"]) {
      c.remap_line = line_of(r);
      if (!r.IsMap()) fail(r, "component.remap: expected a map of from: to");
      unique_keys(r, "component.remap");
      for (const auto& kv : r) c.remaps[kv.first.as<std::string>()] = str(kv.second, "remap." + kv.first.as<std::string>());
    }
    if (const auto q = n["qos"]) {
      c.qos_line = line_of(q);
      if (!q.IsMap()) fail(q, "component.qos: expected a map of topic: {key: value}");
      unique_keys(q, "component.qos");
      for (const auto& kv : q) {
        const std::string topic = kv.first.as<std::string>();
        if (!kv.second.IsMap()) fail(kv.second, "qos." + topic + ": expected a map");
        unique_keys(kv.second, "qos." + topic);
        QoSOverride o;
        for (const auto& f : kv.second) {
          const std::string key = f.first.as<std::string>();
          if (auto err = o.set(key, str(f.second, "qos." + topic + "." + key))) fail(f.first, "qos." + topic + ": " + *err);
        }
        c.qos[topic] = o;
      }
    }
    if (n["isolated"]) c.isolated = boolean(n["isolated"], "component.isolated");
    if (n["intra_process"]) c.use_intra_process = boolean(n["intra_process"], "component.intra_process");
    return c;
  }

  LaunchProcess process(const YAML::Node& n, std::set<std::string>& names) {
    if (!n.IsMap()) fail(n, "processes[]: expected a map");
    allow_keys(n, "process", {"name", "cmd", "respawn", "respawn_delay"});
    LaunchProcess p;
    p.line = line_of(n);
    if (!n["name"]) fail(n, "process: missing 'name'");
    p.name = str(n["name"], "process.name");
    if (!names.insert(p.name).second) fail(n["name"], "process.name: duplicate name '" + p.name + "'");
    if (!n["cmd"] || !n["cmd"].IsSequence() || n["cmd"].size() == 0) fail(n, "process.cmd: expected a non-empty list");
    for (const auto& a : n["cmd"]) p.cmd.push_back(str(a, "process.cmd[]"));
    respawn(n, "process", p.respawn);
    return p;
  }

  void respawn(const YAML::Node& n, const std::string& where, RespawnPolicy& r) const {
    if (n["respawn"]) r.respawn = boolean(n["respawn"], where + ".respawn");
    if (n["respawn_delay"]) r.delay_s = number(n["respawn_delay"], where + ".respawn_delay", 0, 3600);
  }

  void load_params_file(const std::string& rel, LaunchComponent& c) const {
    namespace fs = std::filesystem;
    fs::path path = rel;
    if (path.is_relative()) path = fs::path(file_).parent_path() / path;
    std::error_code ec;
    const bool directory = fs::is_directory(path, ec);
    std::ifstream in(path);
    if (directory || !in)
      throw LaunchError(file_, c.params_line, "component.params_file: cannot read '" + path.string() + "'" +
                                                  (directory ? " (a directory)" : ""));
    YAML::Node root;
    const std::string pfile = path.string();
    try {
      std::stringstream text;
      text << in.rdbuf();
      root = YAML::Load(text.str());
    } catch (const YAML::Exception& e) {
      throw LaunchError(pfile, e.mark.line >= 0 ? e.mark.line + 1 : 0, "YAML syntax error: " + e.msg);
    }
    if (!root.IsMap()) throw LaunchError(pfile, line_of(root), "a parameter file maps node names to {ros__parameters: {...}}");
    // A file given for a component but holding nothing for it is a mistake (a flat {name: value} file, or
    // another node's name): its parameters would silently not apply.
    std::string keys;
    bool matched = false;
    for (const auto& kv : root) {
      const std::string node = kv.first.as<std::string>();
      keys += (keys.empty() ? "" : ", ") + node;
      if (node != c.fqn() && node != c.name && node != "/**" && node != "**" && node != "*") continue;
      matched = true;
      const auto rp = kv.second["ros__parameters"];
      if (!rp || !rp.IsMap()) throw LaunchError(pfile, line_of(kv.second), node + ": expected ros__parameters: {name: value}");
      std::set<std::string> seen;
      for (const auto& p : rp) {
        const std::string k = p.first.as<std::string>();
        if (!seen.insert(k).second)  // yaml-cpp keeps both; the second would be silently ignored
          throw LaunchError(pfile, line_of(p.first), node + ".ros__parameters: duplicate key '" + k + "'");
        if (c.params.count(k)) continue;
        try {
          c.params[k] = parameter_from_yaml(p.second);
        } catch (const std::exception& e) {
          throw LaunchError(pfile, line_of(p.second), node + ".ros__parameters." + k + ": " + e.what());
        }
      }
    }
    if (!matched)
      throw LaunchError(file_, c.params_line,
                        "component.params_file: '" + pfile + "' has no entry for " + c.fqn() + " (its keys: " + keys +
                            "; expected " + c.fqn() + ", " + c.name + " or /** mapping to {ros__parameters: {...}})");
  }

  static bool valid_name(const std::string& s) {
    return !s.empty() && !std::isdigit(static_cast<unsigned char>(s[0])) &&
           std::all_of(s.begin(), s.end(), [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; });
  }

 private:
  std::string file_;
};

/// Resolves a remap key/value the way the node will (relative names live in the component's namespace).
std::string resolve_in(const std::string& ns, const std::string& name) {
  if (!name.empty() && name[0] == '/') return name;
  return (ns == "/" ? "" : ns) + "/" + name;
}

}  // namespace

double RespawnPolicy::delay_for(int consecutive) const {
  double d = delay_s;
  for (int k = 1; k < consecutive && d < 30.0; ++k) d *= 2;
  return std::min(d, std::max(delay_s, 30.0));
}

std::optional<double> parse_number(const std::string& text) { return strict_number::parse_finite(text); }

double option_number(const std::string& option, const std::string& text, double lo, double hi, bool integer) {
  const auto v = parse_number(text);
  if (!v || *v < lo || *v > hi || (integer && *v != std::floor(*v))) {
    throw OptionError(option + " expects " + (integer ? "an integer" : "a number") + " in [" + fmt(lo) + ", " +
                      fmt(hi) + "], got '" + text + "'");
  }
  return *v;
}

LaunchSpec parse_launch_spec_text(const std::string& text, const std::string& file) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw LaunchError(file, e.mark.line >= 0 ? e.mark.line + 1 : 0, "YAML syntax error: " + e.msg);
  }
  try {
    return SpecParser(file).parse(root);
  } catch (const LaunchError&) {
    throw;
  } catch (const YAML::Exception& e) {
    throw LaunchError(file, e.mark.line >= 0 ? e.mark.line + 1 : 0, e.msg);
  }
}

LaunchSpec parse_launch_spec(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw LaunchError(path, 0, "cannot read the file");
  std::stringstream ss;
  ss << in.rdbuf();
  return parse_launch_spec_text(ss.str(), path);
}

std::string launch_spec_error(const std::string& text, const std::string& file) {
  ComponentLoader loader;
  try {
    validate_launch_spec(parse_launch_spec_text(text, file), loader);
  } catch (const LaunchError& e) {
    return e.what();
  }
  return "";
}

void validate_launch_spec(const LaunchSpec& spec, ComponentLoader& loader) {
  struct End {
    EndpointRecord rec;
    const LaunchComponent* comp;
  };
  std::map<std::string, std::vector<End>> topics;
  for (const auto& cont : spec.containers) {
    for (const auto& c : cont.components) {
      const ComponentFactory* factory = nullptr;
      try {
        factory = &loader.factory(c.class_name);
      } catch (const std::exception& e) {
        throw LaunchError(spec.file, c.line, "component.class: " + std::string(e.what()));
      }
      auto ctx = Context::create(ContextOptions{-1, true});
      NodeOptions no(c.name, nullptr);
      no.namespace_ = c.ns;
      no.context = ctx;
      no.parameter_overrides = c.params;
      for (const auto& [from, to] : c.remaps) no.remaps[resolve_in(c.ns, from)] = to;
      for (const auto& [topic, o] : c.qos) no.qos_overrides[resolve_in(c.ns, topic)] = o;
      no.use_intra_process = c.use_intra_process;
      std::shared_ptr<void> obj;
      try {
        obj = (*factory)(no);
      } catch (const ParameterError& e) {
        throw LaunchError(spec.file, c.params_line ? c.params_line : c.line, "params: " + c.fqn() + ": " + e.what());
      } catch (const std::exception& e) {
        throw LaunchError(spec.file, c.line, c.class_name + " (" + c.fqn() + ") cannot be constructed: " + e.what());
      }
      obj.reset();  // the node reports parameters nobody declared as it goes
      if (auto err = unknown_parameter_error(*ctx, c.class_name, c.fqn()))
        throw LaunchError(spec.file, c.params_line ? c.params_line : c.line, *err);
      for (const auto& r : ctx->records()) {
        if (r.kind == EndpointRecord::Kind::Publisher || r.kind == EndpointRecord::Kind::Subscription) {
          topics[r.topic].push_back(End{r, &c});
        }
      }
    }
  }
  for (const auto& [topic, ends] : topics) {
    for (const auto& e : ends) {
      if (e.rec.type != ends.front().rec.type) {
        const auto& a = ends.front();
        throw LaunchError(spec.file, e.comp->remap_line ? e.comp->remap_line : e.comp->line,
                          "topic " + topic + ": " + e.comp->fqn() + " uses " + e.rec.type + " but " + a.comp->fqn() +
                              " uses " + a.rec.type + " (a remapping joins two message types)");
      }
    }
    for (const auto& p : ends) {
      if (p.rec.kind != EndpointRecord::Kind::Publisher) continue;
      for (const auto& s : ends) {
        if (s.rec.kind != EndpointRecord::Kind::Subscription) continue;
        if (auto why = qos_incompatibility(p.rec.qos, s.rec.qos)) {
          throw LaunchError(spec.file, s.comp->qos_line ? s.comp->qos_line : s.comp->line,
                            "topic " + topic + ": " + s.comp->fqn() + " never hears " + p.comp->fqn() + ": " + *why);
        }
      }
    }
  }
}

}  // namespace cairn

// ---------------------------------------------------------------------------------------------------
// The launcher: containers as supervised child processes, components loaded over the DDS load_node service.
#include "cairn/process.hpp"

namespace cairn {

namespace {

using SteadyTime = std::chrono::steady_clock::time_point;

/// A supervised child: when it dies it is respawned after its policy's backoff (or forgotten).
struct Supervised {
  RespawnPolicy policy;
  pid_t pid = -1;
  int restarts = 0;
  int consecutive = 0;  ///< respawns in a row without 10 s of uptime in between
  SteadyTime started{};
  SteadyTime due = SteadyTime::max();  ///< respawn time while dead

  /// Records the death at `now`; returns the backoff in seconds, or a negative value if it is not respawned.
  double died(SteadyTime now) {
    pid = -1;
    if (!policy.respawn) return -1.0;
    consecutive = now - started >= std::chrono::seconds(10) ? 1 : consecutive + 1;
    ++restarts;
    const double d = policy.delay_for(consecutive);
    due = now + std::chrono::microseconds(static_cast<int64_t>(d * 1e6));
    return d;
  }
};

using LoadClient = Client<composition_interfaces::srv::LoadNode_Request, composition_interfaces::srv::LoadNode_Response>;

/// A supervised container. Loading its components is a state advanced by the supervision loop (never waited
/// for), so that a slow (re)load holds up neither the other children's supervision nor a stop.
struct RunningContainer : Supervised {
  std::string name;
  std::size_t threads = 1;
  std::vector<const LaunchComponent*> components;
  std::shared_ptr<LoadClient> client;  ///< of the container's load_node service (any of its processes)
  std::size_t loaded = 0;              ///< components loaded into the current process
  std::optional<LoadClient::Pending> call;  ///< the load request in flight
  bool serving() const { return pid > 0 && loaded == components.size(); }
};

struct RunningProcess : Supervised {
  const LaunchProcess* spec = nullptr;
};

composition_interfaces::srv::LoadNode_Request load_request(const LaunchComponent& c) {
  composition_interfaces::srv::LoadNode_Request r;
  r.plugin_name = c.class_name;
  r.node_name = c.name;
  r.node_namespace = c.ns;
  for (const auto& [k, v] : c.params) {
    rcl_interfaces::msg::Parameter p;
    p.name = k;
    p.value = to_parameter_msg(v);
    r.parameters.push_back(p);
  }
  for (const auto& [from, to] : c.remaps) r.remap_rules.push_back(resolve_in(c.ns, from) + ":=" + to);
  rcl_interfaces::msg::Parameter ipc;
  ipc.name = "use_intra_process_comms";
  ipc.value = to_parameter_msg(c.use_intra_process);
  r.extra_arguments.push_back(ipc);
  rcl_interfaces::msg::Parameter validated;  // validate_launch_spec constructed every component in a dry run
  validated.name = "parameters_validated";
  validated.value = to_parameter_msg(true);
  r.extra_arguments.push_back(validated);
  return r;
}

}  // namespace

int run_launch_main(int argc, char** argv) {
  std::string path;
  double duration = 0;
  bool check_only = false;
  for (int i = 0; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--duration") {
      if (i + 1 >= argc) {
        std::cerr << "cairn: launch: missing value after --duration\n";
        return 2;
      }
      try {
        duration = option_number("--duration", argv[++i], 0, 1e9);  // 0: until SIGINT/SIGTERM
      } catch (const OptionError& e) {
        std::cerr << "cairn: launch: " << e.what() << "\n";
        return 2;
      }
    } else if (a == "--check") {
      check_only = true;
    } else if (a == "-h" || a == "--help") {
      std::cout << "usage: cairn launch <spec.yaml> [--duration SECONDS] [--check]\n"
                   "  validates the whole spec (classes, parameters, topic types, QoS) before starting anything;\n"
                   "  --check stops after validation, --duration stops the launch after SECONDS (at most 1e9;\n"
                   "  0, the default, runs until SIGINT/SIGTERM).\n";
      return 0;
    } else if (path.empty() && a[0] != '-') {
      path = a;
    } else {
      std::cerr << "cairn: launch: unknown argument '" << a << "'\n";
      return 2;
    }
  }
  if (path.empty()) {
    std::cerr << "cairn: launch: missing spec file (cairn launch <spec.yaml>)\n";
    return 2;
  }
  LaunchSpec spec;
  ComponentLoader loader;
  try {
    spec = parse_launch_spec(path);
    validate_launch_spec(spec, loader);
  } catch (const LaunchError& e) {
    std::cerr << "cairn: " << e.what() << "\n";
    return 2;
  }
  std::size_t ncomp = 0;
  for (const auto& c : spec.containers) ncomp += c.components.size();
  if (check_only) {
    std::cout << path << ": ok (" << spec.containers.size() << " containers, " << ncomp << " components, "
              << spec.processes.size() << " processes)\n";
    return 0;
  }
  Executor::install_signal_handlers();
  if (spec.domain_id) setenv("CAIRN_DOMAIN_ID", std::to_string(*spec.domain_id).c_str(), 1);
  const Logger log("launch");
  const std::string self = self_executable();

  std::vector<RunningContainer> containers;
  auto running = [](const LaunchContainer& c, std::string name, std::size_t threads) {
    RunningContainer rc;
    rc.policy = c.respawn;
    rc.name = std::move(name);
    rc.threads = threads;
    return rc;
  };
  for (const auto& c : spec.containers) {
    RunningContainer rc = running(c, c.name, c.threads);
    for (const auto& comp : c.components) {
      if (comp.isolated) {
        containers.push_back(running(c, c.name + "__" + comp.name, 1));
        containers.back().components.push_back(&comp);
      } else {
        rc.components.push_back(&comp);
      }
    }
    containers.push_back(std::move(rc));
  }

  auto ctx = Context::default_context();
  Executor exec;
  NodeOptions no("launch_" + std::to_string(getpid()), &exec);
  no.start_parameter_services = false;
  Node node(no);
  const auto load_timeout = std::chrono::milliseconds(static_cast<int64_t>(spec.load_timeout_s * 1000));

  // Re-sent every 100 ms until answered (the container answers a re-sent request once). After a respawn the killed
  // container's endpoints stay matched until their DDS lease expires, so its load_node service looks ready at once
  // and the first request can go to the dead process only; with a 1 s re-send a respawned container served again
  // ~1.1 s after the crash, with 100 ms ~0.22 s (`cairn bench ipc --only respawn`).
  constexpr auto kLoadResend = std::chrono::milliseconds(100);
  constexpr auto kServiceWait = std::chrono::seconds(20);
  auto spawn = [&](RunningContainer& rc) {
    rc.started = std::chrono::steady_clock::now();
    rc.due = SteadyTime::max();
    rc.loaded = 0;
    rc.call.reset();
    if (!rc.client) {  // one per container, kept across respawns (the node keeps its clients for its lifetime)
      rc.client = node.create_client<composition_interfaces::srv::LoadNode_Request,
                                     composition_interfaces::srv::LoadNode_Response>("/" + rc.name + "/_container/load_node");
    }
    rc.pid = spawn_process({self, "container", "--name", rc.name, "--threads", std::to_string(rc.threads),
                            "--load-timeout", std::to_string(spec.load_timeout_s)});
  };
  // Advances a started container's loading without blocking: returns an error ("file:line: ...") when it cannot
  // be loaded, else "" (still loading, or serving).
  auto advance = [&](RunningContainer& rc) -> std::string {
    while (rc.pid > 0 && !rc.serving()) {
      const auto now = std::chrono::steady_clock::now();
      const LaunchComponent& comp = *rc.components[rc.loaded];
      if (!rc.call) {
        if (!rc.client->service_is_ready()) {
          if (now < rc.started + kServiceWait) return "";  // the process must offer load_node by then
          return spec.file + ": container " + rc.name + " did not offer its load_node service within " +
                 std::to_string(kServiceWait.count()) + " s";
        }
        rc.call = rc.client->send(load_request(comp), load_timeout + std::chrono::seconds(5), kLoadResend);
      }
      auto resp = rc.client->poll(*rc.call, now);
      if (!resp && !rc.call->expired) return "";
      rc.call.reset();
      if (!resp) {
        return spec.file + ":" + std::to_string(comp.line) + ": " + comp.fqn() + ": no reply from container " +
               rc.name + " to the load request";
      }
      if (!resp->success) return spec.file + ":" + std::to_string(comp.line) + ": " + resp->error_message;
      CAIRN_INFO(log, "loaded " << comp.class_name << " as " << resp->full_node_name << " into " << rc.name);
      ++rc.loaded;
    }
    return "";
  };

  std::vector<RunningProcess> procs;
  auto all_pids = [&] {
    std::vector<pid_t> p;
    for (auto& c : containers) p.push_back(c.pid);
    for (auto& rp : procs) p.push_back(rp.pid);
    return p;
  };
  auto start_process = [&](RunningProcess& rp) {
    rp.started = std::chrono::steady_clock::now();
    rp.due = SteadyTime::max();
    rp.pid = spawn_process(rp.spec->cmd);
  };
  // Start-up: every container is started at once and loaded; the processes start when all containers serve. Until
  // then a container that cannot be started or loaded, or dies without respawn, ends the launch (exit 1, one line).
  auto fail_startup = [&](const std::string& what) {
    std::cerr << "cairn: " << what << "\n";
    stop_processes(all_pids());
    return 1;
  };
  for (auto& rc : containers) {
    try {
      spawn(rc);
    } catch (const std::exception& e) {
      return fail_startup(spec.file + ": container " + rc.name + ": " + e.what());
    }
  }
  bool started_up = false;
  auto t_end = std::chrono::steady_clock::time_point::max();
  // What ended without being respawned: a container (they run until stopped) or a process that failed. Any of
  // them makes the launch exit 1, so that a script running a spec (scripts/demo.sh) sees it.
  std::vector<std::string> failures;
  while (!Executor::signal_received() && std::chrono::steady_clock::now() < t_end) {
    const auto now = std::chrono::steady_clock::now();
    // Respawns whose backoff has passed, and loading (a step at a time: nothing here waits).
    bool loading = false, all_serving = true;
    for (auto& rc : containers) {
      if (rc.pid <= 0 && rc.due <= now) {
        CAIRN_WARN(log, "respawning container " << rc.name << " (restart " << rc.restarts << ")");
        try {
          spawn(rc);
        } catch (const std::exception& e) {
          if (!started_up) return fail_startup(spec.file + ": container " + rc.name + ": " + e.what());
          const double d = rc.died(std::chrono::steady_clock::now());  // not even started: try again after the backoff
          CAIRN_ERROR(log, "respawn of " << rc.name << " failed: " << e.what() << "; trying again in " << d << " s");
          continue;
        }
      }
      const std::string error = advance(rc);
      if (!error.empty() && !started_up) return fail_startup(error);
      if (!error.empty()) {
        // Running but without its components: stop it and try again after the next backoff.
        stop_processes({rc.pid});
        const double d = rc.died(std::chrono::steady_clock::now());
        CAIRN_ERROR(log, error << "; container " << rc.name << " stopped, trying again in " << d << " s");
      }
      loading = loading || (rc.pid > 0 && !rc.serving());
      all_serving = all_serving && rc.serving();
    }
    if (!started_up && all_serving) {
      started_up = true;
      for (const auto& p : spec.processes) {
        try {
          RunningProcess rp;
          rp.spec = &p;
          rp.policy = p.respawn;
          procs.push_back(rp);
          start_process(procs.back());
        } catch (const std::exception& e) {
          return fail_startup(spec.file + ":" + std::to_string(p.line) + ": process " + p.name + ": " + e.what());
        }
      }
      CAIRN_INFO(log, "running " << containers.size() << " containers, " << ncomp << " components, " << procs.size()
                                 << " processes" << (duration > 0 ? " for " + std::to_string(duration) + " s" : ""));
      if (duration > 0) t_end = std::chrono::steady_clock::now() + std::chrono::milliseconds(int64_t(duration * 1000));
    }
    for (auto& rp : procs) {
      if (rp.pid > 0 || rp.due > now) continue;
      CAIRN_WARN(log, "respawning process " << rp.spec->name << " (restart " << rp.restarts << ")");
      try {
        start_process(rp);
      } catch (const std::exception& e) {
        CAIRN_ERROR(log, "respawn of process " << rp.spec->name << " failed: " << e.what());
        rp.died(std::chrono::steady_clock::now());  // try again after the next backoff
      }
    }
    int status = 0;
    const pid_t pid = waitpid(-1, &status, WNOHANG);
    if (pid <= 0) {
      std::this_thread::sleep_for(std::chrono::milliseconds(loading ? 2 : 50));
      continue;
    }
    auto backoff = [](double d) {
      std::ostringstream o;
      o << d;
      return o.str();
    };
    for (auto& rc : containers) {
      if (rc.pid != pid) continue;
      rc.call.reset();
      const double d = rc.died(std::chrono::steady_clock::now());
      if (d < 0 && !started_up) {
        return fail_startup(spec.file + ": container " + rc.name + " " + describe_wait_status(status) +
                            " during start-up; respawn is off");
      } else if (d < 0) {
        CAIRN_ERROR(log, "container " << rc.name << " " << describe_wait_status(status) << "; respawn is off");
        failures.push_back("container " + rc.name + " " + describe_wait_status(status));
      } else {
        CAIRN_ERROR(log, "container " << rc.name << " " << describe_wait_status(status) << "; respawning (restart "
                                      << rc.restarts << ") in " << backoff(d) << " s");
      }
    }
    for (auto& rp : procs) {
      if (rp.pid != pid) continue;
      const double d = rp.died(std::chrono::steady_clock::now());
      const bool clean = WIFEXITED(status) && WEXITSTATUS(status) == 0;
      if (d < 0 && clean) {
        CAIRN_INFO(log, "process " << rp.spec->name << " " << describe_wait_status(status));
      } else if (d < 0) {
        CAIRN_ERROR(log, "process " << rp.spec->name << " " << describe_wait_status(status));
        failures.push_back("process " + rp.spec->name + " " + describe_wait_status(status));
      } else {
        CAIRN_WARN(log, "process " << rp.spec->name << " " << describe_wait_status(status) << "; respawning in "
                                   << backoff(d) << " s");
      }
    }
  }
  CAIRN_INFO(log, "stopping");
  stop_processes(all_pids());
  if (failures.empty()) return 0;
  std::string what;
  for (const auto& f : failures) what += (what.empty() ? "" : "; ") + f;
  std::cerr << "cairn: launch: " << spec.file << ": " << failures.size() << " failed: " << what << "\n";
  return 1;
}

}  // namespace cairn
