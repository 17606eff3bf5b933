#include "cairn/bt_executive/monitoring.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <unistd.h>

namespace cairn::bt::monitoring {

std::string_view toString(Level l) {
  switch (l) {
    case Level::Ok: return "OK";
    case Level::Warning: return "WARNING";
    case Level::Error: return "ERROR";
  }
  return "?";
}

Level Band::classify(double v) const {
  if (v < error_low || v > error_high) return Level::Error;
  if (v < warn_low || v > warn_high) return Level::Warning;
  return Level::Ok;
}

namespace {
double seconds(Duration d) { return std::chrono::duration<double>(d).count(); }
std::string fmt(double v) {
  std::ostringstream os;
  os.precision(3);
  os << v;
  return os.str();
}
}  // namespace

// ------------------------------------------------------------------------------------------ TopicRateMonitor
TopicRateMonitor::TopicRateMonitor(std::string topic, std::string publisher, double expected_hz,
                                   double warn_tolerance, double error_tolerance, Duration window)
    : Monitor("rate:" + topic, "topic", std::move(publisher)), expected_(expected_hz), window_(window) {
  band_.warn_low = expected_hz * (1 - warn_tolerance);
  band_.warn_high = expected_hz * (1 + warn_tolerance);
  band_.error_low = expected_hz * (1 - error_tolerance);
  band_.error_high = expected_hz * (1 + error_tolerance);
}

void TopicRateMonitor::onMessage(TimePoint t) {
  std::lock_guard lock(mutex_);
  stamps_.push_back(t);
}

double TopicRateMonitor::rate(TimePoint now) {
  std::lock_guard lock(mutex_);
  const TimePoint from = now - window_;
  std::erase_if(stamps_, [&](TimePoint s) { return s <= from; });
  const std::size_t n = std::count_if(stamps_.begin(), stamps_.end(), [&](TimePoint s) { return s <= now; });
  return static_cast<double>(n) / seconds(window_);
}

Report TopicRateMonitor::evaluate(TimePoint now) {
  const double r = rate(now);
  // A full window must have passed since start/reset before the rate means anything.
  if (now - since_ < window_) return report(Level::Ok, r, "warming up");
  const Level l = band_.classify(r);
  return report(l, r, name().substr(5) + " at " + fmt(r) + " Hz, expected " + fmt(expected_) + " Hz");
}

void TopicRateMonitor::reset(TimePoint now) {
  std::lock_guard lock(mutex_);
  stamps_.clear();
  since_ = now;
}

// ------------------------------------------------------------------------------------------ AgeMonitor
AgeMonitor::AgeMonitor(std::string name, std::string category, std::string target, Duration warn_after,
                       Duration error_after)
    : Monitor(std::move(name), std::move(category), std::move(target)), warn_(warn_after), error_(error_after) {}

void AgeMonitor::heartbeat(TimePoint t) {
  std::lock_guard lock(mutex_);
  last_ = std::max(last_, t);
}

Report AgeMonitor::evaluate(TimePoint now) {
  std::lock_guard lock(mutex_);
  const Duration age = now - last_;
  const Level l = age >= error_ ? Level::Error : age >= warn_ ? Level::Warning : Level::Ok;
  return report(l, seconds(age), name() + ": last event " + fmt(seconds(age)) + " s ago");
}

// ------------------------------------------------------------------------------------------ ValueMonitor
ValueMonitor::ValueMonitor(std::string name, std::string category, std::string target, Band band)
    : Monitor(std::move(name), std::move(category), std::move(target)), band_(band) {}

void ValueMonitor::update(double v) {
  std::lock_guard lock(mutex_);
  value_ = v;
  has_ = true;
}

Report ValueMonitor::evaluate(TimePoint) {
  std::lock_guard lock(mutex_);
  if (!has_) return report(Level::Ok, 0.0, "no sample yet");
  return report(band_.classify(value_), value_, name() + " = " + fmt(value_));
}

// ------------------------------------------------------------------------------------------ NavigationMonitor
NavigationMonitor::NavigationMonitor(std::string target, int warn_failures, int error_failures)
    : Monitor("navigation", "navigation", std::move(target)), warn_(warn_failures), error_(error_failures) {}

void NavigationMonitor::onResult(bool success) {
  std::lock_guard lock(mutex_);
  failures_ = success ? 0 : failures_ + 1;
  if (success) retries_ = 0;
  retrying_ = false;
}

Report NavigationMonitor::evaluate(TimePoint) {
  std::lock_guard lock(mutex_);
  if (retrying_)
    return report(Level::Ok, failures_, "retrying navigation after recovery " + std::to_string(retries_) + " (" +
                                            std::to_string(failures_) + " consecutive failures)");
  const Level l = failures_ >= error_ ? Level::Error : failures_ >= warn_ ? Level::Warning : Level::Ok;
  return report(l, failures_, std::to_string(failures_) + " consecutive navigation failures");
}

void NavigationMonitor::reset(TimePoint) {
  std::lock_guard lock(mutex_);
  failures_ = 0;
  retries_ = 0;
  retrying_ = false;
}

int NavigationMonitor::attempts() const {
  std::lock_guard lock(mutex_);
  return retries_;
}

void NavigationMonitor::retry(TimePoint) {
  std::lock_guard lock(mutex_);
  ++retries_;
  retrying_ = true;
}

// ------------------------------------------------------------------------------------------ ProcessSampler
ProcessSampler::ProcessSampler(int pid, Options o) : pid_(pid), opts_(std::move(o)) {
  if (opts_.clock_ticks <= 0) opts_.clock_ticks = sysconf(_SC_CLK_TCK);
  if (opts_.page_size <= 0) opts_.page_size = sysconf(_SC_PAGESIZE);
}

void ProcessSampler::setPid(int pid) {
  if (pid == pid_) return;
  pid_ = pid;
  last_cpu_s_ = -1.0;
}

ProcessSample ProcessSampler::sample(TimePoint now) {
  ProcessSample s;
  if (pid_ <= 0) return s;
  const std::string dir = opts_.proc_root + "/" + std::to_string(pid_);
  std::ifstream stat(dir + "/stat");
  std::string line;
  if (!std::getline(stat, line)) return s;
  // proc(5): fields after the command name (which may contain spaces and ')') start after the last ')'.
  const auto rp = line.rfind(')');
  if (rp == std::string::npos || rp + 2 > line.size()) return s;
  std::istringstream ss(line.substr(rp + 2));
  std::string f;
  unsigned long long utime = 0, stime = 0;
  int field = 3;
  for (; field <= 15 && ss >> f; ++field) {
    if (field == 14) utime = std::strtoull(f.c_str(), nullptr, 10);
    if (field == 15) stime = std::strtoull(f.c_str(), nullptr, 10);
  }
  if (field <= 15) return s;  // truncated
  std::ifstream statm(dir + "/statm");
  unsigned long long size_pages = 0, resident_pages = 0;
  if (!(statm >> size_pages >> resident_pages)) return s;
  const double cpu_s = static_cast<double>(utime + stime) / static_cast<double>(opts_.clock_ticks);
  if (last_cpu_s_ >= 0 && now > last_t_) {
    s.cpu_percent = std::max(0.0, 100.0 * (cpu_s - last_cpu_s_) / seconds(now - last_t_));
    s.has_cpu = true;
  }
  last_cpu_s_ = cpu_s;
  last_t_ = now;
  s.rss_mb = static_cast<double>(resident_pages) * static_cast<double>(opts_.page_size) / (1024.0 * 1024.0);
  s.ok = true;
  return s;
}

// ------------------------------------------------------------------------------------------ ProcessMonitor
ProcessMonitor::ProcessMonitor(ValueMonitor& cpu, ValueMonitor& ram, ProcessSampler::Options o)
    : cpu_(cpu), ram_(ram), sampler_(0, std::move(o)) {}

void ProcessMonitor::setPid(int pid) { sampler_.setPid(pid); }

bool ProcessMonitor::sample(TimePoint now) {
  const ProcessSample s = sampler_.sample(now);
  if (!s.ok) return false;
  ram_.update(s.rss_mb);
  if (s.has_cpu) cpu_.update(s.cpu_percent);
  return true;
}

// ------------------------------------------------------------------------------------------ ClockOffsetMonitor
ClockOffsetMonitor::ClockOffsetMonitor(std::string name, std::string target, Duration warn, Duration error,
                                       Duration window)
    : Monitor(std::move(name), "resource", std::move(target)), window_(window) {
  band_.warn_high = seconds(warn);
  band_.error_high = seconds(error);
}

void ClockOffsetMonitor::onStamp(TimePoint peer_stamp, TimePoint local_receive) {
  std::lock_guard lock(mutex_);
  samples_.emplace_back(local_receive, local_receive - peer_stamp);
}

bool ClockOffsetMonitor::estimate(TimePoint now, double& offset_s) {
  std::lock_guard lock(mutex_);
  const TimePoint from = now - window_;
  std::erase_if(samples_, [&](const auto& p) { return p.first <= from; });
  if (samples_.empty()) return false;
  Duration lowest = samples_.front().second;
  for (const auto& p : samples_) lowest = std::min(lowest, p.second);  // lower envelope: offset + min latency
  offset_s = seconds(lowest);
  return true;
}

Report ClockOffsetMonitor::evaluate(TimePoint now) {
  double off = 0.0;
  if (!estimate(now, off)) return report(Level::Ok, 0.0, name() + ": no samples");
  return report(band_.classify(std::abs(off)), off, name() + ": clock offset " + fmt(off * 1e3) + " ms");
}

void ClockOffsetMonitor::reset(TimePoint) {
  std::lock_guard lock(mutex_);
  samples_.clear();
}

// ------------------------------------------------------------------------------------------ MonitorSet
Monitor& MonitorSet::add(std::unique_ptr<Monitor> m, std::set<std::string> configurations) {
  defined_.insert(configurations.begin(), configurations.end());
  monitors_.push_back({std::move(m), std::move(configurations)});
  return *monitors_.back().monitor;
}

void MonitorSet::setRequiredComponents(const std::string& configuration, std::vector<std::string> components) {
  defined_.insert(configuration);
  required_[configuration] = std::move(components);
}

const std::vector<std::string>& MonitorSet::requiredComponents() const {
  static const std::vector<std::string> none;
  auto it = required_.find(config_);
  return it == required_.end() ? none : it->second;
}

void MonitorSet::defineConfigurations(const std::vector<std::string>& entries, const std::string& param) {
  // Parse everything first, so a bad entry leaves the set as it was.
  std::map<std::string, std::set<std::string>> monitors_of;  // configuration -> monitor names
  std::map<std::string, std::vector<std::string>> required;
  for (std::size_t i = 0; i < entries.size(); ++i) {
    const std::string where = param + "[" + std::to_string(i) + "]";
    const auto colon = entries[i].find(':');
    std::istringstream head(entries[i].substr(0, colon == std::string::npos ? 0 : colon));
    std::string name, extra;
    if (colon == std::string::npos || !(head >> name) || (head >> extra))
      throw std::invalid_argument(where + ": expected '<configuration>: <monitor or component> ...', got '" +
                                  entries[i] + "'");
    if (monitors_of.count(name)) throw std::invalid_argument(where + ": configuration '" + name + "' defined twice");
    auto& mine = monitors_of[name];
    auto& req = required[name];
    std::istringstream items(entries[i].substr(colon + 1));
    for (std::string item; items >> item;) {
      std::string monitor = item;
      if (item[0] == '/') {  // a component: its liveness monitor, and it must run
        monitor = "alive:" + item;
        req.push_back(item);
      }
      if (!find(monitor)) {
        std::string known;
        for (const auto& e : monitors_) known += (known.empty() ? "" : ", ") + e.monitor->name();
        throw std::invalid_argument(where + ": unknown monitor '" + item + "' (known: " + (known.empty() ? "none" : known) + ")");
      }
      mine.insert(monitor);
    }
  }
  for (auto& e : monitors_)
    for (const auto& [config, names] : monitors_of)
      if (names.count(e.monitor->name())) e.configurations.insert(config);
  for (auto& [config, req] : required) setRequiredComponents(config, std::move(req));
}

std::set<std::string> MonitorSet::configurationNames() const { return defined_; }

void MonitorSet::setConfiguration(const std::string& name) {
  if (!defined_.empty() && !defined_.count(name)) {
    std::string known;
    for (const auto& d : defined_) known += (known.empty() ? "" : ", ") + d;
    throw std::invalid_argument("unknown configuration '" + name + "' (defined: " + known + ")");
  }
  config_ = name;
}

bool MonitorSet::active(const Monitor& m) const {
  for (const auto& e : monitors_)
    if (e.monitor.get() == &m) return e.configurations.empty() || e.configurations.count(config_) > 0;
  return false;
}

Monitor* MonitorSet::find(const std::string& name) const {
  for (auto& e : monitors_)
    if (e.monitor->name() == name) return e.monitor.get();
  return nullptr;
}

std::vector<Report> MonitorSet::evaluate(TimePoint now) {
  std::vector<Report> out;
  for (auto& e : monitors_)
    if (e.configurations.empty() || e.configurations.count(config_)) out.push_back(e.monitor->evaluate(now));
  return out;
}

Report MonitorSet::worstBlocking(const std::vector<Report>& reports) {
  static const std::vector<std::string> priority = {"component", "topic", "localization", "navigation"};
  Report best;
  int best_rank = 1 << 20;
  for (const auto& r : reports) {
    auto it = std::find(priority.begin(), priority.end(), r.category);
    if (it == priority.end() || r.level == Level::Ok) continue;
    const int rank = -static_cast<int>(r.level) * 100 + static_cast<int>(it - priority.begin());
    if (rank < best_rank) {
      best_rank = rank;
      best = r;
    }
  }
  return best;
}

void MonitorSet::resetTarget(const std::string& component, TimePoint now) {
  for (auto& e : monitors_)
    if (e.monitor->target() == component) e.monitor->reset(now);
}

int MonitorSet::attempts(const std::string& category) const {
  int n = 0;
  for (const auto& e : monitors_)
    if (active(*e.monitor) && e.monitor->category() == category) n = std::max(n, e.monitor->attempts());
  return n;
}

void MonitorSet::retry(const std::string& category, TimePoint now) {
  for (auto& e : monitors_)
    if (active(*e.monitor) && e.monitor->category() == category) e.monitor->retry(now);
}

// ------------------------------------------------------------------------------------------ nodes
namespace {

/// Evaluates the active monitors: writes the worst blocking error (level 0/1/2, category, target, message) and
/// sends one alert per resource monitor when it enters its error band.
class UpdateMonitorsNode : public SyncActionNode {
 public:
  UpdateMonitorsNode(const NodeConfig& c, MonitorSet& m, RecoveryInterface& r)
      : SyncActionNode(c), monitors_(m), recovery_(r), level_(c.output<int>("level")),
        category_(c.output<std::string>("category")), target_(c.output<std::string>("target")),
        message_(c.output<std::string>("message")), configuration_(c.input<std::string>("configuration")) {}
  static PortList providedPorts() {
    return {InputPortWithDefault<std::string>("configuration", "",
                                              "switches the MonitorSet to this configuration when the value changes "
                                              "(empty or unset: keep)"),
            OutputPort<int>("level", "0 ok, 1 warning, 2 error (blocking categories)"),
            OutputPort<std::string>("category"), OutputPort<std::string>("target"),
            OutputPort<std::string>("message")};
  }

