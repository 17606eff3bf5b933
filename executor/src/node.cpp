#include "cairn/node.hpp"

#include <algorithm>

#include "cairn/parameter_msgs.hpp"
#include "rcl_interfaces/srv/GetParameters.hpp"
#include "rcl_interfaces/srv/ListParameters.hpp"
#include "rcl_interfaces/srv/SetParameters.hpp"
#include "rosgraph_msgs/msg/Clock.hpp"

namespace cairn {

namespace {
bool valid_token(const std::string& s) {
  return !s.empty() && !std::isdigit(static_cast<unsigned char>(s[0])) &&
         std::all_of(s.begin(), s.end(), [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; });
}
}  // namespace

std::string normalize_namespace(const std::string& ns) {
  std::string out = ns.empty() ? "/" : ns;
  if (out[0] != '/') out = "/" + out;
  while (out.size() > 1 && out.back() == '/') out.pop_back();
  std::size_t start = 1;
  while (start < out.size()) {
    std::size_t end = out.find('/', start);
    if (end == std::string::npos) end = out.size();
    if (!valid_token(out.substr(start, end - start))) throw NodeError("invalid namespace '" + ns + "'");
    start = end + 1;
  }
  return out;
}

namespace {

ParameterValue from_msg(const rcl_interfaces::msg::ParameterValue& m) {
  switch (static_cast<ParameterType>(m.type)) {
    case ParameterType::Bool: return m.bool_value;
    case ParameterType::Integer: return m.integer_value;
    case ParameterType::Double: return m.double_value;
    case ParameterType::String: return m.string_value;
    case ParameterType::ByteArray: return m.byte_array_value;
    case ParameterType::BoolArray: return std::vector<bool>(m.bool_array_value.begin(), m.bool_array_value.end());
    case ParameterType::IntegerArray: return m.integer_array_value;
    case ParameterType::DoubleArray: return m.double_array_value;
    case ParameterType::StringArray: return m.string_array_value;
    default: return std::monostate{};
  }
}
}  // namespace

rcl_interfaces::msg::ParameterValue to_parameter_msg(const ParameterValue& v) {
  rcl_interfaces::msg::ParameterValue m;
  m.type = static_cast<uint8_t>(type_of(v));
  std::visit(
      [&](const auto& x) {
        using X = std::decay_t<decltype(x)>;
        if constexpr (std::is_same_v<X, bool>) m.bool_value = x;
        else if constexpr (std::is_same_v<X, int64_t>) m.integer_value = x;
        else if constexpr (std::is_same_v<X, double>) m.double_value = x;
        else if constexpr (std::is_same_v<X, std::string>) m.string_value = x;
        else if constexpr (std::is_same_v<X, std::vector<uint8_t>>) m.byte_array_value = x;
        else if constexpr (std::is_same_v<X, std::vector<bool>>) m.bool_array_value.assign(x.begin(), x.end());
        else if constexpr (std::is_same_v<X, std::vector<int64_t>>) m.integer_array_value = x;
        else if constexpr (std::is_same_v<X, std::vector<double>>) m.double_array_value = x;
        else if constexpr (std::is_same_v<X, std::vector<std::string>>) m.string_array_value = x;
      },
      v);
  return m;
}

ParameterValue from_parameter_msg(const rcl_interfaces::msg::ParameterValue& m) { return from_msg(m); }

Node::Node(const NodeOptions& opts)
    : ctx_(opts.context ? opts.context : Context::default_context()), exec_(opts.executor), opts_(opts),
      params_(opts.parameter_overrides) {
  if (!valid_token(opts.name)) {
    throw NodeError("invalid node name '" + opts.name + "' (letters, digits and _, not starting with a digit)");
  }
  if (!exec_ && !ctx_->dry_run()) throw NodeError("node '" + opts.name + "' needs an executor");
  name_ = opts.name;
  ns_ = normalize_namespace(opts.namespace_);
  fqn_ = (ns_ == "/" ? "" : ns_) + "/" + name_;
  logger_ = Logger(fqn_.substr(1));
  clock_ = std::make_shared<Clock>(ClockType::Ros);
  default_group_ = std::make_shared<CallbackGroup>(CallbackGroup::Type::MutuallyExclusive);
  ctx_->add_node(fqn_);
  const bool sim = declare_parameter<bool>("use_sim_time", false, {"follow /clock instead of the system clock", {}, {}, false});
  if (sim) enable_sim_time(true);
  on_parameter_change([this](const std::string& name, const ParameterValue& v) -> std::optional<std::string> {
    if (name == "use_sim_time") enable_sim_time(std::get<bool>(v));
    return std::nullopt;
  });
  if (opts.start_parameter_services && !ctx_->dry_run()) start_parameter_services();
}

Node::~Node() {
  std::vector<std::shared_ptr<SubscriptionBase>> subs;
  std::vector<std::shared_ptr<ServiceBase>> services;
  std::vector<std::shared_ptr<TimerBase>> timers;
  {
    std::lock_guard l(mu_);
    subs.swap(subs_);
    services.swap(services_);
    timers.swap(timers_);
  }
  for (auto& t : timers) {
    t->cancel();
    t->disable();
    if (exec_) exec_->remove_timer(t.get());
  }
  for (auto& s : subs) s->shutdown();
  for (auto& s : services) s->shutdown();
  clock_sub_.reset();
  if (ctx_->dry_run()) {
    if (auto unused = params_.unused_overrides(); !unused.empty()) {
      ctx_->note_unused_parameters({fqn_, unused, params_.names()});
    }
  } else {
    ctx_->remove_node(fqn_);
  }
}

std::string Node::resolve_name(const std::string& name) const {
  if (name.empty()) throw NodeError("empty topic or service name in node " + fqn_);
  std::string r;
  if (name[0] == '/') {
    r = name;
  } else if (name.rfind("~/", 0) == 0 || name == "~") {
    r = fqn_ + (name.size() > 1 ? name.substr(1) : "");
  } else {
    r = (ns_ == "/" ? "" : ns_) + "/" + name;
  }
  auto it = opts_.remaps.find(r);
  if (it != opts_.remaps.end()) {
    const std::string& to = it->second;
    if (to.empty()) throw NodeError("empty remap target for " + r);
    if (to[0] == '/') return to;
    return (ns_ == "/" ? "" : ns_) + "/" + to;
  }
  return r;
}

std::shared_ptr<CallbackGroup> Node::create_callback_group(CallbackGroup::Type t) {
  return std::make_shared<CallbackGroup>(t);
}

QoS Node::apply_qos_override(const std::string& topic, QoS qos) const {
  auto it = opts_.qos_overrides.find(topic);
  if (it != opts_.qos_overrides.end()) it->second.apply(qos);
  return qos;
}

void Node::record(EndpointRecord::Kind kind, const std::string& topic, const char* type, const QoS& qos) {
  ctx_->record(EndpointRecord{kind, fqn_, topic, type, qos});
}

std::shared_ptr<TimerBase> Node::adopt_timer(std::shared_ptr<TimerBase> t) {
  if (dry_run()) return t;
  std::vector<std::shared_ptr<TimerBase>> gone;
  {
    std::lock_guard l(mu_);
    // A cancelled timer (a one-shot timer that has fired is one) held by nobody but this node and its executor
    // can never run again: only a holder could reset() it. Kept, a node creating one-shot timers would keep
    // every one of them, and the executor would pass over all of them for every item it runs.
    auto dead = std::stable_partition(timers_.begin(), timers_.end(),
                                      [](const auto& x) { return !(x->canceled() && x.use_count() <= 2); });
    gone.assign(std::make_move_iterator(dead), std::make_move_iterator(timers_.end()));
    timers_.erase(dead, timers_.end());
    timers_.push_back(t);
  }
  for (const auto& g : gone) exec_->remove_timer(g.get());
  exec_->add_timer(t);
  return t;
}

std::shared_ptr<TimerBase> Node::create_wall_timer(std::chrono::nanoseconds period, std::function<void()> cb,
                                                   std::shared_ptr<CallbackGroup> group) {
  return adopt_timer(std::make_shared<TimerBase>(group ? group : default_group_,
                                                 std::make_shared<Clock>(ClockType::Steady), period, std::move(cb)));
}

std::shared_ptr<TimerBase> Node::create_timer(std::chrono::nanoseconds period, std::function<void()> cb,
                                              std::shared_ptr<CallbackGroup> group) {
  return adopt_timer(std::make_shared<TimerBase>(group ? group : default_group_, clock_, period, std::move(cb)));
}

std::shared_ptr<TimerBase> Node::create_one_shot_timer(std::chrono::nanoseconds delay, std::function<void()> cb,
                                                       std::shared_ptr<CallbackGroup> group) {
  auto t = std::make_shared<TimerBase>(group ? group : default_group_, clock_, delay, std::move(cb));
  t->set_one_shot(true);
  return adopt_timer(std::move(t));
}

void Node::enable_sim_time(bool on) {
  clock_->enable_sim_time(on);
  if (on && !clock_sub_ && !dry_run()) {
    std::weak_ptr<Clock> wc = clock_;
    QoS q;
    q.keep_last(1).best_effort();
    clock_sub_ = create_subscription<rosgraph_msgs::msg::Clock>("/clock", q, [wc](const rosgraph_msgs::msg::Clock& c) {
      if (auto clk = wc.lock()) clk->set_sim_time(Time{int64_t(c.clock.sec) * 1000000000LL + c.clock.nanosec});
    });
  }
}

void Node::start_parameter_services() {
  using namespace rcl_interfaces::srv;
  create_service<GetParameters_Request, GetParameters_Response>(
      "~/get_parameters", [this](const GetParameters_Request& req, GetParameters_Response& resp) {
        for (const auto& n : req.names) {
          ParameterValue v;
          if (params_.has(n)) v = params_.get(n);
          resp.values.push_back(to_parameter_msg(v));
        }
      });
  create_service<SetParameters_Request, SetParameters_Response>(
      "~/set_parameters", [this](const SetParameters_Request& req, SetParameters_Response& resp) {
        for (const auto& p : req.parameters) {
          rcl_interfaces::msg::SetParametersResult r;
          auto err = params_.set(p.name, from_msg(p.value));
          r.successful = !err;
          r.reason = err.value_or("");
          if (err) {
            CAIRN_WARN(logger_, "set_parameters: " << *err);
          } else {
            CAIRN_INFO(logger_, "parameter " << p.name << " := " << to_string(from_msg(p.value)));
          }
          resp.results.push_back(r);
        }
      });
  create_service<ListParameters_Request, ListParameters_Response>(
      "~/list_parameters", [this](const ListParameters_Request& req, ListParameters_Response& resp) {
        for (const auto& n : params_.names()) {
          bool match = req.prefixes.empty();
          for (const auto& p : req.prefixes) match = match || n.rfind(p, 0) == 0;
          if (match) resp.names.push_back(n);
        }
      });
}

}  // namespace cairn
