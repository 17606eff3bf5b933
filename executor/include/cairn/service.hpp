// Services: request/reply over DDS topics rq/<name>Request and rr/<name>Reply (ROS 2 naming). Every
// request and reply type starts with cairn_interfaces/msg/RequestHeader (client id, sequence number).
//
// Lost replies are the classic failure of request/reply over DDS (rmw_cyclonedds#74, #187): request and
// reply endpoints are discovered independently. Here a client sends only once both its request writer
// and its reply reader are matched, and a server writes a reply only once its reply writer has matched
// that very client's reply reader (it waits a bounded time for discovery otherwise).
#ifndef CAIRN_SERVICE_HPP
#define CAIRN_SERVICE_HPP

#include <algorithm>
#include <chrono>
#include <deque>
#include <functional>
#include <future>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <thread>

#include "cairn/context.hpp"
#include "cairn/dds.hpp"
#include "cairn/executor.hpp"
#include "cairn/logging.hpp"
#include "cairn/msgs/type_support.hpp"

namespace cairn {

namespace detail {
/// 64-bit client id derived from the client's reply-reader GUID, so a server can tell whether its reply
/// writer has matched that reader.
uint64_t client_id_from_gid(const Gid& g);
Gid reader_gid(int32_t reader);
/// True once `writer` is matched with a reader whose client id is `client_id`.
bool writer_matches_client(int32_t writer, uint64_t client_id);
std::string request_topic(const std::string& service);
std::string reply_topic(const std::string& service);
}  // namespace detail

class ServiceBase : public Executable {
 public:
  using Executable::Executable;
  virtual void shutdown() = 0;
  const std::string& name() const { return name_; }

 protected:
  std::string name_;
};

template <class Req, class Resp>
class Service : public ServiceBase {
 public:
  /// Replies later by calling `reply` (possibly from another thread), e.g. after a slow operation.
  using DeferredCallback = std::function<void(const Req&, std::function<void(Resp)> reply)>;

  Service(std::shared_ptr<CallbackGroup> group, Executor* exec, std::string name, DeferredCallback cb, Logger logger,
          std::chrono::milliseconds reply_match_timeout = std::chrono::milliseconds(2000))
      : ServiceBase(std::move(group)), exec_(exec), cb_(std::move(cb)), logger_(std::move(logger)),
        reply_match_timeout_(reply_match_timeout) {
    name_ = std::move(name);
  }

  void connect(Context& ctx, const std::string& node) {
    DdsEndpointOptions opts{node, false};
    std::weak_ptr<Executable> weak = shared_from_this();
    Executor* exec = exec_;
    QoS q = QoS::services();
    q.keep_all();
    writer_ = std::make_shared<DdsWriter>(ctx, detail::reply_topic(name_), msgs::type_support<Resp>(), q, opts);
    auto reader = std::make_unique<DdsReader>(ctx, detail::request_topic(name_), msgs::type_support<Req>(), q, opts,
                                              [weak, exec](DdsReader&) {
                                                if (auto s = weak.lock()) exec->schedule(s);
                                              });
    {
      std::lock_guard l(reader_mu_);
      reader_ = std::move(reader);
    }
    exec->schedule(shared_from_this());  // requests that arrived before reader_ was set
  }

  void shutdown() override {
    disable();
    std::lock_guard l(reader_mu_);
    reader_.reset();
    writer_.reset();
  }