 protected:
  NodeStatus onTick() override {
    // Stüde §5.3.1: configurations "may be switched autonomously or manually"; edge-triggered, so a switch made
    // elsewhere (the component's configuration topic) is not undone by a stale blackboard value.
    std::string want;
    if (configuration_.get(want) && !want.empty() && want != last_requested_) {
      last_requested_ = want;
      try {
        monitors_.setConfiguration(want);
      } catch (const std::invalid_argument& e) {
        recovery_.sendAlert(std::string("monitor configuration: ") + e.what());
      }
    }
    auto reports = monitors_.evaluate(scheduler().now());
    for (const auto& r : reports) {
      if (r.category != "resource") continue;
      const bool err = r.level == Level::Error;
      if (err && !alerted_.count(r.monitor)) recovery_.sendAlert(r.message);
      if (err) alerted_.insert(r.monitor);
      else alerted_.erase(r.monitor);
    }
    const Report w = MonitorSet::worstBlocking(reports);
    level_.set(static_cast<int>(w.level));
    category_.set(w.category);
    target_.set(w.target);
    message_.set(w.message);
    return NodeStatus::SUCCESS;
  }

 private:
  MonitorSet& monitors_;
  RecoveryInterface& recovery_;
  Output<int> level_;
  Output<std::string> category_, target_, message_;
  Input<std::string> configuration_;
  std::string last_requested_;
  std::set<std::string> alerted_;
};

/// `attempt` := the retries granted to the active monitors of `category` since they last went well (MonitorSet::attempts),
/// or with `retry` true grants one more (MonitorSet::retry): the ladder's step to escalate from, and its last step.
class MonitorRetryNode : public SyncActionNode {
 public:
  MonitorRetryNode(const NodeConfig& c, MonitorSet& m, bool grant)
      : SyncActionNode(c), monitors_(m), grant_(grant), category_(c.input<std::string>("category")) {
    if (!grant) attempt_ = c.output<int>("attempt");
  }

