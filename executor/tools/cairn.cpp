// `cairn` — the command line of the runtime. Runtime verbs are built in; `cairn <verb> …` for any other
// verb runs `cairn-<verb> …` (next to this executable, else on PATH), which is how component tools such as
// `cairn slam optimize` plug in.
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <map>
#include <set>
#include <sstream>
#include <thread>

#include "cairn/component.hpp"
#include "cairn/container.hpp"
#include "cairn/dds.hpp"
#include "cairn/graph.hpp"
#include "cairn/launch.hpp"
#include "cairn/node.hpp"
#include "cairn/parameter_msgs.hpp"
#include "cairn/process.hpp"
#include "composition_interfaces/srv/ListNodes.hpp"
#include "composition_interfaces/srv/LoadNode.hpp"
#include "composition_interfaces/srv/UnloadNode.hpp"
#include "rcl_interfaces/srv/GetParameters.hpp"
#include "rcl_interfaces/srv/ListParameters.hpp"
#include "rcl_interfaces/srv/SetParameters.hpp"

namespace fs = std::filesystem;
using namespace std::chrono_literals;

namespace {

constexpr const char* kHelp = R"(usage: cairn <command> [args]

Runtime (graph discovered through DDS built-in topics; non-cairn DDS participants are seen too):
  topic list                           topics and their types, one per line
  topic echo <topic> [--once] [--count N] [--full-length]
                                       print messages as YAML-like text (lists of numbers or strings
                                       are cut after 256 elements; --full-length prints them whole)
  topic hz <topic> [--duration S]      message rate (printed every second)
  topic info <topic>                   type, publishers and subscriptions with node and QoS
                                       (topic verbs also take --wait S; each refuses the others' options)
  node list                            nodes (and non-cairn DDS participants)
  component list [container]           components loaded in containers
  component types                      component classes that can be loaded
  component load <container> <class> [--name N] [--namespace NS] [-p name:=value]... [-r from:=to]...
  component unload <container> <id>
  param get <node> <name> [--timeout S]
  param set <node> <name> <value>      value as YAML (3, 2.5, true, text, [1, 2]); quote a value with spaces
  param dump <node>                    all parameters as YAML
  launch <spec.yaml> [--duration S] [--check]
                                       validate the whole spec, then start and supervise it
  container --name N [--threads K] [--load-timeout S]
                                       a component container process (K in 1-64, S in 0.1-3600 s, as in launch specs)
  bench ipc [--quick] [--only CASE]    intra-process and DDS latency/throughput, executor dispatch CPU and idle
                                       wake-ups, component load time, crash-to-serving time, local latency with a
                                       remote subscriber, each vs a baseline (JSON lines; CASE: same_thread
                                       cross_thread dds_rtt dds_throughput dispatch idle component_load respawn mixed)

Component tools (run as cairn-<verb>):
  slam optimize <in.g2o> ...           pose-graph optimization (components/graph_slam)
  slam run --carmen <log> --out <dir>  offline 2D graph SLAM: poses.txt, graph.g2o, map.pgm/.yaml/.png, summary.json
  slam eval --poses <f> [--relations <f>] [--corrected <log> --carmen <log>]
                                       Kuemmerle et al. relations metric, corrected-log ATE (JSON with --json)
  slam params | train-verifier | eval-verifier
                                       SLAM parameter table; loop-closure verifier training / evaluation
  sim check | bench | run | people      world summary, simulator speed, a headless run to files, recorded people
                                       (components/sim; cairn sim --help)
  log info | play <file.clf|.bz2|.gz>  CARMEN log summary; playback -> scan, odom, /tf, /clock over DDS
                                       (components/sim; cairn log --help)
  people train | eval | gen-train | bench | mask-bench
                                       people detection and tracking (components/people_tracking; cairn people --help)
  copa train | eval | predict | render CoPA-Map people-activity model (components/copa_map; cairn copa --help)
  bt run | replay | watch | model | psbt-eval
                                       behavior trees (components/bt_executive; cairn bt --help)

Common options: --wait S (topic, node: discovery time, 0-3600 s, default 1.5 s; topic echo/hz: time to find a
publisher, component: time to find the container(s), default 5 s), --timeout S (param, component: time for the
service reply, 0-3600 s, default 5 s / 15 s). --count is 1-1e12 (default: until Ctrl-C); --duration 0-1e9 s
(0, the default: until Ctrl-C).
Environment: CAIRN_DOMAIN_ID / ROS_DOMAIN_ID, CYCLONEDDS_URI, CAIRN_COMPONENT_PATH, CAIRN_LOG_LEVEL.
)";

struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct Args {
  std::vector<std::string> pos;
  std::map<std::string, std::vector<std::string>> opt;
  std::set<std::string> flags;
  bool has(const std::string& f) const { return flags.count(f) > 0; }
  std::optional<std::string> get(const std::string& k) const {
    auto it = opt.find(k);
    if (it == opt.end() || it->second.empty()) return std::nullopt;
    return it->second.back();
  }
  /// Option `k` as a number in [lo, hi] (see cairn::option_number), or `def` when it is not given.
  double num(const std::string& k, double def, double lo, double hi, bool integer = false) const {
    auto v = get(k);
    return v ? cairn::option_number(k, *v, lo, hi, integer) : def;
  }
  /// Rejects positional arguments beyond the first `n` (a value with spaces must be quoted).
  void at_most(std::size_t n, const std::string& usage) const {
    if (pos.size() > n) throw UsageError("unexpected argument '" + pos[n] + "' (" + usage + ")");
  }
};

// Ranges of the options common to several commands (seconds).
constexpr double kMaxWait = 3600, kMaxDuration = 1e9;

Args parse_args(int argc, char** argv, int first, const std::set<std::string>& with_value,
                const std::set<std::string>& flags) {
  Args a;
  for (int i = first; i < argc; ++i) {
    std::string s = argv[i];
    if (with_value.count(s)) {
      if (i + 1 >= argc) throw UsageError("missing value after " + s);
      a.opt[s].push_back(argv[++i]);
    } else if (flags.count(s)) {
      a.flags.insert(s);
    } else if (s.size() > 1 && s[0] == '-' && !std::isdigit(static_cast<unsigned char>(s[1]))) {
      throw UsageError("unknown option '" + s + "'");
    } else {
      a.pos.push_back(s);
    }
  }
  return a;
}

std::string norm_topic(std::string t) { return t.empty() || t[0] == '/' ? t : "/" + t; }

std::chrono::milliseconds wait_of(const Args& a, double def = 1.5) {
  return std::chrono::milliseconds(int64_t(a.num("--wait", def, 0, kMaxWait) * 1000));
}

struct Cli {
  std::shared_ptr<cairn::Context> ctx = cairn::Context::default_context();
  cairn::Executor exec;
  std::unique_ptr<cairn::Node> node;
  Cli() {
    cairn::NodeOptions o("cairn_cli_" + std::to_string(getpid()), &exec);
    o.start_parameter_services = false;
    node = std::make_unique<cairn::Node>(o);
  }
};

std::vector<cairn::GraphEndpoint> discover(Cli& cli, std::chrono::milliseconds wait) {
  cairn::GraphView g(*cli.ctx);
  g.wait_for_discovery(300ms, wait);
  return g.endpoints();
}

// ---------------- topic ----------------
int topic_list(const Args& a) {
  a.at_most(0, "topic list");
  const auto wait = wait_of(a);
  Cli cli;
  std::set<std::pair<std::string, std::string>> rows;
  for (const auto& e : discover(cli, wait)) {
    // ROS-convention topics as /name; service topics (rq/, rr/) are not topics to the user; anything else
    // (topics of non-cairn DDS applications) by its DDS name and type
    if (e.dds_topic.rfind("rq/", 0) == 0 || e.dds_topic.rfind("rr/", 0) == 0) continue;
    rows.insert({cairn::ros_topic_name(e.dds_topic), cairn::ros_type_name(e.dds_type)});
  }
  for (const auto& [t, ty] : rows) std::cout << t << " " << ty << "\n";
  return 0;
}

/// Waits for a publisher of `topic`; returns its endpoint.
std::optional<cairn::GraphEndpoint> find_publisher(Cli& cli, const std::string& topic, std::chrono::milliseconds wait) {
  cairn::GraphView g(*cli.ctx);
  const auto deadline = std::chrono::steady_clock::now() + wait;
  do {
    for (const auto& e : g.endpoints()) {
      if (e.is_publisher && e.dds_topic == cairn::dds_topic_name(topic)) return e;
    }
    std::this_thread::sleep_for(20ms);
  } while (std::chrono::steady_clock::now() < deadline);
  return std::nullopt;
}

const cairn::msgs::TypeSupport& type_of_topic(Cli& cli, const std::string& topic, std::chrono::milliseconds wait,
                                              cairn::QoS* qos_out) {
  auto pub = find_publisher(cli, topic, wait);
  if (!pub) throw std::runtime_error("no publisher of " + topic + " found (is the topic name right? see cairn topic list)");
  const auto* ts = cairn::msgs::find_type_support(pub->dds_type);
  if (!ts) throw std::runtime_error(topic + " carries " + pub->dds_type + ", a type cairn does not know");
  if (qos_out) {
    cairn::QoS q;
    q.reliability = pub->qos.reliability;
    q.durability = pub->qos.durability;
    q.keep_last(100);
    *qos_out = q;
  }
  return *ts;
}

int topic_echo(const Args& a) {
  if (a.pos.empty()) throw UsageError("topic echo <topic>");
  a.at_most(1, "topic echo <topic>");
  const std::string topic = norm_topic(a.pos[0]);
  const long count = a.has("--once") ? 1 : static_cast<long>(a.num("--count", 0, 1, 1e12, true));  // 0: until Ctrl-C
  const auto wait = wait_of(a, 5.0);  // time to find a publisher; a bad --wait is an error before anything starts
  const bool full = a.has("--full-length");  // every element of long lists (ROS 2's echo --full-length)
  Cli cli;
  cairn::QoS qos;
  const auto& ts = type_of_topic(cli, topic, wait, &qos);
  std::atomic<long> printed{0};
  std::mutex mu;
  std::condition_variable cv;
  std::unique_ptr<cairn::DdsReader> reader;
  reader = std::make_unique<cairn::DdsReader>(*cli.ctx, cairn::dds_topic_name(topic), ts, qos,
                                              cairn::DdsEndpointOptions{cli.node->fully_qualified_name(), false},
                                              [&](cairn::DdsReader&) { cv.notify_all(); });
  cairn::Executor::install_signal_handlers();
  std::unique_ptr<void, void (*)(void*)> msg(ts.create(), ts.destroy);
  while (!cairn::Executor::signal_received() && (count == 0 || printed < count)) {
    cairn::MessageInfo info;
    if (reader->take(msg.get(), info)) {
      std::cout << cairn::msgs::to_text(ts, msg.get(), full ? 0 : cairn::msgs::kPrintMaxElements) << "---" << std::endl;
      ++printed;
      continue;
    }
    std::unique_lock l(mu);
    cv.wait_for(l, 100ms);
  }
  return 0;
}

int topic_hz(const Args& a) {
  if (a.pos.empty()) throw UsageError("topic hz <topic>");
  a.at_most(1, "topic hz <topic>");
  const std::string topic = norm_topic(a.pos[0]);
  const double duration = a.num("--duration", 0, 0, kMaxDuration);  // 0: until Ctrl-C
  const auto wait = wait_of(a, 5.0);
  Cli cli;
  cairn::QoS qos;
  const auto& ts = type_of_topic(cli, topic, wait, &qos);
  std::mutex mu;
  std::vector<double> stamps;
  auto reader = std::make_unique<cairn::DdsReader>(*cli.ctx, cairn::dds_topic_name(topic), ts, qos,
                                                   cairn::DdsEndpointOptions{cli.node->fully_qualified_name(), false},
                                                   nullptr);
  cairn::Executor::install_signal_handlers();
  std::unique_ptr<void, void (*)(void*)> msg(ts.create(), ts.destroy);
  const auto t0 = std::chrono::steady_clock::now();
  auto next_report = t0 + 1s;
  auto now_s = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); };
  while (!cairn::Executor::signal_received() && (duration <= 0 || now_s() < duration)) {
    cairn::MessageInfo info;
    while (reader->take(msg.get(), info)) stamps.push_back(now_s());
    if (std::chrono::steady_clock::now() >= next_report) {
      next_report += 1s;
      if (stamps.size() < 2) {
        std::cout << "no new messages" << std::endl;
        continue;
      }
      const std::size_t window = std::min<std::size_t>(stamps.size(), 10000);
      std::vector<double> d;
      for (std::size_t i = stamps.size() - window + 1; i < stamps.size(); ++i) d.push_back(stamps[i] - stamps[i - 1]);
      double mean = 0;
      for (double x : d) mean += x;
      mean /= d.size();
      double var = 0;
      for (double x : d) var += (x - mean) * (x - mean);
      std::cout << std::fixed << std::setprecision(3) << "average rate: " << 1.0 / mean << "\n\tmin: "
                << *std::min_element(d.begin(), d.end()) << "s max: " << *std::max_element(d.begin(), d.end())
                << "s std dev: " << std::setprecision(5) << std::sqrt(var / d.size()) << "s window: " << window
                << std::endl;
    }
    std::this_thread::sleep_for(2ms);
  }
  return 0;
}

