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
#include <vector>

#include "cairn/message_info.hpp"
#include "cairn/qos.hpp"

namespace cairn {

class Context;
}  // namespace cairn
struct ddsi_serdata;
namespace cairn {
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
  /// Serializes `cpp` (a C++ message of the writer's type, XCDR1 straight from the C++ struct) and writes
  /// it. Throws on DDS errors and on messages that cannot be serialized (bounded sequence too long).
  void write(const void* cpp, int64_t source_timestamp_ns);
  /// Sends what a batching writer (QoS::batching) has queued.
  void flush();
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
  /// Takes the next valid sample and decodes it straight into `cpp_out` (a C++ message of the reader's
  /// type; its buffers are reused when it is reused); false if none. Malformed samples are dropped and
  /// logged. One consumer at a time (as the subscription guarantees); safe against a concurrent prefetch().
  bool take(void* cpp_out, MessageInfo& info);
  /// Moves the serialized samples that have arrived out of Cyclone's reader into this reader's own queue
  /// (references, no copy), where take() finds them. Called from the data-available listener, so that the
  /// thread woken up to take() never waits for Cyclone's reader while the listener is still running.
  void prefetch();
  int matched() const;
  int32_t entity() const { return reader_; }
  /// Samples dropped because they did not decode (malformed CDR).
  uint64_t rejected() const { return rejected_.load(std::memory_order_relaxed); }

 private:
  struct Publication {
    Gid gid{};
    uint64_t received = 0;
  };
  struct Queued {
    ::ddsi_serdata* data = nullptr;
    bool valid = false;  // false: a dispose/unregister notification
    int64_t source_timestamp = 0;
    uint64_t publication_handle = 0;
  };
  void fill_locked();
  Queued pop_locked();
  void clear_queue();
  Publication& publication(uint64_t publication_handle);
  const msgs::TypeSupport& ts_;
  DataCallback on_data_;
  int32_t reader_ = 0;
  std::mutex q_mu_;
  std::vector<Queued> ring_;  // serialized samples taken from Cyclone, oldest at q_head_
  std::size_t q_head_ = 0, q_size_ = 0, max_queued_ = SIZE_MAX;
  std::map<uint64_t, Publication> pubs_;  // by publication handle (consumer side only)
  std::pair<const uint64_t, Publication>* last_pub_ = nullptr;
  std::atomic<uint64_t> rejected_{0};
};

/// Creates a topic whose samples are C++ messages of `ts`, serialized by cairn's own ddsi_sertype (XCDR1
/// straight from/into the C++ struct; same bytes as idlc's serializer). Returns the entity or a DDS error.
int32_t create_dds_topic(int32_t participant, const std::string& name, const msgs::TypeSupport& ts);

/// "rt/<name>" for a resolved topic name "/<name>" (ROS 2 convention).
std::string dds_topic_name(const std::string& resolved);

}  // namespace cairn

#endif  // CAIRN_DDS_HPP
