// Node: the unit components are made of. Publishers, subscriptions, timers, services, clients and
// typed parameters, all bound to one executor.
#ifndef CAIRN_NODE_HPP
#define CAIRN_NODE_HPP

#include <chrono>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "cairn/context.hpp"
#include "cairn/executor.hpp"
#include "cairn/logging.hpp"
#include "cairn/parameters.hpp"
#include "cairn/publisher.hpp"
#include "cairn/qos.hpp"
#include "cairn/service.hpp"
#include "cairn/subscription.hpp"

namespace cairn {

struct NodeOptions {
  std::string name;
  std::string namespace_ = "/";
  std::map<std::string, ParameterValue> parameter_overrides;
  /// Topic/service remapping: resolved "from" name -> "to" name (both resolved in the node's namespace).
  std::map<std::string, std::string> remaps;
  /// QoS overrides per resolved topic name.
  std::map<std::string, QoSOverride> qos_overrides;
  std::shared_ptr<Context> context;  ///< null: the process's default context
  Executor* executor = nullptr;      ///< required unless the context is a dry run
  bool use_intra_process = true;
  bool start_parameter_services = true;

  NodeOptions() = default;
  NodeOptions(std::string n, Executor* e) : name(std::move(n)), executor(e) {}
};

/// Raised for invalid names, missing executors and other misuse at construction time.
class NodeError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// "robot", "/robot/", "" -> "/robot", "/robot", "/"; throws NodeError for an invalid token ("/9x", "/a b").
std::string normalize_namespace(const std::string& ns);

class Node {
 public:
  explicit Node(const NodeOptions& opts);
  virtual ~Node();
  Node(const Node&) = delete;
  Node& operator=(const Node&) = delete;

  const std::string& name() const { return name_; }
  const std::string& get_namespace() const { return ns_; }
  const std::string& fully_qualified_name() const { return fqn_; }
  const Logger& logger() const { return logger_; }
  Context& context() { return *ctx_; }
  Executor* executor() { return exec_; }
  bool dry_run() const { return ctx_->dry_run(); }
  /// The node's ROS clock (follows /clock when the parameter use_sim_time is true).
  const std::shared_ptr<Clock>& clock() const { return clock_; }
  Time now() const { return clock_->now(); }

  /// Resolves a topic or service name: absolute stays, "~/x" -> /<ns>/<node>/x, "x" -> /<ns>/x; then remaps.
  std::string resolve_name(const std::string& name) const;

  std::shared_ptr<CallbackGroup> create_callback_group(CallbackGroup::Type t);
  const std::shared_ptr<CallbackGroup>& default_callback_group() const { return default_group_; }

  template <class T>
  std::shared_ptr<Publisher<T>> create_publisher(const std::string& topic, QoS qos = QoS{});

  template <class T, class F>
  std::shared_ptr<Subscription<T>> create_subscription(const std::string& topic, QoS qos, F&& callback,
                                                      std::shared_ptr<CallbackGroup> group = nullptr);

  /// Timer on the steady clock.
  std::shared_ptr<TimerBase> create_wall_timer(std::chrono::nanoseconds period, std::function<void()> cb,
                                               std::shared_ptr<CallbackGroup> group = nullptr);
  /// Fires once, `delay` from now on the node's ROS clock, then cancels itself (reset() re-arms it).
  std::shared_ptr<TimerBase> create_one_shot_timer(std::chrono::nanoseconds delay, std::function<void()> cb,
                                                   std::shared_ptr<CallbackGroup> group = nullptr);
  /// Timer on the node's ROS clock (simulated time when use_sim_time is set).
  std::shared_ptr<TimerBase> create_timer(std::chrono::nanoseconds period, std::function<void()> cb,
                                          std::shared_ptr<CallbackGroup> group = nullptr);

  template <class Req, class Resp>
  std::shared_ptr<Service<Req, Resp>> create_service(const std::string& name,
                                                     std::function<void(const Req&, Resp&)> cb,
                                                     std::shared_ptr<CallbackGroup> group = nullptr);
  template <class Req, class Resp>
  std::shared_ptr<Service<Req, Resp>> create_deferred_service(
      const std::string& name, typename Service<Req, Resp>::DeferredCallback cb,
      std::shared_ptr<CallbackGroup> group = nullptr);
  template <class Req, class Resp>
  std::shared_ptr<Client<Req, Resp>> create_client(const std::string& name);

  // ---- parameters ----
  template <class T>
  T declare_parameter(const std::string& name, const T& default_value, const ParameterDescriptor& desc = {}) {
    using Stored = std::conditional_t<std::is_integral_v<T> && !std::is_same_v<T, bool>, int64_t,
                                      std::conditional_t<std::is_floating_point_v<T>, double, T>>;
    const ParameterValue v = params_.declare(name, parameter_type_of<Stored>(), ParameterValue(Stored(default_value)), desc);
    return parameter_as<T>(v, name);
  }
  template <class T>
  T get_parameter(const std::string& name) const {
    return parameter_as<T>(params_.get(name), name);
  }
  std::optional<std::string> set_parameter(const std::string& name, const ParameterValue& v) {
    return params_.set(name, v);
  }
  ParameterStore& parameters() { return params_; }
  /// Called after validation, before a new value is stored; return a reason to reject it.
  void on_parameter_change(ParameterStore::OnSet cb) { params_.on_set(std::move(cb)); }