 protected:
  void execute() override {
    for (;;) {
      Req req;
      MessageInfo info;
      {
        std::lock_guard l(reader_mu_);
        if (!reader_ || !reader_->take(&req, info)) return;
      }
      const auto header = req.request_header;
      const std::pair<uint64_t, int64_t> key{header.client_guid, header.sequence_number};
      {
        std::lock_guard l(recent_->mu);
        auto it = recent_->replies.find(key);
        if (it != recent_->replies.end()) {
          // a re-sent request: answer again if done, else the answer is on its way
          if (it->second) write_reply(writer_, *it->second, reply_match_timeout_, logger_, name_);
          continue;
        }
        recent_->replies[key] = std::nullopt;
        recent_->order.push_back(key);
        if (recent_->order.size() > 256) {
          recent_->replies.erase(recent_->order.front());
          recent_->order.pop_front();
        }
      }
      std::weak_ptr<DdsWriter> weak_writer = writer_;
      std::weak_ptr<Recent> weak_recent = recent_;
      auto reply = [weak_writer, weak_recent, key, header, timeout = reply_match_timeout_, logger = logger_,
                    name = name_](Resp resp) {
        auto w = weak_writer.lock();
        if (!w) return;
        resp.request_header = header;
        if (auto r = weak_recent.lock()) {
          std::lock_guard l(r->mu);
          if (r->replies.count(key)) r->replies[key] = resp;
        }
        write_reply(w, resp, timeout, logger, name);
      };
      try {
        cb_(req, reply);
      } catch (const std::exception& e) {
        CAIRN_ERROR(logger_, "service " << name_ << " callback threw: " << e.what());
      }
    }
  }

 private:
  struct Recent {
    std::mutex mu;
    std::map<std::pair<uint64_t, int64_t>, std::optional<Resp>> replies;
    std::deque<std::pair<uint64_t, int64_t>> order;
  };

  static void write_reply(const std::shared_ptr<DdsWriter>& w, const Resp& resp, std::chrono::milliseconds timeout,
                          const Logger& logger, const std::string& name) {
    const auto& header = resp.request_header;
    {
        const auto deadline = std::chrono::steady_clock::now() + timeout;
        while (!detail::writer_matches_client(w->entity(), header.client_guid)) {
          if (std::chrono::steady_clock::now() > deadline) {
            CAIRN_WARN(logger, "service " << name << ": client's reply reader not discovered; replying anyway");
            break;
          }
          std::this_thread::sleep_for(std::chrono::milliseconds(2));
        }
        try {
          w->write(&resp, 0);
        } catch (const std::exception& e) {
          CAIRN_ERROR(logger, "service " << name << ": cannot send reply: " << e.what());
        }
    }
  }

  std::shared_ptr<Recent> recent_ = std::make_shared<Recent>();
  Executor* exec_;
  DeferredCallback cb_;
  Logger logger_;
  std::chrono::milliseconds reply_match_timeout_;
  std::shared_ptr<DdsWriter> writer_;
  std::mutex reader_mu_;
  std::unique_ptr<DdsReader> reader_;
};

/// A service client. Thread-safe; replies are handled on a DDS thread, so a synchronous call() from inside
/// an executor callback does not deadlock.
template <class Req, class Resp>
class Client {
 public:
  Client(Context& ctx, std::string name, const std::string& node) : name_(std::move(name)) {
    DdsEndpointOptions opts{node, false};
    QoS q = QoS::services();
    q.keep_all();
    writer_ = std::make_unique<DdsWriter>(ctx, detail::request_topic(name_), msgs::type_support<Req>(), q, opts);
    reader_ = std::make_unique<DdsReader>(ctx, detail::reply_topic(name_), msgs::type_support<Resp>(), q, opts,
                                          [this](DdsReader& r) { on_reply(r); });
    client_id_ = detail::client_id_from_gid(detail::reader_gid(reader_->entity()));
  }
  ~Client() { reader_.reset(); }

  const std::string& name() const { return name_; }

  /// True once a server's request reader and reply writer are both matched.
  bool service_is_ready() const { return writer_->matched() > 0 && reader_->matched() > 0; }

