// cairn_bt::ExecutiveNode — the runtime adapter of the behavior-tree core (issue 8, "Executive component"): loads a
// BehaviorTree.CPP v4 tree from a parameter, ticks it at a rate and on events, publishes its status (latched) and
// transitions, serves start/stop/switch/load commands, and registers runtime-backed action nodes.
//
// Threads: none of its own. The tree's Scheduler (README "Async actions and the runtime adapter") lives on the
// node's executor: now() is the node clock (sim time with use_sim_time), wakeUpAt() a one-shot timer on that
// clock, requestTick() an Executor::post. Every callback of this node — periodic tick, posted tick, wake-up and
// timeout timers, the subscriptions of WaitForMessage, the command service — runs in the node's default
// (mutually exclusive) callback group, so the tree is only ever touched by one thread at a time. Runtime actions
// are EventActionNodes completed by executor events (message arrival, timer), never by a thread per action.
#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <future>
#include <map>
#include <memory>
#include <mutex>
#include <sstream>
#include <string>
#include <vector>

#include "cairn/bt_executive/executive.hpp"
#include "cairn/bt_executive/factory.hpp"
#include "cairn/bt_executive/monitoring.hpp"
#include "cairn/bt_executive/xml_loader.hpp"
#include "cairn/component.hpp"
#include "cairn/container.hpp"
#include "cairn/dds.hpp"
#include "cairn/data_files.hpp"
#include "cairn/msgs/type_support.hpp"
#include "cairn/strict_number.hpp"
#include "cairn_bt_msgs/msg/TreeEvent.hpp"
#include "cairn_bt_msgs/msg/TreeStatus.hpp"
#include "cairn_bt_msgs/srv/ExecutiveCommand.hpp"
#include "cairn_copa_msgs/srv/Retrain.hpp"
#include "cairn_people_msgs/srv/Follow.hpp"
#include "cairn_sim_msgs/srv/NavigateTo.hpp"
#include "cairn_slam_msgs/srv/LoadState.hpp"
#include "cairn_slam_msgs/srv/Optimize.hpp"
#include "cairn_slam_msgs/srv/SaveState.hpp"
#include "cairn/parameter_msgs.hpp"
#include "composition_interfaces/srv/ListNodes.hpp"
#include "composition_interfaces/srv/LoadNode.hpp"
#include "composition_interfaces/srv/UnloadNode.hpp"
#include "rcl_interfaces/srv/GetParameters.hpp"
#include "geometry_msgs/msg/PoseStamped.hpp"
#include "geometry_msgs/msg/Twist.hpp"
#include "nav_msgs/msg/Odometry.hpp"
#include "std_msgs/msg/Header.hpp"
#include "std_msgs/msg/String.hpp"

namespace cairn_bt {

namespace bt = cairn::bt;
namespace bmsg = cairn_bt_msgs::msg;
namespace bsrv = cairn_bt_msgs::srv;

namespace {

builtin_interfaces::msg::Time toStamp(std::int64_t ns) {
  builtin_interfaces::msg::Time t;
  std::int64_t sec = ns / 1000000000;
  std::int64_t rem = ns % 1000000000;
  if (rem < 0) {
    rem += 1000000000;
    --sec;
  }
  t.sec = static_cast<int32_t>(sec);
  t.nanosec = static_cast<uint32_t>(rem);
  return t;
}

// Closes over every callback of the node: after close() returns, no guarded callback runs or will run, so the
// node's members can be destroyed while the base cairn::Node still has live subscriptions and timers.
class Gate {
 public:
  template <class F>
  void run(F&& f) {
    std::lock_guard l(mu_);
    if (open_) f();
  }
  /// Holds the gate (callbacks wait) for the lifetime of the returned lock.
  std::unique_lock<std::recursive_mutex> hold() { return std::unique_lock(mu_); }
  void close() {
    std::lock_guard l(mu_);
    open_ = false;
  }

 private:
  std::recursive_mutex mu_;
  bool open_ = true;
};

// Tree file: absolute, or relative to the working directory, then to the package's shipped trees/ (installed
// share/cairn_bt_executive/trees under $CMAKE_PREFIX_PATH / $COLCON_PREFIX_PATH, then the source tree).
std::string resolveTreeFile(const std::string& name) {
  namespace fs = std::filesystem;
  const fs::path p(name);
  std::vector<fs::path> candidates;
  if (p.is_absolute()) {
    candidates.push_back(p);
  } else {
    candidates.push_back(fs::current_path() / p);
    for (const auto& dir : cairn::prefix_paths("share/cairn_bt_executive/trees")) candidates.push_back(dir / p);
#ifdef CAIRN_BT_TREES_DIR
    candidates.push_back(fs::path(CAIRN_BT_TREES_DIR) / p);
#endif
  }
  return cairn::first_existing_file(candidates, "tree_file '" + name + "'");
}

}  // namespace

// ------------------------------------------------------------------------------------------------ runtime hub
/// What the runtime action nodes use: the tree's scheduler on the node's executor, publishers and shared
/// subscriptions (one per topic, fanned out to the WaitForMessage nodes waiting on it).
class RuntimeHub final : public bt::Scheduler {
 public:
  /// Receives the text of a message (std_msgs/String: its data; other types: the `cairn topic echo` text).
  using Listener = std::function<void(const std::string&)>;

  RuntimeHub(cairn::Node& node, std::shared_ptr<Gate> gate, std::function<void()> on_tick)
      : node_(node), gate_(std::move(gate)), on_tick_(std::move(on_tick)) {}

  ~RuntimeHub() override { shutdown(); }

  /// Removes every pending timer (the gate must be closed already, so none of their callbacks runs).
  void shutdown() {
    std::map<TimerId, std::shared_ptr<cairn::TimerBase>> timers;
    {
      std::lock_guard l(mu_);
      timers.swap(timers_);
    }
    for (auto& [id, t] : timers) {
      t->cancel();
      if (node_.executor()) node_.executor()->remove_timer(t.get());
    }
  }

  // ---- bt::Scheduler
  bt::TimePoint now() const override { return bt::TimePoint{node_.now().ns}; }
  TimerId wakeUpAt(bt::TimePoint t) override {
    return callAt(t, [this] { on_tick_(); });
  }
  void cancelTimer(TimerId id) override {
    std::shared_ptr<cairn::TimerBase> t;
    {
      std::lock_guard l(mu_);
      auto it = timers_.find(id);
      if (it == timers_.end()) return;
      t = std::move(it->second);
      timers_.erase(it);
    }
    t->cancel();
    node_.executor()->remove_timer(t.get());
  }
  void requestTick() override {
    if (node_.dry_run() || node_.executor() == nullptr) return;  // launch validation: nothing ticks
    if (tick_posted_.exchange(true)) return;  // one posted tick serves every request made before it runs
    node_.executor()->post(
        [this, gate = gate_] {
          gate->run([this] {
            tick_posted_.store(false);
            on_tick_();
          });
        },
        node_.default_callback_group());
  }

  /// Runs `fn` in the node's callback group once the node clock reaches `t` (a one-shot timer on the node
  /// clock; removed from the executor when it fires or is cancelled). 0 in a dry run.
  TimerId callAt(bt::TimePoint t, std::function<void()> fn) {
    cairn::Executor* exec = node_.executor();
    if (node_.dry_run() || exec == nullptr) return 0;
    const auto delay = std::max(bt::Duration{0}, t - now());
    TimerId id = 0;
    {
      std::lock_guard l(mu_);
      id = next_id_++;
    }
    auto timer = std::make_shared<cairn::TimerBase>(
        node_.default_callback_group(), node_.clock(), delay, [this, id, fn = std::move(fn), gate = gate_] {
          gate->run([&] {
            std::shared_ptr<cairn::TimerBase> self;
            {
              std::lock_guard l(mu_);
              auto it = timers_.find(id);
              if (it == timers_.end()) return;  // cancelled after it came due
              self = std::move(it->second);
              timers_.erase(it);
            }
            node_.executor()->remove_timer(self.get());
            fn();
          });
        });
    timer->set_one_shot(true);
    {
      std::lock_guard l(mu_);
      timers_[id] = timer;
    }
    exec->add_timer(timer);
    return id;
  }
  std::size_t pendingTimers() const {
    std::lock_guard l(mu_);
    return timers_.size();
  }

  // ---- topics
  std::shared_ptr<cairn::Publisher<std_msgs::msg::String>> stringPublisher(const std::string& topic) {
    auto& p = string_pubs_[node_.resolve_name(topic)];
    if (!p) p = node_.create_publisher<std_msgs::msg::String>(topic, cairn::QoS{});
    return p;
  }

  /// One client per (service, type), shared by every node calling it; created at load for literal names so that
  /// discovery starts early. Null in a dry run.
  template <class Req, class Resp>
  std::shared_ptr<cairn::Client<Req, Resp>> client(const std::string& service) {
    const std::string key = node_.resolve_name(service) + " " + cairn::msgs::type_support<Req>().ros_type_name;
    auto& c = clients_[key];
    if (!c) c = node_.create_client<Req, Resp>(service);
    return std::static_pointer_cast<cairn::Client<Req, Resp>>(c);
  }

