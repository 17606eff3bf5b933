#ifndef CAIRN_PUBLISHER_HPP
#define CAIRN_PUBLISHER_HPP

#include <atomic>
#include <chrono>
#include <memory>
#include <string>

#include "cairn/clock.hpp"
#include "cairn/dds.hpp"
#include "cairn/intra_process.hpp"
#include "cairn/logging.hpp"
#include "cairn/msgs/type_support.hpp"

namespace cairn {

class PublisherBase {
 public:
  virtual ~PublisherBase() = default;
  const std::string& topic() const { return topic_; }
  const QoS& qos() const { return qos_; }

 protected:
  std::string topic_;
  QoS qos_;
};

/// Publishes T on a topic: intra-process subscriptions get the object itself (see intra_process.hpp),
/// subscriptions in other processes get it over DDS (topic rt/<name>, type pkg::msg::dds_::T_).
template <class T>
class Publisher : public PublisherBase {
 public:
  /// `channel` null: no intra-process delivery; `dds` null: no DDS leg (dry run or intra-only).
  Publisher(std::string topic, QoS qos, std::shared_ptr<Channel<T>> channel, std::unique_ptr<DdsWriter> dds, Gid gid,
            std::shared_ptr<Clock> clock, Logger logger)
      : channel_(std::move(channel)), dds_(std::move(dds)), gid_(gid), clock_(std::move(clock)),
        logger_(std::move(logger)) {
    topic_ = std::move(topic);
    qos_ = qos;
    latch_ = qos_.durability == QoS::Durability::TransientLocal ? std::max(qos_.depth, 1) : 0;
  }

  /// Hands the message over. Same-process owners receive this very object.
  void publish(std::unique_ptr<T> msg) {
    MessageInfo info;
    info.source_timestamp_ns = clock_->now().ns;
    info.publisher_gid = gid_;
    info.sequence_number = ++seq_;
    info.from_intra_process = true;
    // DDS readers of this process are ignored (ignore_local), so they never see it twice. Transient-local writers
    // always write so that late joiners in other processes get the history. The channel calls the DDS leg after
    // delivering to sharing local subscriptions (their latency does not include the write) and before delivering
    // to an owning one (which may take this very object).
    auto write_dds = [&](const T& m) { write_to_dds(m, info.source_timestamp_ns); };
    if (channel_) {
      channel_->publish(std::move(msg), info, latch_, write_dds);
    } else {
      write_dds(*msg);
    }
  }
  /// Publishes `msg`: serialized from the reference for other processes; copied once only if a subscription
  /// in this process wants it (prefer the unique_ptr overload when there are local subscribers).
  void publish(const T& msg) {
    if (latch_ > 0 || (channel_ && channel_->count() > 0)) {  // latched: kept for late local joiners
      publish(std::make_unique<T>(msg));
      return;
    }
    ++seq_;
    write_to_dds(msg, clock_->now().ns);
  }

  /// Sends what a batching publisher (QoS::batching) has queued for other processes; a no-op otherwise.
  void flush() {
    if (dds_ && qos_.batching) dds_->flush();
  }

  std::size_t intra_process_subscription_count() const { return channel_ ? channel_->count() : 0; }
  std::size_t inter_process_subscription_count() const { return dds_ ? static_cast<std::size_t>(dds_->matched()) : 0; }
  std::size_t subscription_count() const { return intra_process_subscription_count() + inter_process_subscription_count(); }
  Gid gid() const { return gid_; }
  /// Waits until every matched reliable subscription in another process has acknowledged all messages published
  /// so far (DDS acknowledgment: in the reader's history), at most `timeout` (negative: no limit); true when all
  /// are acknowledged, also with no DDS leg or no reliable readers. Intra-process delivery is synchronous and
  /// needs no acknowledgment. Pacing a producer by its consumers (rclcpp: Publisher::wait_for_all_acked).
  bool wait_for_all_acked(std::chrono::nanoseconds timeout = std::chrono::nanoseconds(-1)) const {
    return !dds_ || dds_->wait_for_acks(timeout.count());
  }

 private:
  /// The DDS leg: written when another process listens, or always for transient local (late joiners).
  void write_to_dds(const T& m, int64_t stamp_ns) {
    if (!dds_ || (latch_ == 0 && dds_->matched() == 0)) return;
    try {
      dds_->write(&m, stamp_ns);
    } catch (const std::exception& e) {
      CAIRN_ERROR(logger_, "publish on " << topic_ << ": " << e.what());
    }
  }

  std::shared_ptr<Channel<T>> channel_;
  std::unique_ptr<DdsWriter> dds_;
  Gid gid_;
  std::shared_ptr<Clock> clock_;
  Logger logger_;
  std::atomic<uint64_t> seq_{0};
  int latch_ = 0;
};

}  // namespace cairn

#endif  // CAIRN_PUBLISHER_HPP