 protected:
  NodeStatus onTick() override {
    std::string category;
    if (!category_.get(category)) return NodeStatus::FAILURE;
    if (grant_) {
      monitors_.retry(category, scheduler().now());
    } else {
      attempt_.set(monitors_.attempts(category));
    }
    return NodeStatus::SUCCESS;
  }

 private:
  MonitorSet& monitors_;
  bool grant_;
  Input<std::string> category_;
  Output<int> attempt_;
};

enum class RecoveryKind { Restart, Backwards, Rotate, Supervisor };

class RecoveryNode : public EventActionNode {
 public:
  RecoveryNode(const NodeConfig& c, RecoveryKind k, MonitorSet& m, RecoveryInterface& r)
      : EventActionNode(c), kind_(k), monitors_(m), recovery_(r) {
    if (k == RecoveryKind::Restart) str_ = c.input<std::string>("component");
    if (k == RecoveryKind::Supervisor) str_ = c.input<std::string>("message");
    if (k == RecoveryKind::Backwards) num_ = c.input<double>("distance");
    if (k == RecoveryKind::Rotate) num_ = c.input<double>("angle");
  }

 protected:
  NodeStatus start(std::uint64_t run) override {
    std::string s;
    double v = 0;
    str_.get(s);
    num_.get(v);
    auto done = [this, run, s](bool ok) {
      // A restarted component starts a fresh monitoring history (no stale rate window).
      if (ok && kind_ == RecoveryKind::Restart) monitors_.resetTarget(s, scheduler().now());
      complete(run, ok ? NodeStatus::SUCCESS : NodeStatus::FAILURE);
    };
    switch (kind_) {
      case RecoveryKind::Restart: recovery_.restartComponent(s, done); break;
      case RecoveryKind::Backwards: recovery_.moveBackwards(v, done); break;
      case RecoveryKind::Rotate: recovery_.slowRotate(v, done); break;
      case RecoveryKind::Supervisor: recovery_.askSupervisor(s, done); break;
    }
    return NodeStatus::RUNNING;
  }
  void cancel() override { recovery_.cancel(); }