  static const std::vector<std::string>& messageTypes() {
    static const std::vector<std::string> types = {"std_msgs/String", "std_msgs/Header", "geometry_msgs/PoseStamped",
                                                   "geometry_msgs/Twist", "nav_msgs/Odometry"};
    return types;
  }

  /// Creates the subscription for `topic` of `type` unless it exists. Throws bt::PortError for an unknown type or
  /// a topic already subscribed with another type.
  void ensureSubscription(const std::string& topic, const std::string& type) {
    const std::string resolved = node_.resolve_name(topic);
    auto it = topics_.find(resolved);
    if (it != topics_.end()) {
      if (it->second.type != type)
        throw bt::PortError("topic '" + resolved + "' is already awaited with type " + it->second.type + ", not " +
                            type);
      return;
    }
    TopicState& ts = topics_[resolved];
    ts.type = type;
    try {
      if (type == "std_msgs/String") {
        ts.sub = subscribe<std_msgs::msg::String>(topic, resolved, [](const std_msgs::msg::String& m) { return m.data; });
      } else if (type == "std_msgs/Header") {
        ts.sub = subscribe<std_msgs::msg::Header>(topic, resolved);
      } else if (type == "geometry_msgs/PoseStamped") {
        ts.sub = subscribe<geometry_msgs::msg::PoseStamped>(topic, resolved);
      } else if (type == "geometry_msgs/Twist") {
        ts.sub = subscribe<geometry_msgs::msg::Twist>(topic, resolved);
      } else if (type == "nav_msgs/Odometry") {
        ts.sub = subscribe<nav_msgs::msg::Odometry>(topic, resolved);
      } else {
        std::string known;
        for (const auto& t : messageTypes()) known += (known.empty() ? "" : ", ") + t;
        throw bt::PortError("unsupported message type '" + type + "' (supported: " + known + ")");
      }
    } catch (...) {
      topics_.erase(resolved);
      throw;
    }
  }

  /// Registers `l` for the next messages on `topic` (already subscribed); returns a handle for unlisten().
  std::uint64_t listen(const std::string& topic, Listener l) {
    const std::uint64_t h = next_listener_++;
    topics_.at(node_.resolve_name(topic)).listeners[h] = std::move(l);
    return h;
  }
  void unlisten(const std::string& topic, std::uint64_t handle) {
    auto it = topics_.find(node_.resolve_name(topic));
    if (it != topics_.end()) it->second.listeners.erase(handle);
  }

 private:
  struct TopicState {
    std::string type;
    std::shared_ptr<cairn::SubscriptionBase> sub;
    std::map<std::uint64_t, Listener> listeners;
  };

  template <class T>
  std::shared_ptr<cairn::SubscriptionBase> subscribe(
      const std::string& topic, const std::string& resolved,
      std::function<std::string(const T&)> text = [](const T& m) { return cairn::msgs::to_text(m); }) {
    return node_.create_subscription<T>(
        topic, cairn::QoS{},
        [this, resolved, text = std::move(text), gate = gate_](const T& m) {
          gate->run([&] {
            auto it = topics_.find(resolved);
            if (it == topics_.end() || it->second.listeners.empty()) return;
            const std::string s = text(m);
            // a listener may unlisten itself (and only itself) while being called: iterate over a copy of the keys
            std::vector<std::uint64_t> keys;
            for (const auto& [k, v] : it->second.listeners) keys.push_back(k);
            for (auto k : keys) {
              auto li = it->second.listeners.find(k);
              if (li != it->second.listeners.end()) {
                Listener copy = li->second;
                copy(s);
              }
            }
          });
        },
        node_.default_callback_group());
  }

  cairn::Node& node_;
  std::shared_ptr<Gate> gate_;
  std::function<void()> on_tick_;
  std::atomic<bool> tick_posted_{false};
  mutable std::mutex mu_;  // timers_ (timer callbacks and cancelTimer may come from different executor threads)
  std::map<TimerId, std::shared_ptr<cairn::TimerBase>> timers_;
  TimerId next_id_ = 1;
  // Below: only touched from the node's callback group (or the constructor).
  std::map<std::string, std::shared_ptr<cairn::Publisher<std_msgs::msg::String>>> string_pubs_;
  std::map<std::string, TopicState> topics_;
  std::uint64_t next_listener_ = 1;
  std::map<std::string, std::shared_ptr<void>> clients_;
};

// ------------------------------------------------------------------------------------------------ runtime actions
/// PublishString: publishes `data` on `topic` (std_msgs/String) and succeeds.
class PublishString final : public bt::SyncActionNode {
 public:
  PublishString(const bt::NodeConfig& c, RuntimeHub& hub)
      : bt::SyncActionNode(c), hub_(hub), topic_(c.input<std::string>("topic")), data_(c.input<std::string>("data")) {
    if (topic_.isLiteral()) pub_ = hub_.stringPublisher(*topic_.get());  // at load: discovery starts early
  }
  static bt::PortList providedPorts() {
    return {bt::InputPort<std::string>("topic", "topic name (relative names resolve in the node's namespace)"),
            bt::InputPortWithDefault<std::string>("data", "", "text to publish")};
  }

 protected:
  bt::NodeStatus onTick() override {
    std::string topic, data;
    if (!topic_.get(topic) || topic.empty()) {
      reportError("PublishString: port 'topic' is not set");
      return bt::NodeStatus::FAILURE;
    }
    data_.get(data);
    auto pub = pub_ ? pub_ : hub_.stringPublisher(topic);
    std_msgs::msg::String m;
    m.data = std::move(data);
    pub->publish(m);
    return bt::NodeStatus::SUCCESS;
  }

 private:
  RuntimeHub& hub_;
  bt::Input<std::string> topic_, data_;
  std::shared_ptr<cairn::Publisher<std_msgs::msg::String>> pub_;
};

/// WaitForMessage: RUNNING until a message arrives on `topic` after the node started (optionally one whose text
/// equals `equals`); SUCCESS then, with the text in `data`. FAILURE after `timeout_ms` (0: no timeout).
class WaitForMessage final : public bt::EventActionNode {
 public:
  WaitForMessage(const bt::NodeConfig& c, RuntimeHub& hub)
      : bt::EventActionNode(c),
        hub_(hub),
        topic_(c.input<std::string>("topic")),
        type_(c.input<std::string>("type")),
        equals_(c.input<std::string>("equals")),
        timeout_(c.input<int>("timeout_ms")),
        data_(c.output<std::string>("data")) {
    std::string type;
    if (!type_.isLiteral() || !type_.get(type))
      throw bt::PortError("port 'type' must be a literal message type");
    const auto& types = RuntimeHub::messageTypes();
    if (std::find(types.begin(), types.end(), type) == types.end()) {
      std::string known;
      for (const auto& t : types) known += (known.empty() ? "" : ", ") + t;
      throw bt::PortError("port 'type': unsupported message type '" + type + "' (supported: " + known + ")");
    }
    type_name_ = type;
    if (topic_.isLiteral()) hub_.ensureSubscription(*topic_.get(), type_name_);  // subscribed from load on
  }
  ~WaitForMessage() override { release(); }

  static bt::PortList providedPorts() {
    return {bt::InputPort<std::string>("topic", "topic to wait on"),
            bt::InputPortWithDefault<std::string>("type", "std_msgs/String",
                                                  "std_msgs/String | std_msgs/Header | geometry_msgs/PoseStamped | "
                                                  "geometry_msgs/Twist | nav_msgs/Odometry"),
            bt::InputPortWithDefault<std::string>("equals", "",
                                                  "only a message whose text equals this counts (empty: any)"),
            bt::InputPortWithDefault<int>("timeout_ms", "0", "FAILURE after this long on the node clock (0: never)"),
            bt::OutputPort<std::string>("data", "std_msgs/String: data; other types: the message as text")};
  }

 protected:
  bt::NodeStatus start(std::uint64_t run) override {
    release();
    std::string topic;
    if (!topic_.get(topic) || topic.empty()) {
      reportError("WaitForMessage: port 'topic' is not set");
      return bt::NodeStatus::FAILURE;
    }
    try {
      hub_.ensureSubscription(topic, type_name_);
    } catch (const std::exception& e) {
      reportError(std::string("WaitForMessage: ") + e.what());
      return bt::NodeStatus::FAILURE;
    }
    std::string equals;
    equals_.get(equals);
    topic_name_ = topic;
    listener_ = hub_.listen(topic, [this, run, equals](const std::string& text) {
      if (!equals.empty() && text != equals) return;
      data_.set(text);
      release();
      complete(run, bt::NodeStatus::SUCCESS);
    });
    int timeout_ms = 0;
    timeout_.get(timeout_ms);
    if (timeout_ms > 0) {
      timer_ = hub_.callAt(hub_.now() + std::chrono::milliseconds(timeout_ms), [this, run] {
        timer_ = 0;
        release();
        complete(run, bt::NodeStatus::FAILURE);
      });
    }
    return bt::NodeStatus::RUNNING;
  }
  void cancel() override { release(); }

