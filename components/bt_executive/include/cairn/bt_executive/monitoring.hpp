// System monitoring with warning/error bands and BT recovery ladders (Stüde §5.3, Table 5.1).
//
// Monitors are plain objects fed by the runtime adapter (message arrivals, heartbeats, process samples,
// navigation results) and evaluated at the tree's time. The node `UpdateMonitors` writes the worst blocking
// error to the blackboard; the arbiter tree (trees/monitoring.xml) blocks the task through `task_blocked`, runs
// the ladder of the error's category and releases the task when the error clears. Recovery actions are
// EventActionNodes that call a RecoveryInterface (container/supervisor services in the runtime, fakes in tests).
#pragma once

#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <vector>

#include "cairn/bt_executive/factory.hpp"
#include "cairn/bt_executive/scheduler.hpp"

namespace cairn::bt::monitoring {

enum class Level { Ok = 0, Warning = 1, Error = 2 };
std::string_view toString(Level l);

/// Warning and error ranges of a monitored value (Stüde §5.3.1: "each monitor includes an individual warning and
/// error range"). Outside [error_low, error_high] -> Error, else outside [warn_low, warn_high] -> Warning.
struct Band {
  double warn_low = -std::numeric_limits<double>::infinity();
  double warn_high = std::numeric_limits<double>::infinity();
  double error_low = -std::numeric_limits<double>::infinity();
  double error_high = std::numeric_limits<double>::infinity();
  Level classify(double v) const;
};

/// Categories select the ladder: component, topic, navigation, localization block the task; resource (CPU, RAM,
/// clock offset, network) only sends a message (Table 5.1).
struct Report {
  std::string monitor;
  std::string category;
  std::string target;  ///< component to restart / subject of the alert
  Level level = Level::Ok;
  double value = 0.0;
  std::string message;
};

class Monitor {
 public:
  Monitor(std::string name, std::string category, std::string target)
      : name_(std::move(name)), category_(std::move(category)), target_(std::move(target)) {}
  virtual ~Monitor() = default;
  const std::string& name() const { return name_; }
  const std::string& category() const { return category_; }
  const std::string& target() const { return target_; }
  virtual Report evaluate(TimePoint now) = 0;
  /// Forget history (after a restart).
  virtual void reset(TimePoint) {}
  /// For errors only the task can clear (navigation: only a goal reached clears "k failures in a row"), a recovery
  /// step is followed by a retry: `retry()` lets the blocked task run again, `attempts()` counts the retries granted
  /// since the monitored thing last went well, so a ladder can escalate (Table 5.1: wait and retry, move
  /// backwards, ask the supervisor). Default: a retry is a reset, and there is no escalation.
  virtual int attempts() const { return 0; }
  virtual void retry(TimePoint now) { reset(now); }

 protected:
  Report report(Level l, double v, std::string msg) const { return {name_, category_, target_, l, v, std::move(msg)}; }

 private:
  std::string name_, category_, target_;
};

/// Topic rate in a tolerance band around the expected rate (Table 5.1 "Topic monitor"). Thread-safe onMessage().
class TopicRateMonitor : public Monitor {
 public:
  TopicRateMonitor(std::string topic, std::string publisher, double expected_hz, double warn_tolerance = 0.2,
                   double error_tolerance = 0.5, Duration window = std::chrono::seconds(2));
  void onMessage(TimePoint t);
  Report evaluate(TimePoint now) override;
  void reset(TimePoint now) override;
  double rate(TimePoint now);

 private:
  double expected_;
  Band band_;
  Duration window_;
  std::mutex mutex_;
  std::vector<TimePoint> stamps_;
  TimePoint since_{0};
};

/// Time since the last event: component liveness (discovery/`list`), or localization health (time since the last
/// loop closure/match, Table 5.1 "Localization monitor").
class AgeMonitor : public Monitor {
 public:
  AgeMonitor(std::string name, std::string category, std::string target, Duration warn_after, Duration error_after);
  void heartbeat(TimePoint t);
  Report evaluate(TimePoint now) override;
  void reset(TimePoint now) override { heartbeat(now); }