int topic_info(const Args& a) {
  if (a.pos.empty()) throw UsageError("topic info <topic>");
  a.at_most(1, "topic info <topic>");
  const std::string topic = norm_topic(a.pos[0]);
  Cli cli;
  std::vector<cairn::GraphEndpoint> pubs, subs;
  for (auto& e : discover(cli, wait_of(a))) {
    if (e.dds_topic != cairn::dds_topic_name(topic)) continue;
    (e.is_publisher ? pubs : subs).push_back(e);
  }
  if (pubs.empty() && subs.empty()) throw std::runtime_error("unknown topic " + topic + " (no publishers or subscriptions)");
  std::set<std::string> types;
  for (auto* v : {&pubs, &subs})
    for (auto& e : *v) types.insert(cairn::ros_type_name(e.dds_type));
  std::cout << "Topic: " << topic << "\nType:";
  for (auto& t : types) std::cout << " " << t;
  if (types.size() > 1) std::cout << "   (WARNING: several types on one topic: they never match)";
  std::cout << "\n";
  for (auto* v : {&pubs, &subs}) {
    std::cout << (v == &pubs ? "Publisher count: " : "Subscription count: ") << v->size() << "\n";
    for (const auto& e : *v) {
      std::cout << "  node: " << (e.node.empty() ? "(non-cairn participant " + cairn::gid_to_string(e.participant) + ")" : e.node)
                << "\n    type: " << cairn::ros_type_name(e.dds_type) << "\n    qos: " << e.qos.to_string()
                << "\n    gid: " << cairn::gid_to_string(e.guid) << "\n";
    }
  }
  return 0;
}

