// The demo pair, as ROS 2's demo_nodes_cpp: Talker publishes std_msgs/String "Hello World: N" on `chatter`,
// Listener logs what it hears. Used by the README, smoke tests and the zero-copy integration tests.
#ifndef CAIRN_DEMO_TALKER_LISTENER_HPP
#define CAIRN_DEMO_TALKER_LISTENER_HPP

#include <atomic>
#include <string>

#include "cairn/node.hpp"
#include "std_msgs/msg/String.hpp"

namespace cairn_demo {

class Talker : public cairn::Node {
 public:
  explicit Talker(const cairn::NodeOptions& opts);
  uint64_t published() const { return count_; }
  /// Address of the last message handed to publish() (tests assert the zero-copy path with it).
  const void* last_published_address() const { return last_address_; }

 private:
  std::shared_ptr<cairn::Publisher<std_msgs::msg::String>> pub_;
  std::shared_ptr<cairn::TimerBase> timer_;
  std::string text_;
  std::atomic<uint64_t> count_{0};
  std::atomic<const void*> last_address_{nullptr};
};

class Listener : public cairn::Node {
 public:
  explicit Listener(const cairn::NodeOptions& opts);
  uint64_t heard() const { return heard_; }
  uint64_t heard_intra_process() const { return intra_; }
  const void* last_received_address() const { return last_address_; }

 private:
  std::shared_ptr<cairn::Subscription<std_msgs::msg::String>> sub_;
  std::atomic<uint64_t> heard_{0}, intra_{0};
  std::atomic<const void*> last_address_{nullptr};
};

}  // namespace cairn_demo

#endif  // CAIRN_DEMO_TALKER_LISTENER_HPP