  bool wait_for_service(std::chrono::nanoseconds timeout) const {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (!service_is_ready()) {
      if (std::chrono::steady_clock::now() >= deadline) return false;
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return true;
  }

  /// Sends without waiting for discovery; prefer call() or wait_for_service() first.
  std::future<Resp> async_send(Req req) { return enqueue(req); }

  /// A request in flight (send()): poll() it until it is answered or its deadline passes.
  struct Pending {
    Req req;  ///< as sent, header included: a re-send has the same id, so the server answers it once
    std::future<Resp> reply;
    std::chrono::steady_clock::time_point deadline, next_send;
    std::chrono::nanoseconds resend_interval{};
    bool expired = false;  ///< the deadline passed without a reply (the request is forgotten)
  };

  /// Sends `req` now (without waiting for discovery) and returns it to be polled; it expires after `timeout`.
  Pending send(Req req, std::chrono::nanoseconds timeout,
               std::chrono::nanoseconds resend_interval = std::chrono::seconds(1)) {
    Pending p;
    p.reply = enqueue(req);
    p.req = std::move(req);
    const auto now = std::chrono::steady_clock::now();
    p.deadline = now + timeout;
    p.resend_interval = resend_interval;
    p.next_send = now + resend_interval;
    return p;
  }

  /// Waits for `p`'s reply until `until` at most (a time already past: does not wait), re-sending it every
  /// resend interval meanwhile. The reply, or nullopt: not yet, or `p.expired` once the deadline has passed.
  std::optional<Resp> poll(Pending& p, std::chrono::steady_clock::time_point until) {
    if (p.expired || !p.reply.valid()) return std::nullopt;
    for (;;) {
      const auto stop = std::min({until, p.deadline, p.next_send});
      if (p.reply.wait_until(stop) == std::future_status::ready) return p.reply.get();
      const auto now = std::chrono::steady_clock::now();
      if (now >= p.deadline) {
        p.expired = true;
        std::lock_guard l(mu_);
        pending_.erase(p.req.request_header.sequence_number);
        return std::nullopt;
      }
      if (now >= p.next_send) {
        writer_->write(&p.req, 0);
        p.next_send = now + p.resend_interval;
      }
      if (now >= until) return std::nullopt;
    }
  }

  /// Waits for the service (at most `timeout`), sends, and waits for the reply within what is left of
  /// `timeout`, re-sending the same request every `resend_interval`. nullopt on timeout.
  std::optional<Resp> call(Req req, std::chrono::nanoseconds timeout,
                           std::chrono::nanoseconds resend_interval = std::chrono::seconds(1)) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    if (!wait_for_service(timeout)) return std::nullopt;
    auto p = send(std::move(req), deadline - std::chrono::steady_clock::now(), resend_interval);
    return poll(p, p.deadline);
  }

 private:
  /// Gives `req` this client's id and the next sequence number (together with its pending entry: another thread
  /// may send meanwhile), sends it, and returns the future of its reply.
  std::future<Resp> enqueue(Req& req) {
    std::promise<Resp> p;
    auto f = p.get_future();
    {
      std::lock_guard l(mu_);
      req.request_header.client_guid = client_id_;
      req.request_header.sequence_number = ++seq_;
      pending_[req.request_header.sequence_number] = std::move(p);
    }
    writer_->write(&req, 0);
    return f;
  }

  void on_reply(DdsReader& reader) {
    std::lock_guard l(mu_);
    for (;;) {
      Resp resp;
      MessageInfo info;
      if (!reader.take(&resp, info)) return;
      if (resp.request_header.client_guid != client_id_) continue;  // another client's reply
      auto it = pending_.find(resp.request_header.sequence_number);
      if (it == pending_.end()) continue;  // timed out already
      it->second.set_value(std::move(resp));
      pending_.erase(it);
    }
  }

  std::string name_;
  std::unique_ptr<DdsWriter> writer_;
  std::unique_ptr<DdsReader> reader_;
  uint64_t client_id_ = 0;
  std::mutex mu_;
  int64_t seq_ = 0;
  std::map<int64_t, std::promise<Resp>> pending_;
};

}  // namespace cairn

#endif  // CAIRN_SERVICE_HPP