 private:
  template <class E>
  void track(const std::shared_ptr<E>& e);
  /// Adds a timer to the node and its executor, and drops the node's timers that can never run again.
  std::shared_ptr<TimerBase> adopt_timer(std::shared_ptr<TimerBase> t);
  void record(EndpointRecord::Kind kind, const std::string& topic, const char* type, const QoS& qos);
  QoS apply_qos_override(const std::string& topic, QoS qos) const;
  void start_parameter_services();
  void enable_sim_time(bool on);

  std::shared_ptr<Context> ctx_;
  Executor* exec_;
  std::string name_, ns_, fqn_;
  Logger logger_;
  NodeOptions opts_;
  std::shared_ptr<Clock> clock_;
  std::shared_ptr<CallbackGroup> default_group_;
  ParameterStore params_;
  std::mutex mu_;
  std::vector<std::shared_ptr<SubscriptionBase>> subs_;
  std::vector<std::shared_ptr<ServiceBase>> services_;
  std::vector<std::shared_ptr<TimerBase>> timers_;
  std::shared_ptr<void> clock_sub_;
};

// ---------------- template implementations ----------------

template <class T>
std::shared_ptr<Publisher<T>> Node::create_publisher(const std::string& topic, QoS qos) {
  const std::string resolved = resolve_name(topic);
  qos = apply_qos_override(resolved, qos);
  const auto& ts = msgs::type_support<T>();
  record(EndpointRecord::Kind::Publisher, resolved, ts.ros_type_name, qos);
  if (dry_run()) {
    return std::make_shared<Publisher<T>>(resolved, qos, nullptr, nullptr, Gid{}, clock_, logger_);
  }
  std::shared_ptr<Channel<T>> channel;
  if (opts_.use_intra_process) channel = ctx_->intra().channel<T>(resolved, ts.ros_type_name);
  auto writer = std::make_unique<DdsWriter>(*ctx_, dds_topic_name(resolved), ts, qos, DdsEndpointOptions{fqn_, true});
  const Gid gid = writer->guid();
  return std::make_shared<Publisher<T>>(resolved, qos, std::move(channel), std::move(writer), gid, clock_, logger_);
}

template <class T, class F>
std::shared_ptr<Subscription<T>> Node::create_subscription(const std::string& topic, QoS qos, F&& callback,
                                                           std::shared_ptr<CallbackGroup> group) {
  const std::string resolved = resolve_name(topic);
  qos = apply_qos_override(resolved, qos);
  const auto& ts = msgs::type_support<T>();
  record(EndpointRecord::Kind::Subscription, resolved, ts.ros_type_name, qos);
  auto sub = std::make_shared<Subscription<T>>(group ? group : default_group_, exec_, resolved, qos,
                                               Subscription<T>::make_callback(std::forward<F>(callback)), clock_,
                                               logger_);
  if (dry_run()) return sub;
  std::shared_ptr<Channel<T>> channel;
  if (opts_.use_intra_process) channel = ctx_->intra().channel<T>(resolved, ts.ros_type_name);
  sub->connect(std::move(channel), ctx_.get(), true, DdsEndpointOptions{fqn_, opts_.use_intra_process});
  track(std::static_pointer_cast<SubscriptionBase>(sub));
  return sub;
}

template <class Req, class Resp>
std::shared_ptr<Service<Req, Resp>> Node::create_service(const std::string& name,
                                                         std::function<void(const Req&, Resp&)> cb,
                                                         std::shared_ptr<CallbackGroup> group) {
  return create_deferred_service<Req, Resp>(
      name,
      [cb = std::move(cb)](const Req& req, std::function<void(Resp)> reply) {
        Resp resp{};
        cb(req, resp);
        reply(std::move(resp));
      },
      std::move(group));
}

template <class Req, class Resp>
std::shared_ptr<Service<Req, Resp>> Node::create_deferred_service(const std::string& name,
                                                                  typename Service<Req, Resp>::DeferredCallback cb,
                                                                  std::shared_ptr<CallbackGroup> group) {
  const std::string resolved = resolve_name(name);
  record(EndpointRecord::Kind::ServiceServer, resolved, msgs::type_support<Req>().ros_type_name, QoS::services());
  auto srv = std::make_shared<Service<Req, Resp>>(group ? group : default_group_, exec_, resolved, std::move(cb),
                                                  logger_);
  if (dry_run()) return srv;
  srv->connect(*ctx_, fqn_);
  track(std::static_pointer_cast<ServiceBase>(srv));
  return srv;
}

template <class Req, class Resp>
std::shared_ptr<Client<Req, Resp>> Node::create_client(const std::string& name) {
  const std::string resolved = resolve_name(name);
  record(EndpointRecord::Kind::ServiceClient, resolved, msgs::type_support<Req>().ros_type_name, QoS::services());
  if (dry_run()) return nullptr;
  return std::make_shared<Client<Req, Resp>>(*ctx_, resolved, fqn_);
}

template <class E>
void Node::track(const std::shared_ptr<E>& e) {
  std::lock_guard l(mu_);
  if constexpr (std::is_base_of_v<SubscriptionBase, E>) {
    subs_.push_back(e);
  } else {
    services_.push_back(e);
  }
}

}  // namespace cairn

#endif  // CAIRN_NODE_HPP
