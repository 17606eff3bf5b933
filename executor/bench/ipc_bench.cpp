// cairn bench ipc — latency and throughput of cairn's message paths, each against a baseline measured in
// the same run, one JSON object per line:
//   same_thread   publisher and subscriber on one executor thread (inline delivery), 1 KiB and 1 MiB;
//                 baseline: handing the unique_ptr to a std::function directly.
//   cross_thread  publisher on another thread than the subscriber's executor (event queue + wake-up);
//                 baseline: a bare std::condition_variable hand-off between two threads.
//   dds_rtt_executor / dds_rtt_immediate
//                 two processes over DDS, round trip 12 B / 1 KiB / 64 KiB / 1 MiB, callbacks on executor
//                 threads (default) or in an Immediate callback group (on Cyclone's receive thread);
//                 baseline: ddsperf ping/pong (cyclonedds-tools) in waitset resp. listener mode, same sizes.
//   dds_throughput 1 KiB reliable keep-all flood to another process, with write batching as ddsperf's pub
//                 (and dds_throughput_unbatched: one datagram per sample); baseline: ddsperf pub/sub.
// Latencies are one-way: half the round trip for dds_rtt, as ddsperf prints them.
//   mixed         1 KiB to a local const& subscriber, inline (publisher's executor thread) or queued (another
//                 executor's thread), with and without a subscriber in another process on the topic: the local
//                 latency; baseline: the same without the remote one.
// Runtime costs (the anchors' executor and container targets, ../shared/design/anchors/middleware-and-behavior-trees.md):
//   dispatch      100 registered entities (90 subscriptions, 10 timers), a thread publishing 10 000 msg/s to
//                 them: the executor thread's CPU time per callback and share of a core; baseline: a bare
//                 mutex + condition-variable queue consumer fed the same way, same run.
//   idle          the same 100 entities with nothing due: the executor thread's wake-ups (voluntary context
//                 switches) in 2 s, and with one 10 Hz timer added (one wake-up per expiry is the floor).
//   component_load load + unload of cairn_demo::Talker in a ComponentManager, as `cairn component load` (with the
//                 container's dry-run construction) and as `cairn launch` loads (parameters validated); the first
//                 load includes dlopen; baseline: constructing an equivalent node (publisher + timer) directly.
//   respawn       `cairn launch` of a container publishing at 100 Hz, its process killed with SIGKILL: time from
//                 the kill to the respawned component's first message; baseline: the same launch's cold start.
#include <pthread.h>
#include <signal.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <mutex>
#include <new>
#include <sstream>
#include <thread>
#include <tuple>

#include "../test/alloc_counter.hpp"
#include "cairn/container.hpp"
#include "cairn/node.hpp"
#include "cairn/process.hpp"
#include "sensor_msgs/msg/Image.hpp"
#include "std_msgs/msg/String.hpp"

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;
using Image = sensor_msgs::msg::Image;

