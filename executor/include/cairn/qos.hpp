// QoS profiles, mapped 1:1 onto DDS QoS policies.
#ifndef CAIRN_QOS_HPP
#define CAIRN_QOS_HPP

#include <chrono>
#include <cstdint>
#include <optional>
#include <string>

struct dds_qos;

namespace cairn {

struct QoS {
  enum class History { KeepLast, KeepAll };
  enum class Reliability { Reliable, BestEffort };
  enum class Durability { Volatile, TransientLocal };
  enum class Liveliness { Automatic, ManualByTopic };

  History history = History::KeepLast;
  int depth = 10;
  Reliability reliability = Reliability::Reliable;
  Durability durability = Durability::Volatile;
  std::chrono::nanoseconds deadline{0};          ///< 0 = infinite
  std::chrono::nanoseconds lifespan{0};          ///< 0 = infinite
  Liveliness liveliness = Liveliness::Automatic;
  std::chrono::nanoseconds liveliness_lease{0};  ///< 0 = infinite
  /// Cyclone's write batching (Internal/WriteBatch, which Cyclone 0.10 only has per process; cairn turns it on
  /// for this one writer while creating it), publishers only: samples for other processes are packed into as
  /// few datagrams as possible and sent when a datagram is full or on Publisher::flush(). For high-rate
  /// streams (ddsperf's pub runs this way); the publisher must flush() at the end of each burst.
  bool batching = false;

  /// ROS 2 default: reliable, volatile, keep last 10.
  static QoS defaults() { return QoS{}; }
  /// ROS 2 SensorDataQoS: best effort, keep last 5.
  static QoS sensor_data();
  /// Latched topics (tf_static, maps, the graph): reliable, transient local, keep last 1.
  static QoS latched(int depth = 1);
  static QoS services();

  QoS& keep_last(int d) { history = History::KeepLast; depth = d; return *this; }
  QoS& keep_all() { history = History::KeepAll; return *this; }
  QoS& reliable() { reliability = Reliability::Reliable; return *this; }
  QoS& best_effort() { reliability = Reliability::BestEffort; return *this; }
  QoS& transient_local() { durability = Durability::TransientLocal; return *this; }
  QoS& durability_volatile() { durability = Durability::Volatile; return *this; }

  /// New DDS QoS object (caller deletes with dds_delete_qos).
  dds_qos* to_dds() const;
  static QoS from_dds(const dds_qos* q);
  std::string to_string() const;
  bool operator==(const QoS&) const = default;
};

/// Partial QoS from a launch spec or the command line; unset fields keep the code's choice.
struct QoSOverride {
  std::optional<QoS::History> history;
  std::optional<int> depth;
  std::optional<QoS::Reliability> reliability;
  std::optional<QoS::Durability> durability;
  std::optional<std::chrono::nanoseconds> deadline;
  std::optional<std::chrono::nanoseconds> lifespan;
  void apply(QoS& q) const;
  /// Sets one field from text: key is history|depth|reliability|durability|deadline|lifespan (seconds).
  /// Returns an error message for an unknown key or value.
  std::optional<std::string> set(const std::string& key, const std::string& value);
  bool empty() const { return !history && !depth && !reliability && !durability && !deadline && !lifespan; }
};

/// Why a publisher with `pub` QoS never delivers to a subscription with `sub` QoS (DDS request/offered
/// rules), or nullopt when they match.
std::optional<std::string> qos_incompatibility(const QoS& pub, const QoS& sub);

}  // namespace cairn

#endif  // CAIRN_QOS_HPP