// ---------------- node ----------------
int node_list(const Args& a) {
  a.at_most(0, "node list");
  const auto wait = wait_of(a);
  Cli cli;
  cairn::GraphView g(*cli.ctx);
  g.wait_for_discovery(300ms, wait);
  std::set<std::string> nodes;
  std::set<cairn::Gid> cairn_participants;
  for (const auto& e : g.endpoints()) {
    if (!e.node.empty()) {
      nodes.insert(e.node);
      cairn_participants.insert(e.participant);
    }
  }
  for (const auto& n : nodes) {
    if (n.rfind("/cairn_cli_", 0) == 0) continue;
    std::cout << n << "\n";
  }
  for (const auto& p : g.participants()) {
    if (!p.cairn && !cairn_participants.count(p.guid)) {
      std::cout << "(DDS participant " << cairn::gid_to_string(p.guid) << ", not a cairn process)\n";
    }
  }
  return 0;
}

// ---------------- component ----------------
using namespace composition_interfaces::srv;

std::string container_service(const std::string& container, const std::string& what) {
  return norm_topic(container) + "/_container/" + what;
}

/// A client of `container`'s service `what` once a server of it is discovered within `wait` (--wait, the
/// discovery time); "no container X found" otherwise, instead of waiting out the whole reply timeout for a
/// container that does not exist.
template <class Req, class Resp>
auto container_client(Cli& cli, const std::string& container, const std::string& what, std::chrono::milliseconds wait) {
  auto client = cli.node->create_client<Req, Resp>(container_service(container, what));
  if (!client->wait_for_service(wait)) {
    char secs[32];
    std::snprintf(secs, sizeof secs, "%g", wait.count() / 1000.0);
    throw std::runtime_error("no container " + norm_topic(container) + " found (its " + what +
                             " service was not discovered within " + secs +
                             " s; --wait S waits longer, `cairn component list` lists the running containers)");
  }
  return client;
}