 private:
  RecoveryKind kind_;
  MonitorSet& monitors_;
  RecoveryInterface& recovery_;
  Input<std::string> str_;
  Input<double> num_;
};

class RestartComponentNode : public RecoveryNode {
 public:
  RestartComponentNode(const NodeConfig& c, MonitorSet& m, RecoveryInterface& r)
      : RecoveryNode(c, RecoveryKind::Restart, m, r) {}
  static PortList providedPorts() { return {InputPort<std::string>("component", "component to restart")}; }
};

}  // namespace

void registerMonitoringNodes(NodeFactory& f, MonitorSet& monitors, RecoveryInterface& recovery) {
  auto reg = [&](std::string id, PortList ports, std::function<std::unique_ptr<TreeNode>(const NodeConfig&)> make,
                 std::string desc) {
    NodeManifest m;
    m.id = std::move(id);
    m.kind = NodeKind::Action;
    m.ports = std::move(ports);
    m.create = std::move(make);
    m.description = std::move(desc);
    f.registerManifest(std::move(m));
  };
  MonitorSet* ms = &monitors;
  RecoveryInterface* rc = &recovery;
  reg("UpdateMonitors", UpdateMonitorsNode::providedPorts(),
      [ms, rc](const NodeConfig& c) { return std::make_unique<UpdateMonitorsNode>(c, *ms, *rc); },
      "evaluates the monitors of the active configuration");
  reg("RestartComponent", RestartComponentNode::providedPorts(),
      [ms, rc](const NodeConfig& c) { return std::make_unique<RestartComponentNode>(c, *ms, *rc); },
      "restarts a component through the container/supervisor (Table 5.1)");
  reg("MoveBackwards", {InputPortWithDefault<double>("distance", "0.5", "metres")},
      [ms, rc](const NodeConfig& c) { return std::make_unique<RecoveryNode>(c, RecoveryKind::Backwards, *ms, *rc); },
      "navigation recovery step 2 (Table 5.1)");
  reg("SlowRotate", {InputPortWithDefault<double>("angle", "6.283", "radians")},
      [ms, rc](const NodeConfig& c) { return std::make_unique<RecoveryNode>(c, RecoveryKind::Rotate, *ms, *rc); },
      "localization recovery (Table 5.1)");
  reg("RecoveryAttempt",
      {InputPort<std::string>("category", "monitor category, e.g. navigation"),
       OutputPort<int>("attempt", "retries granted since its monitors last went well (0: first recovery)")},
      [ms](const NodeConfig& c) { return std::make_unique<MonitorRetryNode>(c, *ms, false); },
      "which step of a recovery ladder is due (escalation, Table 5.1)");
  reg("RetryTask", {InputPort<std::string>("category", "monitor category, e.g. navigation")},
      [ms](const NodeConfig& c) { return std::make_unique<MonitorRetryNode>(c, *ms, true); },
      "after a recovery step: let the blocked task try again (its monitors report OK until its next result)");
  reg("AskSupervisor", {InputPort<std::string>("message", "text of the alert")},
      [ms, rc](const NodeConfig& c) { return std::make_unique<RecoveryNode>(c, RecoveryKind::Supervisor, *ms, *rc); },
      "last resort: alert the supervisors and wait for their all-clear (Stüde §5.3.1)");
}

std::string monitoringTreesPath() {
  if (const char* env = std::getenv("CAIRN_BT_TREES")) return std::string(env) + "/monitoring.xml";
  return std::string(CAIRN_BT_TREES_DIR) + "/monitoring.xml";
}

}  // namespace cairn::bt::monitoring