 private:
  void release() {
    if (listener_ != 0) hub_.unlisten(topic_name_, listener_);
    listener_ = 0;
    if (timer_ != 0) hub_.cancelTimer(timer_);
    timer_ = 0;
  }
  RuntimeHub& hub_;
  bt::Input<std::string> topic_, type_, equals_;
  bt::Input<int> timeout_;
  bt::Output<std::string> data_;
  std::string type_name_, topic_name_;
  std::uint64_t listener_ = 0;
  bt::Scheduler::TimerId timer_ = 0;
};

/// Wait: RUNNING for `msec` on the node clock, completed by a one-shot executor timer (not by polling ticks).
class Wait final : public bt::EventActionNode {
 public:
  Wait(const bt::NodeConfig& c, RuntimeHub& hub)
      : bt::EventActionNode(c), hub_(hub), msec_(c.input<int>("msec")) {}
  ~Wait() override { cancel(); }
  static bt::PortList providedPorts() { return {bt::InputPort<int>("msec", "duration on the node clock")}; }

 protected:
  bt::NodeStatus start(std::uint64_t run) override {
    int ms = 0;
    if (!msec_.get(ms) || ms < 0) {
      reportError("Wait: port 'msec' is not a non-negative integer");
      return bt::NodeStatus::FAILURE;
    }
    timer_ = hub_.callAt(hub_.now() + std::chrono::milliseconds(ms), [this, run] {
      timer_ = 0;
      complete(run, bt::NodeStatus::SUCCESS);
    });
    return bt::NodeStatus::RUNNING;
  }
  void cancel() override {
    if (timer_ != 0) hub_.cancelTimer(timer_);
    timer_ = 0;
  }

 private:
  RuntimeHub& hub_;
  bt::Input<int> msec_;
  bt::Scheduler::TimerId timer_ = 0;
};

// ------------------------------------------------------------------------------------------------ service calls
/// Base of the actions that call a service: onStart sends the request (once the server is discovered), every later
/// tick polls the reply future of cairn::Client::async_send — so a reply is noticed at the next tick, at most one
/// tick period (1 / tick_rate_hz) after it arrived — and `timeout_ms` on the node clock gives FAILURE. A halt or a
/// timeout abandons the call: the late reply is dropped by the client (the future is never read).
template <class Req, class Resp>
class ServiceCallAction : public bt::StatefulActionNode {
 public:
  ServiceCallAction(const bt::NodeConfig& c, RuntimeHub& hub)
      : bt::StatefulActionNode(c), hub_(hub), timeout_(c.input<int>("timeout_ms")) {}

 protected:
  /// The service to call on this run; an error text gives FAILURE.
  virtual std::string serviceName(std::string& name) = 0;
  /// Fills the request from the ports; an error text gives FAILURE.
  virtual std::string makeRequest(Req& req) = 0;
  /// SUCCESS or FAILURE from the reply.
  virtual bt::NodeStatus onReply(const Resp& resp) = 0;
  /// Called when the call is abandoned (halt or timeout) after the request went out.
  virtual void onAbandon() {}
  virtual const char* typeName() const = 0;

  /// Creates the client at load (for a literal service name), so that discovery starts early.
  void prepare(const bt::Input<std::string>& service) {
    if (service.isLiteral() && service.get() && !service.get()->empty()) hub_.client<Req, Resp>(*service.get());
  }

  bt::NodeStatus onStart() override {
    reply_ = {};
    sent_ = false;
    std::string name;
    if (std::string err = serviceName(name); !err.empty()) return fail(err);
    client_ = hub_.client<Req, Resp>(name);
    if (!client_) return fail("no runtime (dry run)");
    int timeout_ms = 0;
    timeout_.get(timeout_ms);
    deadline_ = timeout_ms > 0 ? hub_.now() + std::chrono::milliseconds(timeout_ms) : bt::TimePoint::max();
    req_ = Req{};
    if (std::string err = makeRequest(req_); !err.empty()) return fail(err);
    return onRunning();
  }

  bt::NodeStatus onRunning() override {
    if (!sent_ && client_->service_is_ready()) {
      reply_ = client_->async_send(req_);
      sent_ = true;
    }
    if (sent_ && reply_.wait_for(std::chrono::seconds(0)) == std::future_status::ready) {
      sent_ = false;
      try {
        return onReply(reply_.get());
      } catch (const std::exception& e) {  // broken promise: the client went away
        return fail(std::string("no reply: ") + e.what());
      }
    }
    if (hub_.now() >= deadline_) {
      const bool was_sent = sent_;
      abandon();
      return fail((was_sent ? "no reply from " : "no server for ") + client_->name() + " within timeout_ms");
    }
    return bt::NodeStatus::RUNNING;
  }

  void onHalted() override { abandon(); }

  bt::NodeStatus fail(const std::string& what) {
    reportError(std::string(typeName()) + ": " + what);
    return bt::NodeStatus::FAILURE;
  }
  const std::shared_ptr<cairn::Client<Req, Resp>>& client() const { return client_; }

  RuntimeHub& hub_;

 private:
  void abandon() {
    if (sent_) onAbandon();
    reply_ = {};
    sent_ = false;
  }
  bt::Input<int> timeout_;
  std::shared_ptr<cairn::Client<Req, Resp>> client_;
  Req req_{};
  std::future<Resp> reply_;
  bool sent_ = false;
  bt::TimePoint deadline_{0};
};

/// Reads the `service` port (CallService, NavigateTo).
inline std::string servicePort(const bt::Input<std::string>& in, std::string& name) {
  return in.get(name) && !name.empty() ? "" : "port 'service' is not set";
}

/// What CallService knows about one service type: how the `request` text fills a request, whether a reply means
/// success. The request text is small and per type (no message reflection exists): documented in `help`.
template <class Req, class Resp>
struct ServiceAdapter {
  std::string help;
  std::function<std::string(const std::string& text, Req& req)> fill;  ///< error text or ""
  std::function<bool(const Resp&)> ok;
};

bool parseBoolText(const std::string& text, bool& out) {
  if (text.empty() || text == "false" || text == "0") out = false;
  else if (text == "true" || text == "1") out = true;
  else return false;
  return true;
}

std::vector<std::string> splitWords(const std::string& text) {
  std::istringstream in(text);
  std::vector<std::string> w;
  for (std::string s; in >> s;) w.push_back(s);
  return w;
}

/// CallService: calls `service` of the registered type `type` with the request built from `request`; SUCCESS if
/// the reply reports success, the reply as text in `response`.
template <class Req, class Resp>
class CallService final : public ServiceCallAction<Req, Resp> {
  using Base = ServiceCallAction<Req, Resp>;

 public:
  CallService(const bt::NodeConfig& c, RuntimeHub& hub, ServiceAdapter<Req, Resp> adapter)
      : Base(c, hub), adapter_(std::move(adapter)), service_(c.input<std::string>("service")),
        request_(c.input<std::string>("request")), response_(c.output<std::string>("response")) {
    this->prepare(service_);
    std::string text;
    Req probe{};
    if (request_.isLiteral() && request_.get(text))
      if (std::string err = adapter_.fill(text, probe); !err.empty()) throw bt::PortError("port 'request': " + err);
  }

 protected:
  const char* typeName() const override { return "CallService"; }
  std::string serviceName(std::string& name) override { return servicePort(service_, name); }
  std::string makeRequest(Req& req) override {
    std::string text;
    request_.get(text);
    const std::string err = adapter_.fill(text, req);
    return err.empty() ? err : "request '" + text + "': " + err;
  }
  bt::NodeStatus onReply(const Resp& resp) override {
    response_.set(cairn::msgs::to_text(resp));
    return adapter_.ok(resp) ? bt::NodeStatus::SUCCESS : bt::NodeStatus::FAILURE;
  }

