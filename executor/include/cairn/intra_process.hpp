// Intra-process channels: messages between publishers and subscriptions of one process never leave
// the process and are never serialized.
//
// publish(std::unique_ptr<T>):
//   - one subscription that wants ownership, none sharing: it gets the very same object (0 copies);
//   - only sharing subscriptions: the object becomes one std::shared_ptr<const T> they all share (0 copies);
//   - owners and sharers mixed: sharers share the original, each owner gets a copy (1 copy with one owner).
//   - k owners and no sharers: k-1 copies, the last owner gets the original.
// Transient-local publishers keep their last `depth` messages (shared) for late-joining subscriptions.
#ifndef CAIRN_INTRA_PROCESS_HPP
#define CAIRN_INTRA_PROCESS_HPP

#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <typeindex>
#include <utility>
#include <vector>

#include "cairn/message_info.hpp"

namespace cairn {

template <class T>
class IntraSink {
 public:
  virtual ~IntraSink() = default;
  virtual bool wants_ownership() const = 0;
  virtual void deliver_owned(std::unique_ptr<T> msg, const MessageInfo& info) = 0;
  virtual void deliver_shared(std::shared_ptr<const T> msg, const MessageInfo& info) = 0;
};

class ChannelBase {
 public:
  ChannelBase(std::type_index t, std::string type_name) : type(t), type_name(std::move(type_name)) {}
  virtual ~ChannelBase() = default;
  const std::type_index type;
  const std::string type_name;
};

template <class T>
class Channel : public ChannelBase {
 public:
  using SinkList = std::vector<std::shared_ptr<IntraSink<T>>>;
  explicit Channel(std::string type_name) : ChannelBase(typeid(T), std::move(type_name)) {}

  /// Adds a subscription; replays latched messages to it when `wants_latched`.
  void add(const std::shared_ptr<IntraSink<T>>& s, bool wants_latched) {
    std::deque<std::shared_ptr<const T>> replay;
    {
      std::lock_guard l(mu_);
      auto next = std::make_shared<SinkList>(*sinks_);
      next->push_back(s);
      sinks_ = std::move(next);
      if (wants_latched) replay = latched_;
    }
    for (auto& m : replay) {
      MessageInfo info;
      info.from_intra_process = true;
      if (s->wants_ownership()) {
        s->deliver_owned(std::make_unique<T>(*m), info);
      } else {
        s->deliver_shared(m, info);
      }
    }
  }

  void remove(const IntraSink<T>* s) {
    std::lock_guard l(mu_);
    auto next = std::make_shared<SinkList>();
    for (auto& x : *sinks_) {
      if (x.get() != s) next->push_back(x);
    }
    sinks_ = std::move(next);
  }

  std::size_t count() const {
    std::lock_guard l(mu_);
    return sinks_->size();
  }

  /// Delivers `msg`; `latch_depth` > 0 keeps the last latch_depth messages for late joiners.
  void publish(std::unique_ptr<T> msg, const MessageInfo& info, int latch_depth = 0) {
    publish(std::move(msg), info, latch_depth, [](const T&) {});
  }

  /// Delivers `msg` and hands it to `also` (the publisher's DDS leg) while it is still valid: after the local
  /// deliveries when every subscription shares it (local latency then does not include the DDS write; readers on
  /// other threads only read the object meanwhile), before them when a subscription takes ownership (the object
  /// may be gone afterwards) or there is none.
  template <class F>
  void publish(std::unique_ptr<T> msg, const MessageInfo& info, int latch_depth, F&& also) {
    std::shared_ptr<const SinkList> sinks;
    {
      std::lock_guard l(mu_);
      sinks = sinks_;
    }
    std::size_t owners = 0;
    for (const auto& s : *sinks) owners += s->wants_ownership() ? 1 : 0;
    const std::size_t sharers = sinks->size() - owners;
    const bool also_first = owners > 0 || sinks->empty();
    if (also_first) also(std::as_const(*msg));
    if (latch_depth == 0 && sharers == 0) {
      // owners only: k-1 copies, the last owner gets the original object
      std::size_t seen = 0;
      for (const auto& s : *sinks) {
        if (++seen == sinks->size()) {
          s->deliver_owned(std::move(msg), info);
        } else {
          s->deliver_owned(std::make_unique<T>(*msg), info);
        }
      }
      return;
    }
    std::shared_ptr<const T> shared(std::move(msg));
    for (const auto& s : *sinks) {
      if (s->wants_ownership()) {
        s->deliver_owned(std::make_unique<T>(*shared), info);
      } else {
        s->deliver_shared(shared, info);
      }
    }
    if (!also_first) also(*shared);
    if (latch_depth > 0) {
      std::lock_guard l(mu_);
      latched_.push_back(std::move(shared));
      while (static_cast<int>(latched_.size()) > latch_depth) latched_.pop_front();
    }
  }

 private:
  mutable std::mutex mu_;
  std::shared_ptr<const SinkList> sinks_ = std::make_shared<SinkList>();
  std::deque<std::shared_ptr<const T>> latched_;
};

class IntraProcessManager {
 public:
  /// The channel of `topic`; throws std::invalid_argument when the topic already carries another type
  /// in this process (a publisher/subscription type mismatch).
  template <class T>
  std::shared_ptr<Channel<T>> channel(const std::string& topic, const std::string& type_name) {
    std::lock_guard l(mu_);
    auto& c = channels_[topic];
    if (!c) c = std::make_shared<Channel<T>>(type_name);
    if (c->type != std::type_index(typeid(T))) {
      throw std::invalid_argument("topic '" + topic + "' carries " + c->type_name + " in this process, not " +
                                  type_name);
    }
    return std::static_pointer_cast<Channel<T>>(c);
  }

 private:
  std::mutex mu_;
  std::map<std::string, std::shared_ptr<ChannelBase>> channels_;
};

}  // namespace cairn

#endif  // CAIRN_INTRA_PROCESS_HPP
