// Components that misbehave on purpose, for the container, launch and supervision tests.
#include <chrono>
#include <csignal>
#include <filesystem>
#include <stdexcept>
#include <thread>

#include "cairn/component.hpp"
#include "sensor_msgs/msg/Image.hpp"
#include "std_msgs/msg/String.hpp"

namespace cairn_test {

/// Throws from its constructor.
class Throws : public cairn::Node {
 public:
  explicit Throws(const cairn::NodeOptions& o) : cairn::Node(o) { throw std::runtime_error("deliberate failure"); }
};

/// Takes `seconds` to construct (default 30): the container's load timeout must catch it. With `while_file`
/// set it hangs only while that file exists (at most `seconds`), so a test can make a reload hang and not the
/// first load.
class Hangs : public cairn::Node {
 public:
  explicit Hangs(const cairn::NodeOptions& o) : cairn::Node(o) {
    const double s = declare_parameter<double>("seconds", 30.0);
    const std::string file = declare_parameter<std::string>("while_file", "");
    if (dry_run()) return;
    const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(s);
    if (file.empty()) std::this_thread::sleep_until(until);
    while (!file.empty() && std::filesystem::exists(file) && std::chrono::steady_clock::now() < until) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  }
};

/// Kills its process with SIGSEGV `crash_after` seconds after construction (supervision test).
class Crashes : public cairn::Node {
 public:
  explicit Crashes(const cairn::NodeOptions& o) : cairn::Node(o) {
    const double after = declare_parameter<double>("crash_after", 0.5, {"", 0.0, 60.0, false});
    timer_ = create_wall_timer(std::chrono::nanoseconds(int64_t(after * 1e9)), [] { std::raise(SIGSEGV); });
  }

 private:
  std::shared_ptr<cairn::TimerBase> timer_;
};

/// Publishes sensor_msgs/Image on `chatter` (a type clash with the demo Talker) with a best-effort QoS.
class ImagePublisher : public cairn::Node {
 public:
  explicit ImagePublisher(const cairn::NodeOptions& o) : cairn::Node(o) {
    pub_ = create_publisher<sensor_msgs::msg::Image>("chatter", cairn::QoS::sensor_data());
  }

 private:
  std::shared_ptr<cairn::Publisher<sensor_msgs::msg::Image>> pub_;
};

/// Publishes std_msgs/String best effort on `best_effort_chatter` (QoS mismatch with a reliable subscriber).
class BestEffortTalker : public cairn::Node {
 public:
  explicit BestEffortTalker(const cairn::NodeOptions& o) : cairn::Node(o) {
    pub_ = create_publisher<std_msgs::msg::String>("chatter", cairn::QoS::sensor_data());
  }

 private:
  std::shared_ptr<cairn::Publisher<std_msgs::msg::String>> pub_;
};

}  // namespace cairn_test

CAIRN_REGISTER_COMPONENT(cairn_test::Throws)
CAIRN_REGISTER_COMPONENT(cairn_test::Hangs)
CAIRN_REGISTER_COMPONENT(cairn_test::Crashes)
CAIRN_REGISTER_COMPONENT(cairn_test::ImagePublisher)
CAIRN_REGISTER_COMPONENT(cairn_test::BestEffortTalker)
