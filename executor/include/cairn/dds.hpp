// The DDS leg of publishers, subscriptions and services: type-erased over msgs::TypeSupport.
#ifndef CAIRN_DDS_HPP
#define CAIRN_DDS_HPP

#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>

#include "cairn/message_info.hpp"
#include "cairn/qos.hpp"

namespace cairn {

class Context;
namespace msgs {
struct TypeSupport;
}

/// Endpoint options beyond QoS.
struct DdsEndpointOptions {
  std::string node;          ///< fully qualified node name, advertised in the endpoint's USER_DATA
  bool ignore_local = true;  ///< ignore endpoints of this process (they are served intra-process)
};

class DdsWriter {
 public:
  DdsWriter(Context& ctx, const std::string& dds_topic, const msgs::TypeSupport& ts, const QoS& qos,
            const DdsEndpointOptions& opts);
  ~DdsWriter();
  DdsWriter(const DdsWriter&) = delete;
  DdsWriter& operator=(const DdsWriter&) = delete;
  /// Serializes `cpp` (a C++ message of the writer's type) and writes it. Throws on DDS errors.
  void write(const void* cpp, int64_t source_timestamp_ns);
  /// Number of matched readers (in other processes when ignore_local). Kept up to date by a
  /// publication-matched listener, so asking costs an atomic load (it is asked on every publish).
  int matched() const { return matched_.load(std::memory_order_relaxed); }
  /// Blocks until every matched reliable reader has acknowledged every sample written so far (dds_wait_for_acks:
  /// received into the reader's history, not necessarily taken) or `timeout_ns` passed (< 0: no limit).
  /// True when acknowledged (also with no reliable readers), false on timeout.
  bool wait_for_acks(int64_t timeout_ns) const;
  Gid guid() const { return guid_; }
  int32_t entity() const { return writer_; }

 private:
  const msgs::TypeSupport& ts_;
  int32_t writer_ = 0;
  Gid guid_{};
  std::atomic<int> matched_{0};
};

class DdsReader {
 public:
  using DataCallback = std::function<void(DdsReader&)>;
  /// `on_data` runs on a Cyclone thread whenever data arrives (and once at the end of construction, for
  /// data that arrived before the listener was attached); keep it short (schedule work).
  DdsReader(Context& ctx, const std::string& dds_topic, const msgs::TypeSupport& ts, const QoS& qos,
            const DdsEndpointOptions& opts, DataCallback on_data);
  ~DdsReader();
  DdsReader(const DdsReader&) = delete;
  DdsReader& operator=(const DdsReader&) = delete;
  /// Takes the next valid sample into `cpp_out` (a C++ message of the reader's type); false if none.
  /// Samples are taken from Cyclone in batches (one dds_take per kBatch samples), loaned, and converted
  /// one at a time. Not thread-safe (one consumer at a time, as the subscription guarantees).
  bool take(void* cpp_out, MessageInfo& info);
  int matched() const;
  int32_t entity() const { return reader_; }

 private:
  struct Batch;  // loaned samples of the last dds_take (src/dds.cpp)
  std::unique_ptr<Batch> batch_;
  void return_batch();
  Gid publisher_gid(uint64_t publication_handle);
  const msgs::TypeSupport& ts_;
  DataCallback on_data_;
  int32_t reader_ = 0;
  std::map<uint64_t, std::pair<Gid, uint64_t>> pubs_;  // publication handle -> (guid, reception count)
};

/// "rt/<name>" for a resolved topic name "/<name>" (ROS 2 convention).
std::string dds_topic_name(const std::string& resolved);

}  // namespace cairn

#endif  // CAIRN_DDS_HPP
