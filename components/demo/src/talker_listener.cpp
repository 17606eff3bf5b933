#include "cairn/demo/talker_listener.hpp"

#include "cairn/component.hpp"

namespace cairn_demo {

using std_msgs::msg::String;

Talker::Talker(const cairn::NodeOptions& opts) : cairn::Node(opts) {
  const double rate = declare_parameter<double>("rate_hz", 10.0, {"publishing rate", 0.001, 10000.0, false});
  text_ = declare_parameter<std::string>("text", "Hello World", {"message prefix", {}, {}, false});
  pub_ = create_publisher<String>("chatter", cairn::QoS{});
  timer_ = create_wall_timer(std::chrono::nanoseconds(static_cast<int64_t>(1e9 / rate)), [this] {
    auto msg = std::make_unique<String>();
    msg->data = text_ + ": " + std::to_string(++count_);
    CAIRN_INFO(logger(), "Publishing: '" << msg->data << "'");
    last_address_ = msg.get();
    pub_->publish(std::move(msg));
  });
}

Listener::Listener(const cairn::NodeOptions& opts) : cairn::Node(opts) {
  sub_ = create_subscription<String>("chatter", cairn::QoS{},
                                     [this](std::unique_ptr<String> msg, const cairn::MessageInfo& info) {
                                       last_address_ = msg.get();
                                       ++heard_;
                                       if (info.from_intra_process) ++intra_;
                                       CAIRN_INFO(logger(), "I heard: [" << msg->data << "]"
                                                                         << (info.from_intra_process ? " (intra-process)" : " (dds)"));
                                     });
}

}  // namespace cairn_demo

CAIRN_REGISTER_COMPONENT(cairn_demo::Talker)
CAIRN_REGISTER_COMPONENT(cairn_demo::Listener)
