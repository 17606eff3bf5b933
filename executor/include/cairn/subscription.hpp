#ifndef CAIRN_SUBSCRIPTION_HPP
#define CAIRN_SUBSCRIPTION_HPP

#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <type_traits>
#include <variant>

#include "cairn/dds.hpp"
#include "cairn/executor.hpp"
#include "cairn/intra_process.hpp"
#include "cairn/logging.hpp"
#include "cairn/msgs/type_support.hpp"

namespace cairn {

class SubscriptionBase : public Executable {
 public:
  using Executable::Executable;
  const std::string& topic() const { return topic_; }
  const QoS& qos() const { return qos_; }
  virtual void shutdown() = 0;

 protected:
  std::string topic_;
  QoS qos_;
};

/// A subscription's callback may take the message as std::unique_ptr<T> (it owns it and may mutate it),
/// std::shared_ptr<const T> or const T& (it shares it), each optionally followed by const MessageInfo&.
template <class T>
class Subscription : public SubscriptionBase, public IntraSink<T> {
 public:
  using OwnedCb = std::function<void(std::unique_ptr<T>, const MessageInfo&)>;
  using SharedCb = std::function<void(std::shared_ptr<const T>, const MessageInfo&)>;
  using RefCb = std::function<void(const T&, const MessageInfo&)>;
  using Callback = std::variant<OwnedCb, SharedCb, RefCb>;

  template <class F>
  static Callback make_callback(F&& f) {
    using SP = std::shared_ptr<const T>;
    using UP = std::unique_ptr<T>;
    if constexpr (std::is_invocable_v<F&, SP, const MessageInfo&>) {
      return SharedCb(std::forward<F>(f));
    } else if constexpr (std::is_invocable_v<F&, SP>) {
      return SharedCb([f = std::forward<F>(f)](SP m, const MessageInfo&) mutable { f(std::move(m)); });
    } else if constexpr (std::is_invocable_v<F&, UP, const MessageInfo&>) {
      return OwnedCb(std::forward<F>(f));
    } else if constexpr (std::is_invocable_v<F&, UP>) {
      return OwnedCb([f = std::forward<F>(f)](UP m, const MessageInfo&) mutable { f(std::move(m)); });
    } else if constexpr (std::is_invocable_v<F&, const T&, const MessageInfo&>) {
      return RefCb(std::forward<F>(f));
    } else if constexpr (std::is_invocable_v<F&, const T&>) {
      return RefCb([f = std::forward<F>(f)](const T& m, const MessageInfo&) mutable { f(m); });
    } else {
      static_assert(sizeof(F) == 0, "subscription callback must take unique_ptr<T>, shared_ptr<const T> or const T&");
    }
  }

  Subscription(std::shared_ptr<CallbackGroup> group, Executor* exec, std::string topic, QoS qos, Callback cb,
               std::shared_ptr<Clock> clock, Logger logger)
      : SubscriptionBase(std::move(group)), exec_(exec), cb_(std::move(cb)), clock_(std::move(clock)),
        logger_(std::move(logger)) {
    topic_ = std::move(topic);
    qos_ = qos;
  }

  /// Connects the intra-process and DDS legs (after construction: they need shared_from_this).
  void connect(std::shared_ptr<Channel<T>> channel, Context* ctx, bool dds, const DdsEndpointOptions& opts) {
    channel_ = std::move(channel);
    auto self = std::static_pointer_cast<Subscription<T>>(shared_from_this());
    if (channel_) channel_->add(self, qos_.durability == QoS::Durability::TransientLocal);
    if (!dds || !ctx) return;
    try {
      connect_dds(self, *ctx, opts);
    } catch (...) {
      // e.g. DDS refused the topic name: the channel must not keep (and deliver to) a subscription that was
      // never handed out, nor keep it alive through the channel <-> subscription reference cycle
      if (channel_) channel_->remove(this);
      channel_.reset();
      throw;
    }
  }

  void shutdown() override {
    disable();
    if (channel_) channel_->remove(this);
    reader_raw_.store(nullptr);
    reader_.reset();
  }

  bool wants_ownership() const override { return std::holds_alternative<OwnedCb>(cb_); }

  void deliver_owned(std::unique_ptr<T> msg, const MessageInfo& info) override { deliver(Item{std::move(msg), info}); }
  void deliver_shared(std::shared_ptr<const T> msg, const MessageInfo& info) override {
    deliver(Item{std::move(msg), info});
  }

  std::size_t publisher_count_inter_process() const { return reader_ ? reader_->matched() : 0; }
  uint64_t dropped() const { return dropped_; }
  /// Samples from other processes dropped because they did not decode (malformed CDR).
  uint64_t dds_rejected() const {
    const DdsReader* r = reader_raw_.load(std::memory_order_acquire);
    return r ? r->rejected() : 0;
  }

 protected:
  void execute() override {
    Item item;
    bool have = false;
    {
      std::lock_guard l(mu_);
      if (!queue_.empty()) {
        item = std::move(queue_.front());
        queue_.pop_front();
        have = true;
      }
    }
    if (have) {
      invoke(std::move(item));
      return;
    }
    // DDS leg: drain what has arrived; arrivals from now on schedule a new run
    dds_pending_.store(false);
    drain_dds();
  }