 private:
  ServiceAdapter<Req, Resp> adapter_;
  bt::Input<std::string> service_, request_;
  bt::Output<std::string> response_;
};

/// The service types CallService can call: type name -> node constructor (with the type's request syntax).
struct ServiceTypeEntry {
  std::string help;
  std::function<std::unique_ptr<bt::TreeNode>(const bt::NodeConfig&, RuntimeHub&)> make;
};

template <class Req, class Resp>
ServiceTypeEntry serviceType(ServiceAdapter<Req, Resp> a) {
  const std::string help = a.help;
  return {help, [a](const bt::NodeConfig& c, RuntimeHub& hub) -> std::unique_ptr<bt::TreeNode> {
            return std::make_unique<CallService<Req, Resp>>(c, hub, a);
          }};
}

const std::map<std::string, ServiceTypeEntry>& serviceTypes() {
  namespace slam = cairn_slam_msgs::srv;
  namespace comp = composition_interfaces::srv;
  namespace bs = cairn_bt_msgs::srv;
  static const std::map<std::string, ServiceTypeEntry> types = {
      {"cairn_slam_msgs/srv/Optimize",
       serviceType<slam::Optimize_Request, slam::Optimize_Response>(
           {"republish_map: true | false (default)",
            [](const std::string& t, slam::Optimize_Request& r) {
              return parseBoolText(t, r.republish_map) ? "" : "expected true or false";
            },
            [](const slam::Optimize_Response& r) { return r.success; }})},
      {"cairn_slam_msgs/srv/SaveState",
       serviceType<slam::SaveState_Request, slam::SaveState_Response>(
           {"<path> [<map_stem>]",
            [](const std::string& t, slam::SaveState_Request& r) -> std::string {
              const auto w = splitWords(t);
              if (w.empty() || w.size() > 2) return "expected '<path> [<map_stem>]'";
              r.path = w[0];
              r.map_stem = w.size() > 1 ? w[1] : "";
              return "";
            },
            [](const slam::SaveState_Response& r) { return r.success; }})},
      {"cairn_slam_msgs/srv/LoadState",
       serviceType<slam::LoadState_Request, slam::LoadState_Response>(
           {"<path> [localization_only]",
            [](const std::string& t, slam::LoadState_Request& r) -> std::string {
              const auto w = splitWords(t);
              if (w.empty() || w.size() > 2 || (w.size() == 2 && w[1] != "localization_only"))
                return "expected '<path> [localization_only]'";
              r.path = w[0];
              r.localization_only = w.size() == 2;
              return "";
            },
            [](const slam::LoadState_Response& r) { return r.success; }})},
      {"cairn_copa_msgs/srv/Retrain",
       serviceType<cairn_copa_msgs::srv::Retrain_Request, cairn_copa_msgs::srv::Retrain_Response>(
           {"flush: true | false (default)",
            [](const std::string& t, cairn_copa_msgs::srv::Retrain_Request& r) {
              return parseBoolText(t, r.flush) ? "" : "expected true or false";
            },
            [](const cairn_copa_msgs::srv::Retrain_Response& r) { return r.accepted; }})},
      {"cairn_people_msgs/srv/Follow",
       serviceType<cairn_people_msgs::srv::Follow_Request, cairn_people_msgs::srv::Follow_Response>(
           {"closest | release | <track id>",
            [](const std::string& t, cairn_people_msgs::srv::Follow_Request& r) -> std::string {
              namespace F = cairn_people_msgs::srv::Follow_Request_Constants;
              if (t == "closest") r.command = F::CLOSEST_IN_FRONT;
              else if (t == "release") r.command = F::RELEASE;
              else {
                char* end = nullptr;
                const unsigned long id = std::strtoul(t.c_str(), &end, 10);
                if (t.empty() || *end != '\0' || id > 0xffffffffUL) return "expected closest, release or a track id";
                r.command = F::TRACK_ID;
                r.track_id = static_cast<uint32_t>(id);
              }
              return "";
            },
            [](const cairn_people_msgs::srv::Follow_Response& r) { return r.success; }})},
      {"composition_interfaces/srv/ListNodes",
       serviceType<comp::ListNodes_Request, comp::ListNodes_Response>(
           {"(none)",
            [](const std::string& t, comp::ListNodes_Request&) -> std::string {
              return t.empty() ? "" : "takes no request";
            },
            [](const comp::ListNodes_Response&) { return true; }})},
      {"cairn_bt_msgs/srv/ExecutiveCommand",
       serviceType<bs::ExecutiveCommand_Request, bs::ExecutiveCommand_Response>(
           {"start | stop | switch <tree_id> | load <file> [<tree_id>]",
            [](const std::string& t, bs::ExecutiveCommand_Request& r) -> std::string {
              namespace C = bs::ExecutiveCommand_Request_Constants;
              const auto w = splitWords(t);
              if (w.size() == 1 && w[0] == "start") r.command = C::START;
              else if (w.size() == 1 && w[0] == "stop") r.command = C::STOP;
              else if (w.size() == 2 && w[0] == "switch") r.command = C::SWITCH_TREE, r.tree_id = w[1];
              else if ((w.size() == 2 || w.size() == 3) && w[0] == "load")
                r.command = C::LOAD, r.file = w[1], r.tree_id = w.size() == 3 ? w[2] : "";
              else return "expected start, stop, switch <tree_id> or load <file> [<tree_id>]";
              return "";
            },
            [](const bs::ExecutiveCommand_Response& r) { return r.success; }})},
  };
  return types;
}

std::string serviceTypeList() {
  std::string known;
  for (const auto& [name, e] : serviceTypes()) known += (known.empty() ? "" : ", ") + name;
  return known;
}

std::unique_ptr<bt::TreeNode> makeCallService(const bt::NodeConfig& c, RuntimeHub& hub) {
  std::string type;
  auto in = c.input<std::string>("type");
  if (!in.isLiteral() || !in.get(type)) throw bt::PortError("port 'type' must be a literal service type");
  auto it = serviceTypes().find(type);
  if (it == serviceTypes().end())
    throw bt::PortError("port 'type': unsupported service type '" + type + "' (supported: " + serviceTypeList() + ")");
  return it->second.make(c, hub);
}

bt::PortList callServicePorts() {
  std::string requests;
  for (const auto& [name, e] : serviceTypes()) requests += (requests.empty() ? "" : "; ") + name + ": " + e.help;
  return {bt::InputPort<std::string>("service", "service name (relative names resolve in the node's namespace)"),
          bt::InputPort<std::string>("type", "service type (literal): " + serviceTypeList()),
          bt::InputPortWithDefault<std::string>("request", "", "request text, per type: " + requests),
          bt::InputPortWithDefault<int>("timeout_ms", "5000", "FAILURE after this long on the node clock (0: never)"),
          bt::OutputPort<std::string>("response", "the reply as text (cairn topic echo rendering)")};
}

/// CheckParameter: reads parameter `param` of node `node` through its rcl_interfaces get_parameters service.
/// SUCCESS if it is set and, with `equals` given, equal to it (numbers compare numerically, so 2 equals 2.0).
class CheckParameter final
    : public ServiceCallAction<rcl_interfaces::srv::GetParameters_Request, rcl_interfaces::srv::GetParameters_Response> {
 public:
  CheckParameter(const bt::NodeConfig& c, RuntimeHub& hub)
      : ServiceCallAction(c, hub), node_(c.input<std::string>("node")), param_(c.input<std::string>("param")),
        equals_(c.input<std::string>("equals")), value_(c.output<std::string>("value")) {}
  static bt::PortList providedPorts() {
    return {bt::InputPort<std::string>("node", "fully qualified node name, e.g. /talker"),
            bt::InputPort<std::string>("param", "parameter name"),
            bt::InputPortWithDefault<std::string>("equals", "", "expected value as YAML text (empty: only that it is set)"),
            bt::InputPortWithDefault<int>("timeout_ms", "2000", "FAILURE after this long on the node clock (0: never)"),
            bt::OutputPort<std::string>("value", "the value as YAML text (cairn param get)")};
  }

 protected:
  const char* typeName() const override { return "CheckParameter"; }
  std::string serviceName(std::string& name) override {
    std::string node;
    if (!node_.get(node) || node.empty()) return "port 'node' is not set";
    name = node + "/get_parameters";
    return "";
  }
  std::string makeRequest(rcl_interfaces::srv::GetParameters_Request& req) override {
    std::string name;
    if (!param_.get(name) || name.empty()) return "port 'param' is not set";
    req.names = {name};
    return "";
  }
  bt::NodeStatus onReply(const rcl_interfaces::srv::GetParameters_Response& resp) override {
    if (resp.values.empty()) return fail("empty reply");
    const cairn::ParameterValue v = cairn::from_parameter_msg(resp.values[0]);
    if (std::holds_alternative<std::monostate>(v)) return bt::NodeStatus::FAILURE;  // not declared
    value_.set(cairn::to_string(v));
    std::string equals;
    equals_.get(equals);
    if (equals.empty()) return bt::NodeStatus::SUCCESS;
    const cairn::ParameterValue want = cairn::parse_parameter_text(equals);
    auto number = [](const cairn::ParameterValue& p) -> std::optional<double> {
      if (auto* i = std::get_if<int64_t>(&p)) return static_cast<double>(*i);
      if (auto* d = std::get_if<double>(&p)) return *d;
      return std::nullopt;
    };
    const auto a = number(v), b = number(want);
    const bool same = (a && b) ? *a == *b : cairn::to_string(v) == cairn::to_string(want);
    return same ? bt::NodeStatus::SUCCESS : bt::NodeStatus::FAILURE;
  }

 private:
  bt::Input<std::string> node_, param_, equals_;
  bt::Output<std::string> value_;
};

/// NavigateTo: drives to a named location or a pose through the NavigateTo service (cairn_sim_msgs/srv/NavigateTo,
/// served by the simulator's scripted driving until a navigation component exists). A halt or a timeout cancels
/// the goal on the server. Results feed the navigation monitor.
class NavigateTo final
    : public ServiceCallAction<cairn_sim_msgs::srv::NavigateTo_Request, cairn_sim_msgs::srv::NavigateTo_Response> {
 public:
  using Req = cairn_sim_msgs::srv::NavigateTo_Request;
  using Resp = cairn_sim_msgs::srv::NavigateTo_Response;
  NavigateTo(const bt::NodeConfig& c, RuntimeHub& hub, std::function<void(bool)> on_result)
      : ServiceCallAction(c, hub), on_result_(std::move(on_result)), service_(c.input<std::string>("service")),
        location_(c.input<std::string>("location")), x_(c.input<double>("x")), y_(c.input<double>("y")),
        timeout_ms_(c.input<int>("timeout_ms")), message_(c.output<std::string>("message")) {
    prepare(service_);
  }
  static bt::PortList providedPorts() {
    return {bt::InputPortWithDefault<std::string>("service", "sim/navigate_to", "NavigateTo service"),
            bt::InputPortWithDefault<std::string>("location", "", "named location (world region or route end); empty: x, y"),
            bt::InputPortWithDefault<double>("x", "0", "m, goal in the map frame when location is empty"),
            bt::InputPortWithDefault<double>("y", "0", "m"),
            bt::InputPortWithDefault<int>("timeout_ms", "0", "FAILURE (and the goal cancelled) after this long (0: never)"),
            bt::OutputPort<std::string>("message", "the server's message (arrived, timed out, ...)")};
  }

 protected:
  const char* typeName() const override { return "NavigateTo"; }
  std::string serviceName(std::string& name) override { return servicePort(service_, name); }
  std::string makeRequest(Req& req) override {
    location_.get(req.location);
    if (req.location.empty() && (!x_.get(req.x) || !y_.get(req.y))) return "ports 'x' and 'y' are not set";
    int timeout_ms = 0;
    timeout_ms_.get(timeout_ms);
    req.timeout_s = std::max(0, timeout_ms) / 1000.0;  // the server gives up too (it counts on its own clock)
    return "";
  }
  bt::NodeStatus onReply(const Resp& resp) override {
    message_.set(resp.message);
    if (on_result_) on_result_(resp.success);
    if (!resp.success) reportError("NavigateTo: " + resp.message);
    return resp.success ? bt::NodeStatus::SUCCESS : bt::NodeStatus::FAILURE;
  }
  void onAbandon() override {
    Req cancel;
    cancel.cancel = true;
    (void)client()->async_send(cancel);  // fire and forget: the server stops the robot
  }

 private:
  std::function<void(bool)> on_result_;
  bt::Input<std::string> service_, location_;
  bt::Input<double> x_, y_;
  bt::Input<int> timeout_ms_;
  bt::Output<std::string> message_;
};

// ------------------------------------------------------------------------------------------------ monitoring
/// Monitoring and recovery against the running system (Stüde §5.3, Table 5.1): topic rates from DDS readers of any
/// registered message type, component liveness from the containers' list_nodes, restarts through their
/// unload_node/load_node services, open-loop recovery motions on cmd_vel, alerts on a topic and the supervisor's
/// all-clear from another. No threads: replies are futures advanced by one executor timer (`monitor.poll_ms`).
class DdsSystem final : public bt::monitoring::RecoveryInterface {
 public:
  using ListReq = composition_interfaces::srv::ListNodes_Request;
  using ListResp = composition_interfaces::srv::ListNodes_Response;
  using LoadReq = composition_interfaces::srv::LoadNode_Request;
  using LoadResp = composition_interfaces::srv::LoadNode_Response;
  using UnloadReq = composition_interfaces::srv::UnloadNode_Request;
  using UnloadResp = composition_interfaces::srv::UnloadNode_Response;

