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
#include <map>
#include <memory>
#include <mutex>
#include <sstream>
#include <string>
#include <vector>

#include "cairn/bt_executive/executive.hpp"
#include "cairn/bt_executive/factory.hpp"
#include "cairn/bt_executive/xml_loader.hpp"
#include "cairn/component.hpp"
#include "cairn/data_files.hpp"
#include "cairn/msgs/type_support.hpp"
#include "cairn_bt_msgs/msg/TreeEvent.hpp"
#include "cairn_bt_msgs/msg/TreeStatus.hpp"
#include "cairn_bt_msgs/srv/ExecutiveCommand.hpp"
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
  bt::Executive executive_;  // destroyed first: halting the tree cancels its timers and listeners
  std::vector<bmsg::TreeEvent> pending_events_;
  std::shared_ptr<cairn::Publisher<bmsg::TreeStatus>> status_pub_;
  std::shared_ptr<cairn::Publisher<bmsg::TreeEvent>> event_pub_;
  std::shared_ptr<cairn::Service<bsrv::ExecutiveCommand_Request, bsrv::ExecutiveCommand_Response>> command_srv_;
  std::shared_ptr<cairn::TimerBase> tick_timer_;
};

}  // namespace cairn_bt

CAIRN_REGISTER_COMPONENT(cairn_bt::ExecutiveNode)