  /// Takes and dispatches everything that has arrived (one wake-up serves a whole burst). Samples are
  /// decoded straight into the message the callback gets; that message is reused for the next sample when
  /// the callback cannot keep it (const T&) or did not keep it (shared_ptr no longer shared; a weak_ptr
  /// does not count as keeping it), so a steady stream costs no allocation per sample. Owning callbacks get
  /// a fresh object each time.
  void drain_dds() {
    DdsReader* reader = reader_raw_.load(std::memory_order_acquire);
    if (!reader) return;
    MessageInfo info;
    if (auto* ref = std::get_if<RefCb>(&cb_)) {
      if (!reuse_) reuse_ = std::make_shared<T>();
      while (reader->take(reuse_.get(), info)) {
        info.received_timestamp_ns = clock_->now().ns;
        call_guarded([&] { (*ref)(*reuse_, info); });
      }
    } else if (auto* shared = std::get_if<SharedCb>(&cb_)) {
      for (;;) {
        if (!reuse_ || reuse_.use_count() != 1) reuse_ = std::make_shared<T>();
        if (!reader->take(reuse_.get(), info)) break;
        info.received_timestamp_ns = clock_->now().ns;
        call_guarded([&] { (*shared)(reuse_, info); });
      }
    } else {
      auto& owned = std::get<OwnedCb>(cb_);
      for (;;) {
        if (!spare_) spare_ = std::make_unique<T>();
        if (!reader->take(spare_.get(), info)) break;
        info.received_timestamp_ns = clock_->now().ns;
        call_guarded([&] { owned(std::move(spare_), info); });
      }
    }
  }

  bool immediate() const { return group() && group()->type() == CallbackGroup::Type::Immediate; }

 private:
  // The DDS leg of connect().
  void connect_dds(const std::shared_ptr<Subscription<T>>& self, Context& ctx, const DdsEndpointOptions& opts) {
    std::weak_ptr<Subscription<T>> weak = self;
    reader_ = std::make_unique<DdsReader>(ctx, dds_topic_name(topic_), msgs::type_support<T>(), qos_, opts,
                                          [weak](DdsReader& r) {
                                            auto s = weak.lock();
                                            if (!s) return;
                                            if (s->immediate()) {  // on Cyclone's receive thread
                                              s->guarded([&] { s->drain_dds(); });
                                              return;
                                            }
                                            r.prefetch();  // the woken thread finds them in our queue
                                            // one wake-up drains everything that has arrived, so a burst
                                            // costs one queue entry, not one per sample
                                            if (!s->dds_pending_.exchange(true)) s->exec_->schedule(s);
                                          });
    // The reader's first callbacks may have run before reader_ was set (and found nothing to drain):
    // publish the pointer, then make sure whatever arrived meanwhile is drained.
    reader_raw_.store(reader_.get(), std::memory_order_release);
    if (immediate()) {
      guarded([&] { drain_dds(); });
    } else {
      dds_pending_.store(true);
      exec_->schedule(self);
    }
  }

  struct Item {
    std::variant<std::unique_ptr<T>, std::shared_ptr<const T>> msg;
    MessageInfo info;
  };

  void deliver(Item&& item) {
    if (!enabled()) return;
    if (immediate()) {
      guarded([&] { invoke(std::move(item)); });
      return;
    }
    bool idle;
    {
      std::lock_guard l(mu_);
      idle = queue_.empty();
    }
    if (idle && exec_->can_run_inline(group())) {
      // Same executor thread: run right here, no queue, no wake-up (the zero-copy fast path).
      exec_->run_inline([&] { guarded([&] { invoke(std::move(item)); }); });
      return;
    }
    {
      std::lock_guard l(mu_);
      if (qos_.history == QoS::History::KeepLast && static_cast<int>(queue_.size()) >= std::max(qos_.depth, 1)) {
        queue_.pop_front();  // keep-last: the oldest goes; its wake-up serves the newest
        queue_.push_back(std::move(item));
        ++dropped_;
        return;
      }
      queue_.push_back(std::move(item));
    }
    exec_->schedule(shared_from_this());
  }

  template <class F>
  void call_guarded(F&& f) {
    try {
      f();
    } catch (const std::exception& e) {
      CAIRN_ERROR(logger_, "callback on " << topic_ << " threw: " << e.what());
    }
  }

  void invoke(Item&& item) {
    item.info.received_timestamp_ns = clock_->now().ns;
    try {
      std::visit(
          [&](auto& cb) {
            using CB = std::decay_t<decltype(cb)>;
            auto* up = std::get_if<std::unique_ptr<T>>(&item.msg);
            if constexpr (std::is_same_v<CB, OwnedCb>) {
              if (up) {
                cb(std::move(*up), item.info);
              } else {  // a shared message to an owner that may mutate it: the one copy
                cb(std::make_unique<T>(*std::get<std::shared_ptr<const T>>(item.msg)), item.info);
              }
            } else if constexpr (std::is_same_v<CB, SharedCb>) {
              if (up) {
                cb(std::shared_ptr<const T>(std::move(*up)), item.info);
              } else {
                cb(std::get<std::shared_ptr<const T>>(item.msg), item.info);
              }
            } else {
              cb(up ? **up : *std::get<std::shared_ptr<const T>>(item.msg), item.info);
            }
          },
          cb_);
    } catch (const std::exception& e) {
      CAIRN_ERROR(logger_, "callback on " << topic_ << " threw: " << e.what());
    }
  }

  Executor* exec_;
  Callback cb_;
  std::shared_ptr<Clock> clock_;
  Logger logger_;
  std::shared_ptr<Channel<T>> channel_;
  std::unique_ptr<DdsReader> reader_;
  std::mutex mu_;
  std::deque<Item> queue_;
  uint64_t dropped_ = 0;
  std::atomic<bool> dds_pending_{false};
  std::atomic<DdsReader*> reader_raw_{nullptr};  // what callbacks on other threads read
  std::shared_ptr<T> reuse_;  // DDS leg: the message decoded into, reused while nobody else holds it
  std::unique_ptr<T> spare_;  // DDS leg, owning callbacks: decoded into, then handed over
};

}  // namespace cairn

#endif  // CAIRN_SUBSCRIPTION_HPP