  /// A component the executive watches and may restart: "<fqn> <class> <container>".
  struct ComponentSpec {
    std::string fqn, class_name, container;
    bt::monitoring::AgeMonitor* liveness = nullptr;
  };

  DdsSystem(cairn::Node& node, RuntimeHub& hub) : node_(node), hub_(hub) {}
  ~DdsSystem() override { readers_.clear(); }

  bt::monitoring::MonitorSet& monitors() { return monitors_; }

  /// The monitor.* parameters (README "Monitoring over DDS").
  struct Config {
    std::vector<std::string> topics, components, processes, clocks;
    bt::Duration liveness_warn{}, liveness_error{}, process_period{}, clock_window{};
    std::string alert_topic, clear_topic, cmd_vel_topic;
  };

  /// Parses the monitor.* parameters; throws std::invalid_argument naming the parameter and entry.
  void configure(const Config& cfg) {
    namespace m = bt::monitoring;
    const auto& [topics, components, processes, clocks, liveness_warn, liveness_error, process_period, clock_window,
                 alert_topic, clear_topic, cmd_vel_topic] = cfg;
    process_period_ = process_period;
    for (std::size_t i = 0; i < components.size(); ++i) {
      const auto w = splitWords(components[i]);
      const std::string where = "monitor.components[" + std::to_string(i) + "]";
      if (w.size() != 3 || w[0].empty() || w[0][0] != '/')
        throw std::invalid_argument(where + ": expected '<node fqn> <class> <container>', got '" + components[i] + "'");
      ComponentSpec c{w[0], w[1], w[2]};
      c.liveness = &monitors_.emplace<m::AgeMonitor>({}, "alive:" + c.fqn, "component", c.fqn, liveness_warn, liveness_error);
      components_.push_back(c);
      listClient(c.container);
    }
    for (std::size_t i = 0; i < topics.size(); ++i) {
      const auto w = splitWords(topics[i]);
      const std::string where = "monitor.topics[" + std::to_string(i) + "]";
      const double hz = w.size() == 4 ? cairn::strict_number::parse_finite(w[2]).value_or(0.0) : 0.0;
      if (!(hz > 0.0))
        throw std::invalid_argument(where + ": expected '<topic> <type> <expected_hz> <component>', got '" + topics[i] + "'");
      const cairn::msgs::TypeSupport* ts = typeSupport(w[1], where);
      auto& mon = monitors_.emplace<m::TopicRateMonitor>({}, node_.resolve_name(w[0]), w[3], hz);
      rates_.push_back(&mon);
      addReader(w[0], *ts, [this, monp = &mon](const cairn::MessageInfo&) { monp->onMessage(bt::TimePoint{node_.now().ns}); });
    }
    for (std::size_t i = 0; i < processes.size(); ++i) {
      const auto w = splitWords(processes[i]);
      const std::string where = "monitor.processes[" + std::to_string(i) + "]";
      double v[4] = {0, 0, 0, 0};
      bool ok = w.size() == 5;
      for (std::size_t k = 0; ok && k < 4; ++k) {
        v[k] = cairn::strict_number::parse_finite(w[k + 1]).value_or(0.0);
        ok = v[k] > 0.0;
      }
      if (!ok || v[0] > v[1] || v[2] > v[3])
        throw std::invalid_argument(where + ": expected '<container> <cpu_warn_%> <cpu_error_%> <ram_warn_mb> "
                                    "<ram_error_mb>' (positive, warn <= error), got '" + processes[i] + "'");
      // Stüde Table 5.1 "CPU, RAM monitor": not in the tolerance band -> send a message (category resource).
      auto& cpu = monitors_.emplace<m::ValueMonitor>({}, "cpu:" + w[0], "resource", w[0], m::Band{.warn_high = v[0], .error_high = v[1]});
      auto& ram = monitors_.emplace<m::ValueMonitor>({}, "ram:" + w[0], "resource", w[0], m::Band{.warn_high = v[2], .error_high = v[3]});
      ProcessState ps;
      ps.container = w[0];
      ps.monitor = std::make_unique<m::ProcessMonitor>(cpu, ram);
      if (!node_.dry_run())
        ps.params = hub_.client<rcl_interfaces::srv::GetParameters_Request, rcl_interfaces::srv::GetParameters_Response>(
            "/" + w[0] + "/get_parameters");
      processes_.push_back(std::move(ps));
    }
    for (std::size_t i = 0; i < clocks.size(); ++i) {
      const auto w = splitWords(clocks[i]);
      const std::string where = "monitor.clocks[" + std::to_string(i) + "]";
      const double warn = w.size() == 4 ? cairn::strict_number::parse_finite(w[2]).value_or(0.0) : 0.0;
      const double err = w.size() == 4 ? cairn::strict_number::parse_finite(w[3]).value_or(0.0) : 0.0;
      if (!(warn > 0.0) || !(err >= warn))
        throw std::invalid_argument(where + ": expected '<topic> <type> <warn_ms> <error_ms>' (0 < warn <= error), got '" +
                                    clocks[i] + "'");
      const cairn::msgs::TypeSupport* ts = typeSupport(w[1], where);
      const std::string topic = node_.resolve_name(w[0]);
      auto& mon = monitors_.emplace<m::ClockOffsetMonitor>(
          {}, "clock:" + topic, topic, std::chrono::nanoseconds(static_cast<std::int64_t>(warn * 1e6)),
          std::chrono::nanoseconds(static_cast<std::int64_t>(err * 1e6)), clock_window);
      // The DDS source timestamp is the writer's system clock; compare with ours at the take.
      addReader(w[0], *ts, [monp = &mon](const cairn::MessageInfo& info) {
        const auto local = std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch());
        monp->onStamp(bt::TimePoint{std::chrono::nanoseconds(info.source_timestamp_ns)}, bt::TimePoint{local});
      });
    }
    alert_topic_ = alert_topic;
    cmd_vel_topic_ = cmd_vel_topic;
    clear_topic_ = clear_topic;
    if (!alert_topic.empty()) hub_.stringPublisher(alert_topic);
    if (!clear_topic.empty()) hub_.ensureSubscription(clear_topic, "std_msgs/String");
    const bt::TimePoint now{node_.now().ns};
    for (auto& c : components_) c.liveness->heartbeat(now);  // a grace period of liveness_error from the start
    for (auto* r : rates_) r->reset(now);                     // and a full rate window
  }

  bool empty() const { return components_.empty() && rates_.empty() && processes_.empty(); }

