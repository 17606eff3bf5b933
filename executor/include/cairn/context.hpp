// The process-wide runtime context: one DDS participant, the intra-process channels, the ROS clock and
// the registry of nodes living in this process.
#ifndef CAIRN_CONTEXT_HPP
#define CAIRN_CONTEXT_HPP

#include <atomic>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "cairn/clock.hpp"
#include "cairn/message_info.hpp"
#include "cairn/qos.hpp"

namespace cairn {

namespace msgs {
struct TypeSupport;
}
class IntraProcessManager;

/// What a node declared (recorded always; in a dry-run context this is all that happens).
struct EndpointRecord {
  enum class Kind { Publisher, Subscription, ServiceServer, ServiceClient };
  Kind kind;
  std::string node;   ///< fully qualified node name
  std::string topic;  ///< resolved name, e.g. /chatter
  std::string type;   ///< ROS type name, e.g. std_msgs/msg/String
  QoS qos;
};

struct ContextOptions {
  int domain_id = -1;    ///< -1: $CAIRN_DOMAIN_ID, else $ROS_DOMAIN_ID, else 0
  bool dry_run = false;  ///< validation only: nodes record what they declare, nothing touches DDS
};

class Context {
 public:
  static std::shared_ptr<Context> create(ContextOptions opts = {});
  /// The context of this process, created on first use.
  static std::shared_ptr<Context> default_context();
  ~Context();
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;

  bool dry_run() const { return opts_.dry_run; }
  int domain_id() const { return domain_id_; }
  /// The DDS participant (created on first use). Throws std::runtime_error if DDS cannot start.
  int32_t participant();
  /// The DDS topic for `dds_topic_name` with type `ts`; created once per process. Throws if the same
  /// name is already used with another type in this process.
  int32_t topic(const std::string& dds_topic_name, const msgs::TypeSupport& ts);

  IntraProcessManager& intra() { return *intra_; }
  const std::shared_ptr<Clock>& ros_clock() const { return ros_clock_; }
  /// Process-unique ids (publishers without a DDS writer, clients, ...).
  uint64_t next_id() { return next_id_.fetch_add(1); }
  Gid make_local_gid();

  void record(const EndpointRecord& r);
  std::vector<EndpointRecord> records() const;
  void add_node(const std::string& fqn);
  void remove_node(const std::string& fqn);
  std::vector<std::string> nodes() const;

  /// Parameters given to a node that it never declared (reported by dry-run nodes on destruction).
  struct UnusedParameters {
    std::string node;
    std::vector<std::string> names;
    std::vector<std::string> declared;
  };
  void note_unused_parameters(UnusedParameters u);
  std::vector<UnusedParameters> unused_parameters() const;

 private:
  explicit Context(ContextOptions opts);
  ContextOptions opts_;
  int domain_id_ = 0;
  std::mutex mu_;
  int32_t participant_ = 0;
  std::map<std::string, std::pair<int32_t, std::string>> topics_;  // name -> (entity, dds type name)
  std::unique_ptr<IntraProcessManager> intra_;
  std::shared_ptr<Clock> ros_clock_;
  std::atomic<uint64_t> next_id_{1};
  mutable std::mutex rec_mu_;
  std::vector<EndpointRecord> records_;
  std::vector<std::string> nodes_;
  std::vector<UnusedParameters> unused_;
};

/// Domain id from the environment ($CAIRN_DOMAIN_ID, $ROS_DOMAIN_ID, else 0).
int domain_id_from_env();

}  // namespace cairn

#endif  // CAIRN_CONTEXT_HPP