 private:
  Duration warn_, error_;
  std::mutex mutex_;
  TimePoint last_{0};
};

/// A sampled value in a band: CPU %, RAM MB, clock offset between hosts [s], network load.
class ValueMonitor : public Monitor {
 public:
  ValueMonitor(std::string name, std::string category, std::string target, Band band);
  void update(double v);
  Report evaluate(TimePoint now) override;

 private:
  Band band_;
  std::mutex mutex_;
  double value_ = 0.0;
  bool has_ = false;
};

/// Navigation health: consecutive failed goals (no global path, recoveries failed) -> Error.
class NavigationMonitor : public Monitor {
 public:
  NavigationMonitor(std::string target, int warn_failures = 1, int error_failures = 2);
  /// A NavigateTo result: a success clears the failures and the retries; a failure counts (and ends a retry).
  void onResult(bool success);
  Report evaluate(TimePoint now) override;
  void reset(TimePoint) override;
  /// Retries granted since the last success.
  int attempts() const override;
  /// OK until the next result, so the blocked task runs and sends its goal again.
  void retry(TimePoint now) override;

 private:
  int warn_, error_;
  mutable std::mutex mutex_;
  int failures_ = 0;
  int retries_ = 0;
  bool retrying_ = false;
};

/// CPU and memory of a process from /proc (Linux): CPU % of one core between two samples (utime + stime of
/// /proc/<pid>/stat, fields 14 and 15) and the resident set size (/proc/<pid>/statm, field 2, in pages).
struct ProcessSample {
  double cpu_percent = 0.0;
  double rss_mb = 0.0;
  bool ok = false;       ///< the files were read
  bool has_cpu = false;  ///< a previous sample of the same pid exists, so cpu_percent means something
};
class ProcessSampler {
 public:
  struct Options {
    std::string proc_root = "/proc";
    long clock_ticks = 0;  ///< per second; 0: sysconf(_SC_CLK_TCK)
    long page_size = 0;    ///< bytes; 0: sysconf(_SC_PAGESIZE)
  };
  explicit ProcessSampler(int pid) : ProcessSampler(pid, Options{}) {}
  ProcessSampler(int pid, Options o);
  ProcessSample sample(TimePoint now);
  /// A new process (after a respawn): forgets the CPU history.
  void setPid(int pid);
  int pid() const { return pid_; }

 private:
  int pid_;
  Options opts_;
  double last_cpu_s_ = -1.0;
  TimePoint last_t_{0};
};

/// CPU % and RSS [MB] of one process (a container) as two ValueMonitors "cpu:<name>" and "ram:<name>" of category
/// "resource" (Table 5.1 "CPU, RAM ... Monitor: not in tolerance band -> send message"). Only the error bands' upper
/// ends are meaningful; a process that cannot be read is reported by the liveness monitor, not here.
class ProcessMonitor {
 public:
  ProcessMonitor(ValueMonitor& cpu, ValueMonitor& ram, ProcessSampler::Options o = {});
  /// Samples the process if its pid is known (> 0); false if it could not be read (e.g. it died).
  bool sample(TimePoint now);
  void setPid(int pid);
  int pid() const { return sampler_.pid(); }

 private:
  ValueMonitor& cpu_;
  ValueMonitor& ram_;
  ProcessSampler sampler_;
};

/// Clock offset between this host and a peer, from (peer stamp, local receive time) pairs of messages the peer
/// publishes (Table 5.1 "NTP monitor"; the thesis compares NTP time differences). Each pair gives
/// d = t_receive - t_stamp = offset + latency with latency >= 0, so the estimator is the lower envelope over a
/// sliding window: offset^ = min(d) over the last `window`. It is biased by the smallest one-way latency in the window
/// (positive; sub-millisecond on a LAN, more on Wi-Fi) and cannot see an asymmetric path; a peer that stamps late
/// (stamp taken long before publishing) looks like a clock behind ours. The band applies to |offset^|; with no sample in
/// the window the level is OK ("no samples"; a silent peer is the topic/liveness monitors' business).
class ClockOffsetMonitor : public Monitor {
 public:
  ClockOffsetMonitor(std::string name, std::string target, Duration warn, Duration error,
                     Duration window = std::chrono::seconds(5));
  /// Thread-safe.
  void onStamp(TimePoint peer_stamp, TimePoint local_receive);
  /// Seconds (local - peer, minus the minimal latency); false if no sample is in the window.
  bool estimate(TimePoint now, double& offset_s);
  Report evaluate(TimePoint now) override;
  void reset(TimePoint now) override;