  /// Called by the poll timer in the node's callback group: advances restarts, handles list replies and sends the
  /// next list requests.
  void poll(bool send_lists) {
    const bt::TimePoint now{node_.now().ns};
    for (auto& [container, l] : lists_) {
      if (l.pending.valid() && l.pending.wait_for(std::chrono::seconds(0)) == std::future_status::ready) {
        ListResp resp;
        try {
          resp = l.pending.get();
        } catch (const std::exception&) {
          continue;
        }
        for (auto& c : components_)
          if (c.container == container &&
              std::find(resp.full_node_names.begin(), resp.full_node_names.end(), c.fqn) != resp.full_node_names.end())
            c.liveness->heartbeat(now);
      }
      // A request to a container that died is never answered: give up on it and ask again.
      if (l.pending.valid() && now - l.sent > kReplyTimeout) l.pending = {};
      if (send_lists && !l.pending.valid() && l.client && l.client->service_is_ready()) {
        l.pending = l.client->async_send(ListReq{});
        l.sent = now;
      }
    }
    for (auto it = restarts_.begin(); it != restarts_.end();) it = advance(*it, now) ? restarts_.erase(it) : std::next(it);
    for (auto& p : processes_) pollProcess(p, now);
  }

  // ---- RecoveryInterface
  void restartComponent(const std::string& component, Done done) override {
    auto it = std::find_if(components_.begin(), components_.end(), [&](const ComponentSpec& c) { return c.fqn == component; });
    if (it == components_.end()) {
      CAIRN_ERROR(node_.logger(), "RestartComponent: '" << component << "' is not in monitor.components");
      done(false);
      return;
    }
    CAIRN_WARN(node_.logger(), "restarting " << it->fqn << " (" << it->class_name << ") in container " << it->container);
    Restart r;
    r.spec = *it;
    r.done = std::move(done);
    r.deadline = bt::TimePoint{node_.now().ns} + std::chrono::seconds(15);
    restarts_.push_back(std::move(r));
  }
  void moveBackwards(double distance_m, Done done) override {
    drive(-kRecoverySpeed, 0.0, std::abs(distance_m) / kRecoverySpeed, std::move(done));  // Table 5.1 step 2
  }
  void slowRotate(double angle_rad, Done done) override {
    drive(0.0, kRecoveryTurn, std::abs(angle_rad) / kRecoveryTurn, std::move(done));  // Table 5.1 localization
  }
  void askSupervisor(const std::string& message, Done done) override {
    sendAlert("supervisor needed: " + message);
    if (clear_topic_.empty()) {
      done(false);
      return;
    }
    clear_listener_ = hub_.listen(clear_topic_, [this, done = std::move(done)](const std::string&) {
      hub_.unlisten(clear_topic_, clear_listener_);
      clear_listener_ = 0;
      done(true);
    });
  }
  void sendAlert(const std::string& message) override {
    CAIRN_WARN(node_.logger(), "alert: " << message);
    if (alert_topic_.empty()) return;
    std_msgs::msg::String m;
    m.data = message;
    hub_.stringPublisher(alert_topic_)->publish(m);
  }
  void cancel() override {
    restarts_.clear();
    if (clear_listener_ != 0) hub_.unlisten(clear_topic_, clear_listener_);
    clear_listener_ = 0;
    if (drive_timer_ != 0) hub_.cancelTimer(drive_timer_);
    if (drive_timer_ != 0) publishTwist(0.0, 0.0);
    drive_timer_ = 0;
  }

 private:
  static constexpr double kRecoverySpeed = 0.1;  // m/s, backwards (chosen; Table 5.1 gives no speed)
  static constexpr double kRecoveryTurn = 0.3;   // rad/s, "slow rotate" (chosen)

  /// A list or parameter request unanswered this long is dropped and sent again (its server died, e.g. a killed
  /// container whose DDS participant has not timed out yet).
  static constexpr bt::Duration kReplyTimeout = std::chrono::seconds(2);

  struct ListState {
    std::shared_ptr<cairn::Client<ListReq, ListResp>> client;
    std::future<ListResp> pending;
    bt::TimePoint sent{0};
  };
  struct Restart {
    ComponentSpec spec;
    Done done;
    int stage = 0;  // 0 send list, 1 list sent, 2 unload sent, 3 load sent
    bt::TimePoint list_sent{0};
    std::future<ListResp> list;
    std::future<UnloadResp> unload;
    std::future<LoadResp> load;
    bt::TimePoint deadline{0};
  };

  ListState& listClient(const std::string& container) {
    auto& l = lists_[container];
    if (!l.client) l.client = hub_.client<ListReq, ListResp>("/" + container + "/_container/list_nodes");
    return l;
  }

  template <class F>
  static bool ready(F& f) {
    return f.valid() && f.wait_for(std::chrono::seconds(0)) == std::future_status::ready;
  }

  /// One step of a restart (list -> unload if present -> load); true when finished (done called).
  bool advance(Restart& r, bt::TimePoint now) {
    const std::string base = "/" + r.spec.container + "/_container/";
    auto finish = [&](bool ok, const std::string& why) {
      if (!ok) CAIRN_ERROR(node_.logger(), "restart of " << r.spec.fqn << " failed: " << why);
      // on success RestartComponent resets the target's monitors (a fresh history for the new instance)
      auto done = std::move(r.done);
      done(ok);
      return true;
    };
    if (now > r.deadline) return finish(false, "no answer from container " + r.spec.container);
    try {
      if (r.stage == 0) {
        auto c = hub_.client<ListReq, ListResp>(base + "list_nodes");
        if (c->service_is_ready()) r.list = c->async_send(ListReq{}), r.stage = 1, r.list_sent = now;
      } else if (r.stage == 1 && !ready(r.list) && now - r.list_sent > kReplyTimeout) {
        r.stage = 0;  // the container died under us: ask its successor
      } else if (r.stage == 1 && ready(r.list)) {
        const ListResp l = r.list.get();
        auto it = std::find(l.full_node_names.begin(), l.full_node_names.end(), r.spec.fqn);
        if (it != l.full_node_names.end()) {
          UnloadReq u;
          u.unique_id = l.unique_ids.at(static_cast<std::size_t>(it - l.full_node_names.begin()));
          r.unload = hub_.client<UnloadReq, UnloadResp>(base + "unload_node")->async_send(u);
          r.stage = 2;
        } else {
          r.load = hub_.client<LoadReq, LoadResp>(base + "load_node")->async_send(loadRequest(r.spec));
          r.stage = 3;
        }
      } else if (r.stage == 2 && ready(r.unload)) {
        const UnloadResp u = r.unload.get();
        if (!u.success) return finish(false, "unload: " + u.error_message);
        r.load = hub_.client<LoadReq, LoadResp>(base + "load_node")->async_send(loadRequest(r.spec));
        r.stage = 3;
      } else if (r.stage == 3 && ready(r.load)) {
        const LoadResp l = r.load.get();
        if (!l.success && (l.error_message.rfind(cairn::kNothingToRestore, 0) == 0 ||
                           l.error_message.find("is already loaded") != std::string::npos)) {
          // A freshly respawned container whose launcher has not reloaded the node yet (nothing to restore), or
          // whose launcher reloaded it just before us (already loaded): list again until the deadline, then restart
          // that instance with its launch parameters.
          r.stage = 0;
          return false;
        }
        return l.success ? finish(true, "") : finish(false, "load: " + l.error_message);
      }
    } catch (const std::exception& e) {
      return finish(false, e.what());
    }
    return false;
  }

  /// The component with its class and name, and `restore_parameters`: the container loads it with the parameters,
  /// remaps and QoS it was last loaded with (its launch parameters), which the executive does not know.
  static LoadReq loadRequest(const ComponentSpec& s) {
    LoadReq r;
    r.plugin_name = s.class_name;
    const auto slash = s.fqn.rfind('/');
    r.node_name = s.fqn.substr(slash + 1);
    r.node_namespace = slash == 0 ? "/" : s.fqn.substr(0, slash);
    rcl_interfaces::msg::Parameter restore;
    restore.name = "restore_parameters";
    restore.value = cairn::to_parameter_msg(cairn::ParameterValue(true));
    r.extra_arguments.push_back(restore);
    return r;
  }

  static const cairn::msgs::TypeSupport* typeSupport(std::string type, const std::string& where) {
    const std::string given = type;
    if (type.find("/msg/") == std::string::npos && type.find('/') != std::string::npos)
      type.insert(type.find('/'), "/msg");  // std_msgs/String -> std_msgs/msg/String
    const cairn::msgs::TypeSupport* ts = cairn::msgs::find_type_support(type);
    if (ts == nullptr) throw std::invalid_argument(where + ": unknown message type '" + given + "'");
    return ts;
  }

  /// A best-effort, volatile DDS reader of any registered type (any offered QoS matches it); `on` per message.
  void addReader(const std::string& topic, const cairn::msgs::TypeSupport& ts, std::function<void(const cairn::MessageInfo&)> on) {
    if (node_.dry_run()) return;
    cairn::QoS q;
    q.best_effort();
    auto sample = std::shared_ptr<void>(ts.create(), ts.destroy);
    // The readers live in a participant of their own, like an external DDS tool: DDS readers ignore their own
    // participant, and a publisher serves same-process subscribers intra-process and writes to DDS only for
    // other participants, so a reader in the node's participant never sees a topic published in this container.
    if (!observer_) observer_ = cairn::Context::create(cairn::ContextOptions{node_.context().domain_id(), false});
    readers_.push_back(std::make_unique<cairn::DdsReader>(
        *observer_, cairn::dds_topic_name(node_.resolve_name(topic)), ts, q,
        cairn::DdsEndpointOptions{node_.fully_qualified_name(), false},
        [sample, on = std::move(on), mu = std::make_shared<std::mutex>()](cairn::DdsReader& r) {
          std::lock_guard l(*mu);
          cairn::MessageInfo info;
          while (r.take(sample.get(), info)) on(info);
        }));
  }

