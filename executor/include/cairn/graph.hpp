// The DDS graph as seen through the built-in topics (DCPSParticipant, DCPSPublication, DCPSSubscription):
// what the CLI lists. It sees every DDS participant on the domain, cairn or not.
#ifndef CAIRN_GRAPH_HPP
#define CAIRN_GRAPH_HPP

#include <chrono>
#include <optional>
#include <string>
#include <vector>

#include "cairn/context.hpp"
#include "cairn/message_info.hpp"
#include "cairn/qos.hpp"

namespace cairn {

struct GraphEndpoint {
  bool is_publisher = false;
  std::string dds_topic;  ///< e.g. rt/chatter
  std::string dds_type;   ///< e.g. std_msgs::msg::dds_::String_
  std::string node;       ///< fully qualified cairn node name, empty for non-cairn endpoints
  Gid guid{}, participant{};
  QoS qos;
};

struct GraphParticipant {
  Gid guid{};
  bool cairn = false;  ///< a cairn process (USER_DATA "cairn:pid=…")
};

class GraphView {
 public:
  explicit GraphView(Context& ctx);
  ~GraphView();
  /// Alive endpoints of other participants (this process's own endpoints are left out).
  std::vector<GraphEndpoint> endpoints();
  /// Alive participants other than this one.
  std::vector<GraphParticipant> participants();
  /// Waits until the set of endpoints has not changed for `settle` (at most `timeout`).
  void wait_for_discovery(std::chrono::milliseconds settle, std::chrono::milliseconds timeout);

 private:
  Context& ctx_;
  int32_t pub_reader_ = 0, sub_reader_ = 0, part_reader_ = 0;
  Gid self_{};
};

/// "rt/chatter" -> "/chatter"; other prefixes (rq/, rr/) are left as they are.
std::string ros_topic_name(const std::string& dds_topic);
/// "std_msgs::msg::dds_::String_" -> "std_msgs/msg/String" (unchanged if not of that shape).
std::string ros_type_name(const std::string& dds_type);
std::string gid_to_string(const Gid& g);

}  // namespace cairn

#endif  // CAIRN_GRAPH_HPP