 private:
  Band band_;
  Duration window_;
  std::mutex mutex_;
  std::vector<std::pair<TimePoint, Duration>> samples_;  ///< (receive time, receive - stamp)
};

/// Monitors grouped into configurations (operating, charging, mapping: Stüde §5.3.1). Only the active
/// configuration's monitors are evaluated; each configuration lists the components that must run. Not thread-safe:
/// configure, switch and evaluate from the tree's thread (the component's callback group).
class MonitorSet {
 public:
  Monitor& add(std::unique_ptr<Monitor> m, std::set<std::string> configurations);
  template <class M, class... A>
  M& emplace(std::set<std::string> configurations, A&&... args) {
    return static_cast<M&>(add(std::make_unique<M>(std::forward<A>(args)...), std::move(configurations)));
  }
  void setRequiredComponents(const std::string& configuration, std::vector<std::string> components);
  const std::vector<std::string>& requiredComponents() const;
  /// Configurations as data: entries '<name>: <item> <item> ...' where an item is a monitor name ("rate:/scan",
  /// "navigation", "cpu:main", ...) or a component fqn ("/slam": its liveness monitor "alive:/slam", and the
  /// component is required in that configuration). Monitors named in no entry stay active everywhere; a monitor
  /// named in some entry is active only in those. Throws std::invalid_argument "<param>[i]: ..." on a bad entry or
  /// an unknown monitor. Call after every monitor is added.
  void defineConfigurations(const std::vector<std::string>& entries, const std::string& param = "configurations");
  /// Names given to defineConfigurations/add/setRequiredComponents.
  std::set<std::string> configurationNames() const;
  /// Throws std::invalid_argument for a name no configuration was defined with (when any was defined).
  void setConfiguration(const std::string& name);
  const std::string& configuration() const { return config_; }
  bool active(const Monitor& m) const;
  Monitor* find(const std::string& name) const;
  /// Reports of the active monitors.
  std::vector<Report> evaluate(TimePoint now);
  /// Worst report of a blocking category (ties: order of priority component, topic, localization, navigation).
  static Report worstBlocking(const std::vector<Report>& reports);
  /// Resets every monitor whose target is `component` (after a restart).
  void resetTarget(const std::string& component, TimePoint now);
  /// The most retries granted to an active monitor of `category` (Monitor::attempts), and a retry for each of them.
  int attempts(const std::string& category) const;
  void retry(const std::string& category, TimePoint now);

 private:
  struct Entry {
    std::unique_ptr<Monitor> monitor;
    std::set<std::string> configurations;
  };
  std::vector<Entry> monitors_;
  std::map<std::string, std::vector<std::string>> required_;
  std::set<std::string> defined_;
  std::string config_ = "operating";
};

/// What the recovery ladders need from the system; the runtime implements it with the container/supervisor
/// services, the navigation action and an alert topic. `done(success)` may be called from any thread.
class RecoveryInterface {
 public:
  using Done = std::function<void(bool success)>;
  virtual ~RecoveryInterface() = default;
  virtual void restartComponent(const std::string& component, Done done) = 0;
  virtual void moveBackwards(double distance_m, Done done) = 0;
  virtual void slowRotate(double angle_rad, Done done) = 0;
  /// Stüde §5.3.1: message with a teleoperation link to the supervisors; done(true) on their all-clear.
  virtual void askSupervisor(const std::string& message, Done done) = 0;
  /// Non-blocking notification (resource monitors).
  virtual void sendAlert(const std::string& message) = 0;
  virtual void cancel() {}
};

/// Registers UpdateMonitors, RestartComponent, MoveBackwards, SlowRotate and AskSupervisor. Both objects must
/// outlive every tree built with the factory.
void registerMonitoringNodes(NodeFactory& factory, MonitorSet& monitors, RecoveryInterface& recovery);

/// Path of the shipped arbiter and ladder trees (trees/monitoring.xml in the source tree).
std::string monitoringTreesPath();

}  // namespace cairn::bt::monitoring