int component_main(int argc, char** argv) {
  if (argc < 3) throw UsageError("component list|types|load|unload");
  const std::string sub = argv[2];
  if (sub == "types") {
    if (argc > 3) throw UsageError("unexpected argument '" + std::string(argv[3]) + "' (component types)");
    cairn::ComponentLoader loader;
    for (const auto& [cls, lib] : loader.available()) std::cout << cls << "  (" << lib << ")\n";
    return 0;
  }
  const Args a = parse_args(argc, argv, 3, {"--name", "--namespace", "-p", "-r", "--timeout", "--wait"}, {});
  const auto timeout = std::chrono::milliseconds(int64_t(a.num("--timeout", 15, 0, kMaxWait) * 1000));
  const auto wait = wait_of(a, 5.0);  // time to find the container(s)
  if (sub == "list") a.at_most(1, "component list [container]");
  if (sub == "load") a.at_most(2, "component load <container> <class> [options]");
  if (sub == "unload") a.at_most(2, "component unload <container> <id>");
  Cli cli;
  if (sub == "list") {
    std::vector<std::string> containers;
    if (!a.pos.empty()) {
      containers.push_back(norm_topic(a.pos[0]));
    } else {
      std::set<std::string> found;
      for (const auto& e : discover(cli, wait)) {
        const std::string suffix = "/_container/list_nodesRequest";
        if (!e.is_publisher && e.dds_topic.rfind("rq/", 0) == 0 && e.dds_topic.size() > suffix.size() &&
            e.dds_topic.compare(e.dds_topic.size() - suffix.size(), suffix.size(), suffix) == 0) {
          found.insert(e.dds_topic.substr(2, e.dds_topic.size() - suffix.size() - 2));
        }
      }
      containers.assign(found.begin(), found.end());
    }
    for (const auto& c : containers) {
      auto client = container_client<ListNodes_Request, ListNodes_Response>(cli, c, "list_nodes", wait);
      auto resp = client->call(ListNodes_Request{}, timeout);
      if (!resp) throw std::runtime_error("container " + c + " did not answer list_nodes");
      std::cout << c << "\n";
      for (std::size_t i = 0; i < resp->unique_ids.size(); ++i) {
        std::cout << "  " << resp->unique_ids[i] << "  " << resp->full_node_names[i] << "\n";
      }
    }
    return 0;
  }
  if (sub == "load") {
    if (a.pos.size() < 2) throw UsageError("component load <container> <class> [--name N] [-p k:=v] [-r a:=b]");
    LoadNode_Request req;
    req.plugin_name = a.pos[1];
    req.node_name = a.get("--name").value_or("");
    try {
      req.node_namespace = cairn::normalize_namespace(a.get("--namespace").value_or("/"));  // "robot" = "/robot"
    } catch (const cairn::NodeError& e) {
      throw UsageError(std::string("--namespace: ") + e.what());
    }
    if (auto it = a.opt.find("-p"); it != a.opt.end()) {
      for (const auto& kv : it->second) {
        const auto p = kv.find(":=");
        if (p == std::string::npos) throw UsageError("-p expects name:=value, got '" + kv + "'");
        rcl_interfaces::msg::Parameter par;
        par.name = kv.substr(0, p);
        par.value = cairn::to_parameter_msg(cairn::parse_parameter_text(kv.substr(p + 2)));
        req.parameters.push_back(par);
      }
    }
    if (auto it = a.opt.find("-r"); it != a.opt.end()) {
      for (const auto& kv : it->second) {
        if (kv.find(":=") == std::string::npos) throw UsageError("-r expects from:=to, got '" + kv + "'");
        std::string from = kv.substr(0, kv.find(":="));
        std::string ns = req.node_namespace == "/" ? "" : req.node_namespace;
        if (!from.empty() && from[0] != '/') from = ns + "/" + from;
        req.remap_rules.push_back(from + kv.substr(kv.find(":=")));
      }
    }
    auto client = container_client<LoadNode_Request, LoadNode_Response>(cli, a.pos[0], "load_node", wait);
    auto resp = client->call(req, timeout);
    if (!resp) throw std::runtime_error("container " + norm_topic(a.pos[0]) + " did not answer load_node (is it running?)");
    if (!resp->success) throw std::runtime_error(resp->error_message);
    std::cout << "Loaded component " << resp->unique_id << " into '" << norm_topic(a.pos[0]) << "' container node as '"
              << resp->full_node_name << "'\n";
    return 0;
  }
  if (sub == "unload") {
    if (a.pos.size() < 2) throw UsageError("component unload <container> <id>");
    UnloadNode_Request req;
    req.unique_id = static_cast<uint64_t>(cairn::option_number("id", a.pos[1], 0, 9e15, true));
    auto client = container_client<UnloadNode_Request, UnloadNode_Response>(cli, a.pos[0], "unload_node", wait);
    auto resp = client->call(req, timeout);
    if (!resp) throw std::runtime_error("container " + norm_topic(a.pos[0]) + " did not answer unload_node");
    if (!resp->success) throw std::runtime_error(resp->error_message);
    std::cout << "Unloaded component " << req.unique_id << " from '" << norm_topic(a.pos[0]) << "' container node\n";
    return 0;
  }
  throw UsageError("unknown component command '" + sub + "'");
}