namespace {

struct Stats {
  double p50 = 0, p99 = 0, max = 0;
  std::size_t n = 0;
};

Stats stats(std::vector<double> v) {
  Stats s;
  if (v.empty()) return s;
  std::sort(v.begin(), v.end());
  s.n = v.size();
  s.p50 = v[v.size() / 2];
  s.p99 = v[std::min(v.size() - 1, v.size() * 99 / 100)];
  s.max = v.back();
  return s;
}

double ns_since(Clock::time_point t0) { return std::chrono::duration<double, std::nano>(Clock::now() - t0).count(); }

std::string size_name(std::size_t n) {
  if (n >= (1u << 20)) return std::to_string(n >> 20) + "MiB";
  if (n >= 1024) return std::to_string(n >> 10) + "KiB";
  return std::to_string(n) + "B";
}

cairn::NodeOptions opts(const std::string& name, cairn::Executor& e) {
  cairn::NodeOptions o(name, &e);
  o.start_parameter_services = false;
  return o;
}

// ---------------- same thread ----------------
void same_thread(std::size_t size, int iters) {
  cairn::Executor exec;
  cairn::Node node(opts("bench_same", exec));
  auto pub = node.create_publisher<Image>("bench/same");
  std::unique_ptr<Image> slot = std::make_unique<Image>();
  slot->data.resize(size);
  const Image* original = slot.get();
  Clock::time_point t0;
  std::vector<double> lat;
  lat.reserve(iters + 1000);
  long copies = 0;
  auto sub = node.create_subscription<Image>("bench/same", cairn::QoS{}, [&](std::unique_ptr<Image> m) {
    lat.push_back(ns_since(t0));
    if (m.get() != original) ++copies;
    slot = std::move(m);
  });
  long allocs = 0;
  bool done = false;
  auto timer = node.create_wall_timer(1ms, [&] {
    if (done) return;
    for (int i = 0; i < 1000; ++i) {  // warm-up
      t0 = Clock::now();
      pub->publish(std::move(slot));
    }
    lat.clear();
    start_counting_allocations();
    const auto start = Clock::now();
    for (int i = 0; i < iters; ++i) {
      t0 = Clock::now();
      pub->publish(std::move(slot));
    }
    const double total = ns_since(start);
    allocs = stop_counting_allocations();
    const auto s = stats(lat);
    // baseline: a direct std::function call handing over the unique_ptr
    std::function<void(std::unique_ptr<Image>)> direct = [&](std::unique_ptr<Image> m) {
      lat.push_back(ns_since(t0));
      slot = std::move(m);
    };
    lat.clear();
    for (int i = 0; i < iters; ++i) {
      t0 = Clock::now();
      direct(std::move(slot));
    }
    const auto b = stats(lat);
    std::printf(
        "{\"case\":\"same_thread\",\"size\":\"%s\",\"p50_ns\":%.0f,\"p99_ns\":%.0f,\"max_ns\":%.0f,\"msgs_per_s\":%.0f,"
        "\"copies\":%ld,\"allocs_per_msg\":%.3f,\"baseline\":\"direct std::function call\",\"baseline_p50_ns\":%.0f,"
        "\"ratio_p50\":%.2f,\"goal\":\"p50<=1000ns, 0 copies, 0 allocations\"}\n",
        size_name(size).c_str(), s.p50, s.p99, s.max, iters / (total * 1e-9), copies, double(allocs) / iters, b.p50,
        b.p50 > 0 ? s.p50 / b.p50 : 0.0);
    std::fflush(stdout);
    done = true;
  });
  exec.spin_until([&] { return done; }, 60s);
}

// ---------------- cross thread ----------------
void cross_thread(int iters) {
  cairn::Executor exec;
  cairn::Node node(opts("bench_cross", exec));
  auto pub = node.create_publisher<Image>("bench/cross");
  std::mutex mu;
  std::condition_variable cv;
  bool got = false;
  Clock::time_point t0;
  std::vector<double> lat;
  lat.reserve(iters);
  auto sub = node.create_subscription<Image>("bench/cross", cairn::QoS{}, [&](std::unique_ptr<Image>) {
    const double d = ns_since(t0);
    std::lock_guard l(mu);
    lat.push_back(d);
    got = true;
    cv.notify_one();
  });
  std::thread spinner([&] { exec.spin(); });
  auto round = [&](int n) {
    for (int i = 0; i < n; ++i) {
      auto m = std::make_unique<Image>();
      m->data.resize(1024);
      {
        std::lock_guard l(mu);
        got = false;
      }
      t0 = Clock::now();
      pub->publish(std::move(m));
      std::unique_lock l(mu);
      cv.wait(l, [&] { return got; });
    }
  };
  round(200);
  lat.clear();
  round(iters);
  const auto s = stats(lat);
  exec.cancel();
  spinner.join();

  // baseline: condition-variable hand-off of a unique_ptr to a waiting thread, same ping structure
  std::mutex bm;
  std::condition_variable bcv, back;
  std::unique_ptr<Image> box;
  bool stop = false, ack = false;
  std::vector<double> blat;
  blat.reserve(iters);
  std::thread consumer([&] {
    std::unique_lock l(bm);
    for (;;) {
      bcv.wait(l, [&] { return box || stop; });
      if (stop) return;
      blat.push_back(ns_since(t0));
      box.reset();
      ack = true;
      back.notify_one();
    }
  });
  for (int i = 0; i < iters + 200; ++i) {
    if (i == 200) blat.clear();
    auto m = std::make_unique<Image>();
    m->data.resize(1024);
    std::unique_lock l(bm);
    ack = false;
    t0 = Clock::now();
    box = std::move(m);
    bcv.notify_one();
    back.wait(l, [&] { return ack; });
  }
  {
    std::lock_guard l(bm);
    stop = true;
  }
  bcv.notify_one();
  consumer.join();
  const auto b = stats(blat);
  std::printf(
      "{\"case\":\"cross_thread\",\"size\":\"1KiB\",\"p50_ns\":%.0f,\"p99_ns\":%.0f,\"max_ns\":%.0f,"
      "\"baseline\":\"std::condition_variable hand-off\",\"baseline_p50_ns\":%.0f,\"baseline_p99_ns\":%.0f,"
      "\"ratio_p50\":%.2f,\"goal\":\"ratio_p50<=1.2\"}\n",
      s.p50, s.p99, s.max, b.p50, b.p99, b.p50 > 0 ? s.p50 / b.p50 : 0.0);
  std::fflush(stdout);
}

// ---------------- executor dispatch and idle wake-ups ----------------
double thread_cpu_ns(std::thread& t) {
  clockid_t id;
  timespec ts{};
  if (pthread_getcpuclockid(t.native_handle(), &id) != 0 || clock_gettime(id, &ts) != 0) return 0.0;
  return double(ts.tv_sec) * 1e9 + double(ts.tv_nsec);
}

// Voluntary context switches of thread `tid` so far (/proc): each one is the thread going to sleep, i.e. a wake-up.
long voluntary_switches(pid_t tid) {
  std::ifstream f("/proc/self/task/" + std::to_string(tid) + "/status");
  std::string key;
  long v = -1;
  while (f >> key) {
    if (key == "voluntary_ctxt_switches:") {
      f >> v;
      break;
    }
  }
  return v;
}

constexpr int kDispatchTopics = 90, kDispatchTimers = 10;

// The dispatch and idle cases' timers: registered, never due.
std::vector<std::shared_ptr<cairn::TimerBase>> hourly_timers(cairn::Node& node) {
  std::vector<std::shared_ptr<cairn::TimerBase>> timers;
  for (int i = 0; i < kDispatchTimers; ++i) timers.push_back(node.create_wall_timer(std::chrono::hours(1), [] {}));
  return timers;
}

// Spins `exec` on a new thread; `tid` gets its kernel thread id (for voluntary_switches).
std::thread spin_thread(cairn::Executor& exec, std::atomic<pid_t>& tid) {
  return std::thread([&exec, &tid] {
    tid = static_cast<pid_t>(syscall(SYS_gettid));
    exec.spin();
  });
}

// Publishes `rate` messages per second round robin to `publish(i)`, from now for `seconds`; returns the count.
long paced_feed(double rate, double seconds, const std::function<void(int)>& publish) {
  const auto step = std::chrono::nanoseconds(static_cast<long>(1e9 / rate));
  const auto start = Clock::now();
  const auto end = start + std::chrono::nanoseconds(static_cast<long>(seconds * 1e9));
  long n = 0;
  for (auto next = start; next < end; next += step) {
    std::this_thread::sleep_until(next);
    publish(static_cast<int>(n++ % kDispatchTopics));
  }
  return n;
}

void dispatch(double seconds, double rate) {
  cairn::Executor exec;
  cairn::Node node(opts("bench_dispatch", exec));
  std::vector<std::shared_ptr<cairn::Publisher<Image>>> pubs;
  std::vector<std::shared_ptr<cairn::Subscription<Image>>> subs;
  std::atomic<long> calls{0};
  for (int i = 0; i < kDispatchTopics; ++i) {
    const std::string topic = "bench/dispatch_" + std::to_string(i);
    pubs.push_back(node.create_publisher<Image>(topic));
    // keep-all like the baseline's unbounded queue: a stalled executor delays messages but drops none
    subs.push_back(node.create_subscription<Image>(topic, cairn::QoS{}.keep_all(), [&](std::unique_ptr<Image>) {
      calls.fetch_add(1, std::memory_order_relaxed);
    }));
  }
  std::vector<std::shared_ptr<cairn::TimerBase>> timers = hourly_timers(node);
  std::atomic<pid_t> tid{0};
  std::thread spinner = spin_thread(exec, tid);
  auto publish = [&](int i) { pubs[static_cast<std::size_t>(i)]->publish(std::make_unique<Image>()); };
  paced_feed(rate, 0.3, publish);  // warm-up
  std::this_thread::sleep_for(20ms);
  const long c0 = calls, v0 = voluntary_switches(tid);
  const double cpu0 = thread_cpu_ns(spinner);
  const auto w0 = Clock::now();
  const long sent = paced_feed(rate, seconds, publish);
  for (int i = 0; i < 500 && calls - c0 < sent; ++i) std::this_thread::sleep_for(10ms);  // drained (5 s at most)
  const double cpu = thread_cpu_ns(spinner) - cpu0, wall = ns_since(w0);
  const long got = calls - c0, wakeups = voluntary_switches(tid) - v0;
  exec.cancel();
  spinner.join();

  // Baseline: a consumer thread popping unique_ptrs from a mutex-guarded deque (condition-variable wake-up) and
  // calling one of 90 std::function handlers; fed by the same pacing.
  std::mutex mu;
  std::condition_variable cv;
  std::deque<std::pair<int, std::unique_ptr<Image>>> q;
  bool stop = false;
  long bcalls = 0;
  std::vector<std::function<void(std::unique_ptr<Image>)>> handlers(kDispatchTopics, [&](std::unique_ptr<Image>) { ++bcalls; });
  std::atomic<pid_t> btid{0};
  std::thread consumer([&] {
    btid = static_cast<pid_t>(syscall(SYS_gettid));
    std::unique_lock l(mu);
    for (;;) {
      cv.wait(l, [&] { return !q.empty() || stop; });
      if (q.empty()) return;
      auto item = std::move(q.front());
      q.pop_front();
      l.unlock();
      handlers[static_cast<std::size_t>(item.first)](std::move(item.second));
      l.lock();
    }
  });
  auto bpublish = [&](int i) {
    auto m = std::make_unique<Image>();
    {
      std::lock_guard l(mu);
      q.emplace_back(i, std::move(m));
    }
    cv.notify_one();
  };
  paced_feed(rate, 0.3, bpublish);
  std::this_thread::sleep_for(20ms);
  const double bcpu0 = thread_cpu_ns(consumer);
  const long bv0 = voluntary_switches(btid);
  long bc0;
  {
    std::lock_guard l(mu);
    bc0 = bcalls;
  }
  const long bsent = paced_feed(rate, seconds, bpublish);
  for (int i = 0; i < 500; ++i) {  // drained (5 s at most)
    std::this_thread::sleep_for(10ms);
    std::lock_guard l(mu);
    if (q.empty()) break;
  }
  const double bcpu = thread_cpu_ns(consumer) - bcpu0;
  const long bwakeups = voluntary_switches(btid) - bv0;
  long bgot;
  {
    std::lock_guard l(mu);
    bgot = bcalls - bc0;
    stop = true;
  }
  cv.notify_one();
  consumer.join();
  std::printf(
      "{\"case\":\"dispatch\",\"entities\":%d,\"rate_hz\":%.0f,\"sent\":%ld,\"callbacks\":%ld,"
      "\"cpu_per_callback_ns\":%.0f,\"core_percent\":%.2f,\"wakeups_per_callback\":%.2f,"
      "\"baseline\":\"mutex+condvar queue consumer\",\"baseline_sent\":%ld,\"baseline_callbacks\":%ld,"
      "\"baseline_cpu_per_msg_ns\":%.0f,\"baseline_wakeups_per_msg\":%.2f,\"ratio\":%.2f,\"goal\":\"<=1000 ns CPU per callback, <5%% of a core\"}\n",
      kDispatchTopics + kDispatchTimers, rate, sent, got, got ? cpu / double(got) : 0.0, 100.0 * cpu / wall,
      got ? double(wakeups) / double(got) : 0.0, bsent, bgot, bgot ? bcpu / double(bgot) : 0.0, bgot ? double(bwakeups) / double(bgot) : 0.0,
      bgot && got && bcpu > 0 ? (cpu / double(got)) / (bcpu / double(bgot)) : 0.0);
  std::fflush(stdout);
}

void idle(double seconds) {
  cairn::Executor exec;
  cairn::Node node(opts("bench_idle", exec));
  std::vector<std::shared_ptr<cairn::Subscription<Image>>> subs;
  for (int i = 0; i < kDispatchTopics; ++i)
    subs.push_back(node.create_subscription<Image>("bench/idle_" + std::to_string(i), cairn::QoS{}, [](std::unique_ptr<Image>) {}));
  std::vector<std::shared_ptr<cairn::TimerBase>> timers = hourly_timers(node);
  std::atomic<pid_t> tid{0};
  std::thread spinner = spin_thread(exec, tid);
  std::this_thread::sleep_for(300ms);  // settle (DDS readers, discovery run on Cyclone's threads)
  long v0 = voluntary_switches(tid);
  std::this_thread::sleep_for(std::chrono::milliseconds(static_cast<long>(seconds * 1000)));
  const long idle_wakeups = voluntary_switches(tid) - v0;
  std::atomic<long> expiries{0};
  timers.push_back(node.create_wall_timer(100ms, [&] { ++expiries; }));
  std::this_thread::sleep_for(150ms);
  v0 = voluntary_switches(tid);
  const long e0 = expiries;
  std::this_thread::sleep_for(std::chrono::milliseconds(static_cast<long>(seconds * 1000)));
  const long timer_wakeups = voluntary_switches(tid) - v0, fired = expiries - e0;
  exec.cancel();
  spinner.join();
  std::printf(
      "{\"case\":\"idle\",\"entities\":%d,\"seconds\":%.1f,\"wakeups\":%ld,\"timer_10hz_wakeups\":%ld,"
      "\"timer_expiries\":%ld,\"goal\":\"0 wake-ups when nothing is due, one per timer expiry\"}\n",
      kDispatchTopics + kDispatchTimers, seconds, idle_wakeups, timer_wakeups, fired);
  std::fflush(stdout);
}

// ---------------- component load ----------------
void component_load(int iters) {
  auto ctx = cairn::Context::create();
  cairn::Executor exec;
  cairn::ComponentLoader loader;
  cairn::ComponentManager mgr(ctx, exec, "bench_container", loader);
  auto timed_load = [&](bool validated, double& ns) {
    cairn::LoadRequest r{"cairn_demo::Talker", "bench_talker"};
    r.parameters_validated = validated;
    const auto t0 = Clock::now();
    const cairn::LoadResult res = mgr.load(r);
    ns = ns_since(t0);
    if (!res.ok) throw std::runtime_error("load cairn_demo::Talker: " + res.error);
    if (auto err = mgr.unload(res.unique_id)) throw std::runtime_error("unload: " + *err);
  };
  double first = 0.0;
  try {
    timed_load(false, first);
  } catch (const std::exception& e) {
    std::printf("{\"case\":\"component_load\",\"error\":\"%s\"}\n", e.what());
    return;
  }
  std::vector<double> dry, validated, direct;
  for (int i = 0; i < iters; ++i) {
    double ns = 0.0;
    timed_load(false, ns);
    dry.push_back(ns);
    timed_load(true, ns);
    validated.push_back(ns);
    // Baseline: the node the component is (a publisher and a timer), constructed directly.
    const auto t0 = Clock::now();
    {
      cairn::Node n(cairn::NodeOptions("bench_direct", &exec));
      auto pub = n.create_publisher<std_msgs::msg::String>("chatter");
      auto tm = n.create_wall_timer(100ms, [] {});
      direct.push_back(ns_since(t0));
    }
  }
  const Stats d = stats(dry), v = stats(validated), b = stats(direct);
  std::printf(
      "{\"case\":\"component_load\",\"class\":\"cairn_demo::Talker\",\"first_load_ms\":%.2f,\"loads\":%d,"
      "\"p50_ms\":%.3f,\"p99_ms\":%.3f,\"max_ms\":%.3f,\"validated_p50_ms\":%.3f,\"validated_p99_ms\":%.3f,"
      "\"baseline\":\"constructing the equivalent node directly\",\"baseline_p50_ms\":%.3f,\"ratio_validated_p50\":%.2f,"
      "\"goal\":\"p99<=50ms\"}\n",
      first / 1e6, iters, d.p50 / 1e6, d.p99 / 1e6, d.max / 1e6, v.p50 / 1e6, v.p99 / 1e6, b.p50 / 1e6,
      b.p50 > 0 ? v.p50 / b.p50 : 0.0);
  std::fflush(stdout);
}

// ---------------- crash -> serving again ----------------
// Children of `parent` whose command line contains `needle`.
std::vector<pid_t> children_with(pid_t parent, const std::string& needle) {
  std::vector<pid_t> out;
  for (const auto& e : std::filesystem::directory_iterator("/proc")) {
    const std::string name = e.path().filename();
    if (name.find_first_not_of("0123456789") != std::string::npos) continue;
    std::ifstream st(e.path() / "stat");
    std::string line;
    if (!std::getline(st, line)) continue;
    const auto close = line.rfind(')');
    if (close == std::string::npos) continue;
    std::istringstream rest(line.substr(close + 2));
    char state;
    pid_t ppid = 0;
    rest >> state >> ppid;
    if (ppid != parent) continue;
    std::ifstream cl(e.path() / "cmdline");
    std::string cmd((std::istreambuf_iterator<char>(cl)), std::istreambuf_iterator<char>());
    std::replace(cmd.begin(), cmd.end(), '\0', ' ');
    if (cmd.find(needle) != std::string::npos) out.push_back(static_cast<pid_t>(std::stol(name)));
  }
  return out;
}

void respawn(const std::string& self, int kills) {
  const std::string cairn_exe = (std::filesystem::path(self).parent_path() / "cairn").string();
  const std::string spec = (std::filesystem::temp_directory_path() / ("cairn_bench_respawn_" + std::to_string(getpid()) + ".yaml")).string();
  std::ofstream(spec) << "containers:\n  - name: bench_respawn\n    respawn: true\n    respawn_delay: 0.1\n"
                         "    components:\n      - class: cairn_demo::Talker\n        name: bench_talker\n"
                         "        remap: {chatter: bench/respawn_chatter}\n        params: {rate_hz: 100.0}\n";
  cairn::Executor exec;
  cairn::Node node(opts("bench_respawn_watch", exec));
  long last = 0;       // counter of the last message ("hello world: N")
  bool restarted = false;
  long received = 0;
  auto sub = node.create_subscription<std_msgs::msg::String>("bench/respawn_chatter", cairn::QoS{}, [&](const std_msgs::msg::String& m) {
    const auto colon = m.data.rfind(": ");
    const long n = colon == std::string::npos ? 0 : std::atol(m.data.c_str() + colon + 2);
    if (n < last) restarted = true;
    last = n;
    ++received;
  });
  std::vector<double> cold, again;
  for (int k = 0; k < kills; ++k) {
    last = 0;
    received = 0;
    restarted = false;
    const auto t0 = Clock::now();
    const pid_t launch = cairn::spawn_process({"/bin/sh", "-c", "exec " + cairn_exe + " launch " + spec + " > /dev/null 2>&1"});
    if (!exec.spin_until([&] { return received > 0; }, 20s)) {
      std::printf("{\"case\":\"respawn\",\"error\":\"no message from the launched container within 20 s\"}\n");
      cairn::stop_processes({launch});
      break;
    }
    cold.push_back(ns_since(t0));
    exec.spin_until([&] { return last >= 50; }, 5s);  // running steadily
    std::vector<pid_t> c;
    for (int tries = 0; tries < 50 && c.empty(); ++tries) c = children_with(launch, "bench_respawn");
    if (c.size() != 1) {
      std::printf("{\"case\":\"respawn\",\"error\":\"found %zu container processes\"}\n", c.size());
      cairn::stop_processes({launch});
      break;
    }
    const auto t1 = Clock::now();
    kill(c[0], SIGKILL);
    if (exec.spin_until([&] { return restarted; }, 20s)) again.push_back(ns_since(t1));
    cairn::stop_processes({launch});
    exec.spin_for(200ms);
  }
  std::filesystem::remove(spec);
  if (again.empty()) return;
  const Stats a = stats(again), c = stats(cold);
  std::printf(
      "{\"case\":\"respawn\",\"kills\":%zu,\"serving_again_p50_ms\":%.0f,\"serving_again_max_ms\":%.0f,"
      "\"respawn_delay_ms\":100,\"baseline\":\"cold start of the same launch\",\"baseline_p50_ms\":%.0f,"
      "\"ratio_p50\":%.2f,\"goal\":\"<=2000ms\"}\n",
      a.n, a.p50 / 1e6, a.max / 1e6, c.p50 / 1e6, c.p50 > 0 ? a.p50 / c.p50 : 0.0);
  std::fflush(stdout);
}

// ---------------- mixed: local latency with a remote subscriber on the topic ----------------
// The local subscriber (const&, sharing) on the publisher's own executor thread (inline: its callback runs in
// publish()) or on another executor's thread (queued); latency = publish() call to callback entry.
void mixed(const std::string& self, int iters) {
  cairn::Executor exec, other;
  cairn::Node node(opts("bench_mixed", exec));
  auto pub = node.create_publisher<Image>("bench/flood");  // the sink process subscribes to this topic
  std::atomic<int64_t> t0_ns{0};
  std::mutex mu;
  std::vector<double> lat;
  lat.reserve(static_cast<std::size_t>(iters));
  auto record = [&](const Image&) {
    const double d = double(Clock::now().time_since_epoch().count() - t0_ns.load());
    std::lock_guard l(mu);
    lat.push_back(d);
  };
  std::thread other_thread([&] { other.spin(); });
  int measurement = 0;
  auto measure = [&](bool inline_sub) {
    // The subscription's own node, gone after the measurement: a node keeps its subscriptions for its lifetime,
    // so subscriptions of earlier measurements on `node`/`node_other` stayed on the channel and each later
    // measurement also timed them (an inline one first, a queued one's wake-up before the measured callback).
    cairn::Node sub_node(opts("bench_mixed_sub" + std::to_string(++measurement), inline_sub ? exec : other));
    auto sub = sub_node.create_subscription<Image>("bench/flood", cairn::QoS{}.keep_all(), record);
    {
      std::lock_guard l(mu);
      lat.clear();
    }
    bool done = false;
    auto timer = node.create_wall_timer(1ms, [&] {
      if (done) return;
      for (int i = 0; i < iters; ++i) {
        auto m = std::make_unique<Image>();
        m->data.resize(1024);
        std::this_thread::sleep_for(100us);  // paced: the reliable writer and the other thread keep up
        t0_ns = Clock::now().time_since_epoch().count();
        pub->publish(std::move(m));
      }
      done = true;
    });
    exec.spin_until([&] { return done; }, 120s);
    timer->cancel();
    std::this_thread::sleep_for(20ms);
    std::lock_guard l(mu);
    return stats(lat);
  };
  const Stats inline_alone = measure(true), queued_alone = measure(false);
  const pid_t sink = cairn::spawn_process({self, "sink", "60"});
  const bool matched = exec.spin_until([&] { return pub->inter_process_subscription_count() > 0; }, 20s);
  const Stats inline_with = measure(true), queued_with = measure(false);
  cairn::stop_processes({sink});
  other.cancel();
  other_thread.join();
  for (const auto& [name, with, alone] : {std::tuple{"inline", inline_with, inline_alone}, std::tuple{"queued", queued_with, queued_alone}}) {
    std::printf(
        "{\"case\":\"mixed_%s\",\"size\":\"1KiB\",\"remote_matched\":%s,\"p50_ns\":%.0f,\"p99_ns\":%.0f,"
        "\"baseline\":\"same local subscriber, no remote one\",\"baseline_p50_ns\":%.0f,\"baseline_p99_ns\":%.0f,"
        "\"ratio_p50\":%.2f,\"goal\":\"ratio_p50<=1.1\"}\n",
        name, matched ? "true" : "false", with.p50, with.p99, alone.p50, alone.p99, alone.p50 > 0 ? with.p50 / alone.p50 : 0.0);
  }
  std::fflush(stdout);
}

// ---------------- DDS, two processes ----------------
int pong_main(bool immediate) {
  cairn::Executor::install_signal_handlers();
  cairn::Executor exec;
  cairn::Node node(opts("bench_pong", exec));
  cairn::QoS q;
  q.keep_last(1);
  auto pub = node.create_publisher<Image>("bench/pong", q);
  auto group = node.create_callback_group(immediate ? cairn::CallbackGroup::Type::Immediate
                                                    : cairn::CallbackGroup::Type::MutuallyExclusive);
  auto sub = node.create_subscription<Image>(
      "bench/ping", q, [&](std::unique_ptr<Image> m) { pub->publish(std::move(m)); }, group);
  exec.spin();
  return 0;
}

int sink_main(double seconds) {
  cairn::Executor exec;
  cairn::Node node(opts("bench_sink", exec));
  cairn::QoS q;
  q.keep_all();
  long count = 0;
  Clock::time_point first, last;
  auto sub = node.create_subscription<Image>("bench/flood", q, [&](const Image&) {
    if (count++ == 0) first = Clock::now();
    last = Clock::now();
  });
  exec.spin_for(std::chrono::milliseconds(int64_t(seconds * 1000)));
  const double dt = std::chrono::duration<double>(last - first).count();
  std::printf("%ld %.6f\n", count, dt);
  return 0;
}

struct DdsperfResult {
  double p50_us = 0, p99_us = 0, max_us = 0, rate_ks = 0;
  bool ok = false;
};

std::string run_capture(const std::string& cmd) {
  std::string out;
  FILE* p = popen(cmd.c_str(), "r");
  if (!p) return out;
  char buf[4096];
  size_t n;
  while ((n = fread(buf, 1, sizeof buf, p)) > 0) out.append(buf, n);
  pclose(p);
  return out;
}

double field(const std::string& line, const std::string& key) {
  const auto p = line.find(key);
  if (p == std::string::npos) return -1;
  return std::atof(line.c_str() + p + key.size());
}

/// ddsperf ping/pong: median over the per-second lines of their 50%/99%/max (one-way = rtt/2).
DdsperfResult ddsperf_ping(int domain, std::size_t size, double seconds, const std::string& mode) {
  const std::string d = std::to_string(domain);
  const pid_t pong = cairn::spawn_process({"/bin/sh", "-c", "exec ddsperf -i " + d + " pong " + mode + " > /dev/null 2>&1"});
  std::this_thread::sleep_for(300ms);
  const std::string out = run_capture("ddsperf -i " + d + " -D " + std::to_string(int(seconds) + 1) + " ping size " +
                                      std::to_string(size) + " " + mode + " 2>&1");
  cairn::stop_processes({pong});
  std::vector<double> p50, p99, mx;
  std::istringstream in(out);
  std::string line;
  bool first = true;
  while (std::getline(in, line)) {
    if (line.find(" 50% ") == std::string::npos) continue;
    if (first) {  // the first second includes discovery and warm-up
      first = false;
      continue;
    }
    p50.push_back(field(line, " 50% "));
    p99.push_back(field(line, " 99% "));
    mx.push_back(field(line, " max "));
  }
  DdsperfResult r;
  if (p50.empty()) return r;
  std::sort(p50.begin(), p50.end());
  std::sort(p99.begin(), p99.end());
  r.p50_us = p50[p50.size() / 2];
  r.p99_us = p99[p99.size() / 2];
  r.max_us = *std::max_element(mx.begin(), mx.end());
  r.ok = true;
  return r;
}

DdsperfResult ddsperf_throughput(int domain, std::size_t size, double seconds) {
  const std::string d = std::to_string(domain);
  const std::string log = "/tmp/cairn_bench_ddsperf_sub_" + std::to_string(getpid()) + ".txt";
  const pid_t sub = cairn::spawn_process({"/bin/sh", "-c", "exec ddsperf -i " + d + " -D " +
                                                               std::to_string(int(seconds) + 2) + " sub > " + log + " 2>&1"});
  std::this_thread::sleep_for(300ms);
  run_capture("ddsperf -i " + d + " -D " + std::to_string(int(seconds)) + " pub size " + std::to_string(size) + " 2>&1");
  waitpid(sub, nullptr, 0);
  std::vector<double> rates;
  std::istringstream in(run_capture("cat " + log));
  std::remove(log.c_str());
  std::string line;
  while (std::getline(in, line)) {
    const double r = field(line, " rate ");
    if (r > 0) rates.push_back(r);
  }
  DdsperfResult res;
  if (rates.size() > 2) rates.erase(rates.begin());  // first second: discovery
  if (rates.empty()) return res;
  std::sort(rates.begin(), rates.end());
  res.rate_ks = rates[rates.size() / 2];
  res.ok = true;
  return res;
}

// immediate = false: callbacks on executor threads (the default, one thread hop per message, as ddsperf's
// waitset mode); true: Immediate callback group, callbacks on Cyclone's receive thread (as ddsperf's
// default listener mode).
void dds_rtt(const std::string& self, std::size_t size, double seconds, bool immediate) {
  cairn::Executor exec;
  cairn::Node node(opts("bench_ping", exec));
  cairn::QoS q;
  q.keep_last(1);
  auto pub = node.create_publisher<Image>("bench/ping", q);
  std::mutex mu;
  std::condition_variable cv;
  bool got = false;
  std::unique_ptr<Image> back;
  std::vector<double> half_rtt;
  half_rtt.reserve(1 << 20);
  // Immediate mode, as ddsperf's listener-mode ping: the callback that receives a pong sends the next ping
  // right there on Cyclone's receive thread (no thread wakes up on the ping side).
  std::atomic<bool> chain{false}, record{false};
  std::atomic<long> rounds{0};
  Clock::time_point t0;  // written and read by the receive thread only while chaining
  auto group = node.create_callback_group(immediate ? cairn::CallbackGroup::Type::Immediate
                                                    : cairn::CallbackGroup::Type::MutuallyExclusive);
  auto sub = node.create_subscription<Image>(
      "bench/pong", q,
      [&](std::unique_ptr<Image> m) {
        if (chain.load(std::memory_order_acquire)) {
          const auto now = Clock::now();
          if (record.load(std::memory_order_relaxed)) {
            half_rtt.push_back(std::chrono::duration<double, std::nano>(now - t0).count() / 2);
          }
          rounds.fetch_add(1, std::memory_order_relaxed);
          t0 = Clock::now();
          pub->publish(std::move(m));
          return;
        }
        std::lock_guard l(mu);
        back = std::move(m);
        got = true;
        cv.notify_one();
      },
      group);
  const pid_t pong = cairn::spawn_process({self, "pong", immediate ? "immediate" : "executor"});
  exec.spin_until([&] { return pub->inter_process_subscription_count() > 0 && sub->publisher_count_inter_process() > 0; }, 20s);
  auto msg = std::make_unique<Image>();
  msg->data.resize(size);
  const auto run = [&](double secs, bool rec) {
    const auto end = Clock::now() + std::chrono::milliseconds(int64_t(secs * 1000));
    while (Clock::now() < end) {
      {
        std::lock_guard l(mu);
        got = false;
      }
      const auto t0 = Clock::now();
      pub->publish(std::move(msg));
      if (!exec.spin_until([&] { return got; }, 2s)) {  // lost: re-create and go on
        msg = std::make_unique<Image>();
        msg->data.resize(size);
        continue;
      }
      if (rec) half_rtt.push_back(ns_since(t0) / 2);
      std::lock_guard l(mu);
      msg = std::move(back);
    }
  };
  const auto run_chained = [&](double secs, bool rec) {
    record.store(rec);
    const auto end = Clock::now() + std::chrono::milliseconds(int64_t(secs * 1000));
    long seen = rounds.load();
    auto progress = Clock::now() - 1h;
    while (Clock::now() < end) {
      const long r = rounds.load();
      if (r != seen) {
        progress = Clock::now();
      } else if (Clock::now() - progress > 1s) {  // nothing came back (start, or a lost sample): (re)start the chain
        chain.store(false);
        exec.spin_for(50ms);  // a late pong lands in `back`, not in the chain
        auto m = std::make_unique<Image>();
        m->data.resize(size);
        t0 = Clock::now();
        chain.store(true, std::memory_order_release);
        pub->publish(std::move(m));
        progress = Clock::now();
      }
      seen = r;
      std::this_thread::sleep_for(100ms);
    }
    chain.store(false);
    record.store(false);
    exec.spin_for(50ms);  // let the last round trip finish before the vector is read
  };
  if (immediate) {
    run_chained(1.0, false);
    half_rtt.clear();
    run_chained(seconds, true);
  } else {
    run(1.0, false);
    run(seconds, true);
  }
  cairn::stop_processes({pong});
  const auto s = stats(half_rtt);
  const std::string mode = immediate ? "listener" : "waitset";
  const auto base = ddsperf_ping(node.context().domain_id(), size, seconds, mode);
  std::printf(
      "{\"case\":\"dds_rtt_%s\",\"size\":\"%s\",\"p50_us\":%.2f,\"p99_us\":%.2f,\"max_us\":%.1f,\"samples\":%zu,"
      "\"baseline\":\"ddsperf ping/pong %s\",\"baseline_p50_us\":%.2f,\"baseline_p99_us\":%.2f,\"ratio_p50\":%.3f,"
      "\"goal\":\"ratio_p50<=1.10\"}\n",
      immediate ? "immediate" : "executor", size_name(size).c_str(), s.p50 / 1000, s.p99 / 1000, s.max / 1000, s.n,
      mode.c_str(), base.p50_us, base.p99_us, base.ok && base.p50_us > 0 ? (s.p50 / 1000) / base.p50_us : 0.0);
  std::fflush(stdout);
}

// batching: the publisher packs samples into few datagrams (QoS::batching), as ddsperf's pub does (it turns
// on Cyclone's write batching); without it every sample is its own datagram (cairn's default).
void dds_throughput(const std::string& self, std::size_t size, double seconds, bool batching) {
  cairn::Executor exec;
  cairn::Node node(opts("bench_flood", exec));
  cairn::QoS q;
  q.keep_all();
  q.batching = batching;
  auto pub = node.create_publisher<Image>("bench/flood", q);
  const std::string log = "/tmp/cairn_bench_sink_" + std::to_string(getpid()) + ".txt";
  const pid_t sink = cairn::spawn_process({"/bin/sh", "-c", "exec " + self + " sink " + std::to_string(seconds + 2) +
                                                                " > " + log});
  exec.spin_until([&] { return pub->inter_process_subscription_count() > 0; }, 20s);
  const auto end = Clock::now() + std::chrono::milliseconds(int64_t(seconds * 1000));
  Image m;
  m.data.resize(size);
  while (Clock::now() < end) pub->publish(m);  // const& with no local subscriber: serialized, not copied
  pub->flush();
  int st;
  waitpid(sink, &st, 0);
  long count = 0;
  double dt = 0;
  std::istringstream in(run_capture("cat " + log));
  std::remove(log.c_str());
  in >> count >> dt;
  const double rate = dt > 0 ? count / dt / 1000 : 0;
  const auto base = ddsperf_throughput(node.context().domain_id(), size, seconds);
  std::printf(
      "{\"case\":\"dds_throughput%s\",\"size\":\"%s\",\"kS_per_s\":%.1f,\"received\":%ld,\"baseline\":\"ddsperf pub/sub\","
      "\"baseline_kS_per_s\":%.1f,\"ratio\":%.3f,\"goal\":\"%s\"}\n",
      batching ? "" : "_unbatched", size_name(size).c_str(), rate, count, base.rate_ks, base.ok && base.rate_ks > 0 ? rate / base.rate_ks : 0.0,
      batching ? "ratio>=0.8" : "none: information (ddsperf pub batches; one datagram per sample here)");
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  const std::string mode = argc > 1 ? argv[1] : "";
  if (mode == "pong") return pong_main(argc > 2 && std::string(argv[2]) == "immediate");
  if (mode == "sink") return sink_main(argc > 2 ? std::atof(argv[2]) : 5.0);
  if (mode != "ipc") {
    std::cerr << "usage: cairn bench ipc [--quick] [--only same_thread|cross_thread|dds_rtt|dds_throughput|dispatch|idle|"
                 "component_load|respawn|mixed]\n";
    return 2;
  }
  bool quick = false;
  std::string only;
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--quick") {
      quick = true;
    } else if (a == "--only" && i + 1 < argc) {
      only = argv[++i];
    } else {
      std::cerr << "cairn: bench: unknown argument '" << a << "'\n";
      return 2;
    }
  }
  static const std::vector<std::string> kCases = {"same_thread", "cross_thread", "dds_rtt", "dds_throughput",
                                                 "dispatch", "idle", "component_load", "respawn", "mixed"};
  if (!only.empty() && std::find(kCases.begin(), kCases.end(), only) == kCases.end()) {
    std::cerr << "cairn: bench: --only: unknown case '" << only << "'\n";
    return 2;
  }
  if (!std::getenv("CYCLONEDDS_URI")) {
    std::cerr << "cairn: bench: set CYCLONEDDS_URI first (source scripts/env.sh: loopback only)\n";
    return 2;
  }
  const std::string self = cairn::self_executable();
  const double secs = quick ? 2 : 5;
  auto want = [&](const char* c) { return only.empty() || only == c; };
  if (want("same_thread")) {
    same_thread(1024, quick ? 20000 : 200000);
    same_thread(1 << 20, quick ? 2000 : 20000);
  }
  if (want("cross_thread")) cross_thread(quick ? 2000 : 20000);
  if (want("dds_rtt")) {
    for (bool immediate : {false, true}) {
      for (std::size_t s : {std::size_t(12), std::size_t(1024), std::size_t(64 << 10), std::size_t(1 << 20)}) {
        dds_rtt(self, s, secs, immediate);
      }
    }
  }
  if (want("dds_throughput")) {
    dds_throughput(self, 1024, secs, true);
    dds_throughput(self, 1024, secs, false);
  }
  if (want("dispatch")) dispatch(secs, 10000.0);
  if (want("idle")) idle(2.0);
  if (want("component_load")) component_load(quick ? 20 : 100);
  if (want("respawn")) respawn(self, quick ? 3 : 5);
  if (want("mixed")) mixed(self, quick ? 2000 : 10000);
  return 0;
}