  using ParamReq = rcl_interfaces::srv::GetParameters_Request;
  using ParamResp = rcl_interfaces::srv::GetParameters_Response;
  /// CPU/RAM of a container's process: its pid from the container node's `pid` parameter (asked again whenever
  /// the process cannot be read, e.g. after a respawn), sampled every monitor.process_sample_ms from /proc.
  struct ProcessState {
    std::string container;
    std::unique_ptr<bt::monitoring::ProcessMonitor> monitor;
    std::shared_ptr<cairn::Client<ParamReq, ParamResp>> params;
    std::future<ParamResp> pending;
    bt::TimePoint sent{0};
    bt::TimePoint next_sample{0};
    bool need_pid = true;
  };

  void pollProcess(ProcessState& p, bt::TimePoint now) {
    if (ready(p.pending)) {
      try {
        const ParamResp resp = p.pending.get();
        const cairn::ParameterValue v = resp.values.empty() ? cairn::ParameterValue{} : cairn::from_parameter_msg(resp.values[0]);
        if (const auto* pid = std::get_if<int64_t>(&v)) {
          p.monitor->setPid(static_cast<int>(*pid));
          p.need_pid = false;
          p.next_sample = now;
        }
      } catch (const std::exception&) {
      }
    }
    if (p.need_pid) {
      if (p.pending.valid() && now - p.sent > kReplyTimeout) p.pending = {};
      if (!p.pending.valid() && p.params && p.params->service_is_ready()) {
        ParamReq req;
        req.names = {"pid"};
        p.pending = p.params->async_send(req);
        p.sent = now;
      }
      return;
    }
    if (now < p.next_sample) return;
    p.next_sample = now + process_period_;
    if (!p.monitor->sample(now)) p.need_pid = true;  // gone: ask the (respawned) container for its new pid
  }

  void publishTwist(double v, double w) {
    if (!twist_pub_) twist_pub_ = node_.create_publisher<geometry_msgs::msg::Twist>(cmd_vel_topic_, cairn::QoS{});
    if (!twist_pub_) return;
    geometry_msgs::msg::Twist t;
    t.linear.x = v;
    t.angular.z = w;
    twist_pub_->publish(t);
  }

  /// Open loop: (v, w) on cmd_vel at 10 Hz for `seconds` of node time, then zero and done(true).
  void drive(double v, double w, double seconds, Done done) {
    const bt::TimePoint end = bt::TimePoint{node_.now().ns} + std::chrono::nanoseconds(static_cast<std::int64_t>(seconds * 1e9));
    auto step = std::make_shared<std::function<void()>>();
    *step = [this, v, w, end, done = std::move(done), step_weak = std::weak_ptr(step)]() {
      const bt::TimePoint now{node_.now().ns};
      if (now >= end) {
        publishTwist(0.0, 0.0);
        drive_timer_ = 0;
        done(true);
        return;
      }
      publishTwist(v, w);
      if (auto s = step_weak.lock()) drive_timer_ = hub_.callAt(std::min(end, now + std::chrono::milliseconds(100)), [s] { (*s)(); });
    };
    drive_step_ = step;
    (*step)();
  }

  cairn::Node& node_;
  RuntimeHub& hub_;
  bt::monitoring::MonitorSet monitors_;
  std::vector<ComponentSpec> components_;
  std::map<std::string, ListState> lists_;
  std::shared_ptr<cairn::Context> observer_;  ///< participant of the monitoring readers (declared first: outlives them)
  std::vector<std::unique_ptr<cairn::DdsReader>> readers_;
  std::vector<bt::monitoring::TopicRateMonitor*> rates_;
  std::vector<Restart> restarts_;
  std::vector<ProcessState> processes_;
  bt::Duration process_period_{std::chrono::seconds(1)};
  std::string alert_topic_, clear_topic_, cmd_vel_topic_;
  std::uint64_t clear_listener_ = 0;
  bt::Scheduler::TimerId drive_timer_ = 0;
  std::shared_ptr<std::function<void()>> drive_step_;
  std::shared_ptr<cairn::Publisher<geometry_msgs::msg::Twist>> twist_pub_;
};

template <class T>
void registerRuntimeNode(bt::NodeFactory& f, const std::string& id, const std::string& description, RuntimeHub& hub) {
  bt::NodeManifest m;
  m.id = id;
  m.description = description;
  m.kind = bt::NodeKind::Action;
  m.ports = T::providedPorts();
  m.create = [&hub](const bt::NodeConfig& c) -> std::unique_ptr<bt::TreeNode> { return std::make_unique<T>(c, hub); };
  f.registerManifest(std::move(m));
}