// ---------------- param ----------------
int param_main(int argc, char** argv) {
  if (argc < 4) throw UsageError("param get|set|dump <node> ...");
  const std::string sub = argv[2];
  const Args a = parse_args(argc, argv, 4, {"--timeout", "--wait"}, {});
  if (a.get("--wait")) throw UsageError("param has no discovery step: --timeout S bounds the wait for the reply");
  const std::string node = norm_topic(argv[3]);
  const auto timeout = std::chrono::milliseconds(int64_t(a.num("--timeout", 5, 0, kMaxWait) * 1000));
  if (sub == "get") a.at_most(1, "param get <node> <name>");
  if (sub == "set") a.at_most(2, "param set <node> <name> <value>; quote a value with spaces");
  if (sub == "dump") a.at_most(0, "param dump <node>");
  Cli cli;
  using namespace rcl_interfaces::srv;
  auto get = [&](const std::vector<std::string>& names) {
    auto c = cli.node->create_client<GetParameters_Request, GetParameters_Response>(node + "/get_parameters");
    GetParameters_Request req;
    req.names = names;
    auto resp = c->call(req, timeout);
    if (!resp) throw std::runtime_error("node " + node + " not found (no answer from " + node + "/get_parameters)");
    return *resp;
  };
  if (sub == "get") {
    if (a.pos.empty()) throw UsageError("param get <node> <name>");
    auto resp = get({a.pos[0]});
    const auto v = cairn::from_parameter_msg(resp.values.at(0));
    if (std::holds_alternative<std::monostate>(v)) throw std::runtime_error("node " + node + " has no parameter '" + a.pos[0] + "'");
    std::cout << cairn::to_string(v) << "\n";
    return 0;
  }
  if (sub == "set") {
    if (a.pos.size() < 2) throw UsageError("param set <node> <name> <value>");
    auto c = cli.node->create_client<SetParameters_Request, SetParameters_Response>(node + "/set_parameters");
    SetParameters_Request req;
    rcl_interfaces::msg::Parameter p;
    p.name = a.pos[0];
    p.value = cairn::to_parameter_msg(cairn::parse_parameter_text(a.pos[1]));
    req.parameters.push_back(p);
    auto resp = c->call(req, timeout);
    if (!resp) throw std::runtime_error("node " + node + " not found (no answer from " + node + "/set_parameters)");
    if (!resp->results.at(0).successful) throw std::runtime_error(resp->results[0].reason);
    std::cout << "Set parameter successful\n";
    return 0;
  }
  if (sub == "dump") {
    auto lc = cli.node->create_client<ListParameters_Request, ListParameters_Response>(node + "/list_parameters");
    auto names = lc->call(ListParameters_Request{}, timeout);
    if (!names) throw std::runtime_error("node " + node + " not found (no answer from " + node + "/list_parameters)");
    auto resp = get(names->names);
    std::cout << node << ":\n  ros__parameters:\n";
    for (std::size_t i = 0; i < names->names.size(); ++i) {
      std::cout << "    " << names->names[i] << ": " << cairn::to_string(cairn::from_parameter_msg(resp.values.at(i))) << "\n";
    }
    return 0;
  }
  throw UsageError("unknown param command '" + sub + "'");
}

// ---------------- external tools ----------------
int exec_tool(const std::string& verb, int argc, char** argv) {
  const std::string tool = "cairn-" + verb;
  std::vector<std::string> candidates;
  const fs::path self = cairn::self_executable();
  candidates.push_back((self.parent_path() / tool).string());
  std::vector<char*> args;
  args.push_back(const_cast<char*>(tool.c_str()));
  for (int i = 2; i < argc; ++i) args.push_back(argv[i]);
  args.push_back(nullptr);
  for (const auto& c : candidates) {
    if (access(c.c_str(), X_OK) == 0) {
      execv(c.c_str(), args.data());
    }
  }
  execvp(tool.c_str(), args.data());
  std::cerr << "cairn: unknown command '" << verb << "' (no built-in verb and no " << tool
            << " next to cairn or on PATH; see cairn --help)\n";
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || std::string(argv[1]) == "-h" || std::string(argv[1]) == "--help" || std::string(argv[1]) == "help") {
    std::cout << kHelp;
    return argc < 2 ? 2 : 0;
  }
  const std::string verb = argv[1];
  const bool builtin = verb == "topic" || verb == "node" || verb == "component" || verb == "param";
  for (int i = 2; builtin && i < argc; ++i) {
    if (std::string(argv[i]) == "-h" || std::string(argv[i]) == "--help") {
      std::cout << kHelp;
      return 0;
    }
  }
  try {
    if (verb == "topic") {
      if (argc < 3) throw UsageError("topic list|echo|hz|info");
      const std::string sub = argv[2];
      // Each subcommand its own options: one shared set let `echo --duration 5` run forever.
      auto args = [&](const std::set<std::string>& with_value, const std::set<std::string>& flags) {
        return parse_args(argc, argv, 3, with_value, flags);
      };
      if (sub == "list") return topic_list(args({"--wait"}, {}));
      if (sub == "echo") return topic_echo(args({"--count", "--wait"}, {"--once", "--full-length"}));
      if (sub == "hz") return topic_hz(args({"--duration", "--wait"}, {}));
      if (sub == "info") return topic_info(args({"--wait"}, {}));
      throw UsageError("unknown topic command '" + sub + "'");
    }
    if (verb == "node") {
      if (argc < 3 || std::string(argv[2]) != "list") throw UsageError("node list");
      return node_list(parse_args(argc, argv, 3, {"--wait"}, {}));
    }
    if (verb == "component") return component_main(argc, argv);
    if (verb == "param") return param_main(argc, argv);
    if (verb == "launch") return cairn::run_launch_main(argc - 2, argv + 2);
    if (verb == "container") return cairn::run_container_main(argc - 2, argv + 2);
  } catch (const UsageError& e) {
    std::cerr << "cairn: " << verb << ": " << e.what() << " (see cairn --help)\n";
    return 2;
  } catch (const cairn::OptionError& e) {
    std::cerr << "cairn: " << verb << ": " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "cairn: " << verb << ": " << e.what() << "\n";
    return 1;
  }
  return exec_tool(verb, argc, argv);
}