// ------------------------------------------------------------------------------------------------ the component
class ExecutiveNode : public cairn::Node {
 public:
  explicit ExecutiveNode(const cairn::NodeOptions& o)
      : cairn::Node(o),
        gate_(std::make_shared<Gate>()),
        hub_(*this, gate_, [this] { tick(); }),
        system_(*this, hub_),
        executive_(factory_, hub_) {
    // Timers and subscriptions created below may fire on executor threads before construction is over.
    const auto hold = gate_->hold();
    using D = cairn::ParameterDescriptor;
    const std::string file = declare_parameter<std::string>(
        "tree_file", "",
        D{"BehaviorTree.CPP v4 XML; relative: working directory, then share/cairn_bt_executive/trees; empty: wait "
          "for a LOAD command", {}, {}, true});
    const std::string tree_id =
        declare_parameter<std::string>("tree_id", "", D{"tree of the file to run (empty: main_tree_to_execute)", {}, {}, true});
    const double rate = declare_parameter<double>("tick_rate_hz", 10.0, D{"periodic root ticks per second (events tick in between)", 0.1, 1000.0, true});
    const bool autostart = declare_parameter<bool>("autostart", true, D{"start the tree once loaded", {}, {}, true});
    executive_.setEventCapacity(0);  // transitions go out on bt/events as they happen; no JSON buffer needed

    registerRuntimeNode<PublishString>(factory_, "PublishString", "publishes std_msgs/String `data` on `topic`", hub_);
    registerRuntimeNode<WaitForMessage>(factory_, "WaitForMessage",
                                        "waits for a message on `topic` (optionally equal to `equals`), with timeout", hub_);
    registerRuntimeNode<Wait>(factory_, "Wait", "waits `msec` on the node clock (executor one-shot timer)", hub_);
    registerRuntimeNode<CheckParameter>(factory_, "CheckParameter",
                                        "SUCCESS if parameter `param` of node `node` is set (and equals `equals`)", hub_);
    {
      bt::NodeManifest m;
      m.id = "CallService";
      m.description = "calls `service` of a registered type with the `request` text; SUCCESS if the reply says so";
      m.kind = bt::NodeKind::Action;
      m.ports = callServicePorts();
      m.create = [this](const bt::NodeConfig& c) { return makeCallService(c, hub_); };
      factory_.registerManifest(std::move(m));
    }

    // Monitoring and recovery (Stüde §5.3): the monitoring nodes of trees/monitoring.xml on the running system.
    const auto mon_topics = declare_parameter<std::vector<std::string>>(
        "monitor.topics", {}, D{"topic rate monitors: '<topic> <type> <expected_hz> <component>'", {}, {}, true});
    const auto mon_components = declare_parameter<std::vector<std::string>>(
        "monitor.components", {}, D{"liveness (container list) and restart: '<node fqn> <class> <container>'", {}, {}, true});
    const int poll_ms = declare_parameter<int>("monitor.poll_ms", 200, D{"container list period and restart steps", 10, 60000, true});
    const int live_warn = declare_parameter<int>("monitor.liveness_warn_ms", 1000, D{"not listed for this long: warning", 1, 3600000, true});
    const int live_err = declare_parameter<int>("monitor.liveness_error_ms", 2000, D{"not listed for this long: error", 1, 3600000, true});
    if (live_warn > live_err)  // as the process and clock monitors: warn <= error
      throw std::invalid_argument("monitor.liveness_warn_ms (" + std::to_string(live_warn) +
                                  ") must not exceed monitor.liveness_error_ms (" + std::to_string(live_err) + ")");
    const int nav_failures = declare_parameter<int>(
        "monitor.navigation_failures", 0, D{"NavigateTo failures in a row that are a navigation error (0: no monitor)", 0, 1000, true});
    const std::string alert_topic = declare_parameter<std::string>("monitor.alert_topic", "bt/alerts", D{"alerts (std_msgs/String)", {}, {}, true});
    const std::string clear_topic = declare_parameter<std::string>(
        "monitor.clear_topic", "bt/all_clear", D{"a message here is the supervisor's all-clear for AskSupervisor", {}, {}, true});
    const std::string cmd_vel = declare_parameter<std::string>("monitor.cmd_vel_topic", "cmd_vel", D{"MoveBackwards / SlowRotate (open loop)", {}, {}, true});
    DdsSystem::Config mc;
    mc.topics = mon_topics;
    mc.components = mon_components;
    mc.processes = declare_parameter<std::vector<std::string>>(
        "monitor.processes", {},
        D{"CPU/RAM of container processes: '<container> <cpu_warn_%> <cpu_error_%> <ram_warn_mb> <ram_error_mb>'", {}, {}, true});
    mc.clocks = declare_parameter<std::vector<std::string>>(
        "monitor.clocks", {}, D{"clock offset to a peer publishing on a topic: '<topic> <type> <warn_ms> <error_ms>'", {}, {}, true});
    mc.liveness_warn = std::chrono::milliseconds(live_warn);
    mc.liveness_error = std::chrono::milliseconds(live_err);
    mc.process_period = std::chrono::milliseconds(declare_parameter<int>(
        "monitor.process_sample_ms", 1000, D{"CPU/RAM sampling period (CPU % is the mean over it)", 10, 3600000, true}));
    mc.clock_window = std::chrono::milliseconds(declare_parameter<int>(
        "monitor.clock_window_ms", 5000, D{"clock offset: minimum of receive - stamp over this window", 10, 3600000, true}));
    mc.alert_topic = alert_topic;
    mc.clear_topic = clear_topic;
    mc.cmd_vel_topic = cmd_vel;
    system_.configure(mc);
    if (nav_failures > 0)
      nav_monitor_ = &system_.monitors().emplace<bt::monitoring::NavigationMonitor>({}, "navigation", nav_failures, nav_failures);
    // Configurations (Stüde §5.3.1): which monitors are active and which components must run, switched by the tree
    // (@configuration) or by a message on monitor.configuration_topic.
    system_.monitors().defineConfigurations(
        declare_parameter<std::vector<std::string>>(
            "monitor.configurations", {},
            D{"'<configuration>: <monitor name or component fqn> ...' (empty: every monitor in every configuration)", {}, {}, true}),
        "monitor.configurations");
    try {
      system_.monitors().setConfiguration(declare_parameter<std::string>(
          "monitor.configuration", "operating", D{"configuration active at start", {}, {}, true}));
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(std::string("monitor.configuration: ") + e.what());
    }
    const std::string config_topic = declare_parameter<std::string>(
        "monitor.configuration_topic", "bt/configuration",
        D{"std_msgs/String naming the configuration to switch to (empty: none)", {}, {}, true});
    if (!config_topic.empty() && !dry_run()) {
      hub_.ensureSubscription(config_topic, "std_msgs/String");
      hub_.listen(config_topic, [this](const std::string& name) {
        try {
          system_.monitors().setConfiguration(name);
          CAIRN_INFO(logger(), "monitor configuration: " << name);
        } catch (const std::invalid_argument& e) {
          system_.sendAlert(std::string("monitor configuration: ") + e.what());
        }
      });
    }
    bt::monitoring::registerMonitoringNodes(factory_, system_.monitors(), system_);
    {
      bt::NodeManifest m;
      m.id = "NavigateTo";
      m.description = "drives to a named location or a pose (NavigateTo service; the simulator serves it)";
      m.kind = bt::NodeKind::Action;
      m.ports = NavigateTo::providedPorts();
      m.create = [this](const bt::NodeConfig& c) {
        return std::make_unique<NavigateTo>(c, hub_, [this](bool ok) {
          if (nav_monitor_) nav_monitor_->onResult(ok);
        });
      };
      factory_.registerManifest(std::move(m));
    }

    status_pub_ = create_publisher<bmsg::TreeStatus>("bt/status", cairn::QoS::latched());
    // transient local: a late watcher (or one still in discovery) gets the last 1000 transitions
    event_pub_ = create_publisher<bmsg::TreeEvent>("bt/events", cairn::QoS{}.keep_last(1000).transient_local());

    if (!file.empty()) {
      const std::string path = resolveTreeFile(file);  // throws: launch validation reports it
      try {
        executive_.load(path, tree_id);
      } catch (const bt::LoadError& e) {
        throw std::invalid_argument(std::string("tree_file: ") + e.what());
      }
      observe();
    }
    command_srv_ = create_service<bsrv::ExecutiveCommand_Request, bsrv::ExecutiveCommand_Response>(
        "~/command", [this](const bsrv::ExecutiveCommand_Request& req, bsrv::ExecutiveCommand_Response& resp) {
          gate_->run([&] { command(req, resp); });
        });
    tick_timer_ = create_timer(
        std::chrono::nanoseconds(static_cast<std::int64_t>(1e9 / rate)), [this] { gate_->run([this] { tick(); }); });
    if (!system_.empty())
      poll_timer_ = create_timer(std::chrono::milliseconds(poll_ms), [this] { gate_->run([this] { system_.poll(true); }); });
    if (dry_run()) return;
    if (autostart && executive_.tree()) {
      executive_.start();
      hub_.requestTick();
    }
    publishStatus();
  }

  ~ExecutiveNode() override {
    gate_->close();  // no callback of this node runs from here on
    hub_.shutdown();
  }

 private:
  void observe() {
    if (!executive_.tree()) return;
    executive_.tree()->addObserver([this, id = executive_.treeId()](const bt::TransitionEvent& e) {
      bmsg::TreeEvent ev;
      ev.tree_id = id;
      ev.stamp = toStamp(e.time.count());
      ev.step = e.step;
      ev.uid = e.uid;
      ev.path = std::string(e.path);
      ev.from_status = static_cast<uint8_t>(e.old_status);
      ev.to_status = static_cast<uint8_t>(e.new_status);
      pending_events_.push_back(std::move(ev));
    });
  }

  void tick() {
    if (executive_.state() != bt::Executive::State::Running) return;
    executive_.tick();
    flush();
  }

  /// Publishes the transitions collected since the last flush, then the status snapshot.
  void flush() {
    for (const auto& ev : pending_events_) event_pub_->publish(ev);
    pending_events_.clear();
    publishStatus();
  }

  void publishStatus() {
    if (dry_run()) return;
    bmsg::TreeStatus s;
    s.stamp = toStamp(now().ns);
    s.tree_id = executive_.treeId();
    s.file = executive_.file();
    s.state = static_cast<uint8_t>(executive_.state());
    s.status = static_cast<uint8_t>(executive_.lastStatus());
    if (auto* t = executive_.tree()) {
      s.tick_count = t->context().step();
      s.nodes.reserve(t->nodes().size());
      for (const auto& n : t->nodes()) {
        bmsg::NodeStatus ns;
        ns.uid = n->uid();
        ns.path = n->path();
        ns.status = static_cast<uint8_t>(n->status());
        s.nodes.push_back(std::move(ns));
      }
    }
    s.status_json = executive_.statusJson();
    status_pub_->publish(s);
  }

  void command(const bsrv::ExecutiveCommand_Request& req, bsrv::ExecutiveCommand_Response& resp) {
    namespace C = bsrv::ExecutiveCommand_Request_Constants;
    resp.success = true;
    try {
      switch (req.command) {
        case C::START:
          resp.success = executive_.start();
          resp.message = resp.success ? "started tree '" + executive_.treeId() + "'" : "no tree loaded";
          if (resp.success) hub_.requestTick();
          break;
        case C::STOP:
          executive_.stop();
          resp.message = "stopped";
          break;
        case C::SWITCH_TREE:
          executive_.switchTree(req.tree_id);
          observe();
          resp.message = "switched to tree '" + executive_.treeId() + "'";
          if (executive_.state() == bt::Executive::State::Running) hub_.requestTick();
          break;
        case C::LOAD: {
          const bool was_running = executive_.state() == bt::Executive::State::Running;
          executive_.load(resolveTreeFile(req.file), req.tree_id);
          observe();
          if (was_running) {
            executive_.start();
            hub_.requestTick();
          }
          resp.message = "loaded tree '" + executive_.treeId() + "' from " + executive_.file();
          break;
        }
        default:
          resp.success = false;
          resp.message = "unknown command " + std::to_string(int(req.command)) + " (0 start, 1 stop, 2 switch, 3 load)";
      }
    } catch (const std::exception& e) {  // LoadError (file:line), unknown tree, missing file: the old tree stays
      resp.success = false;
      resp.message = e.what();
    }
    resp.state = std::string(bt::toString(executive_.state()));
    if (!resp.success) CAIRN_WARN(logger(), "command refused: " << resp.message);
    flush();
  }

  std::shared_ptr<Gate> gate_;
  bt::NodeFactory factory_;
  RuntimeHub hub_;          // the scheduler: must outlive the executive's tree
  DdsSystem system_;        // monitors and recovery: must outlive the tree too
  bt::monitoring::NavigationMonitor* nav_monitor_ = nullptr;
  bt::Executive executive_;  // destroyed first: halting the tree cancels its timers and listeners
  std::vector<bmsg::TreeEvent> pending_events_;
  std::shared_ptr<cairn::Publisher<bmsg::TreeStatus>> status_pub_;
  std::shared_ptr<cairn::Publisher<bmsg::TreeEvent>> event_pub_;
  std::shared_ptr<cairn::Service<bsrv::ExecutiveCommand_Request, bsrv::ExecutiveCommand_Response>> command_srv_;
  std::shared_ptr<cairn::TimerBase> tick_timer_, poll_timer_;
};

}  // namespace cairn_bt

CAIRN_REGISTER_COMPONENT(cairn_bt::ExecutiveNode)
