// Helpers for component integration tests (header-only, gtest-free): a component in an in-process container
// spun on its own thread, and a peer node in a second Context so that everything between them goes over DDS.
#ifndef CAIRN_TEST_SUPPORT_HPP
#define CAIRN_TEST_SUPPORT_HPP

#include <chrono>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <thread>

#include "cairn/container.hpp"
#include "cairn/executor.hpp"
#include "cairn/node.hpp"

namespace cairn::testing {

/// Polls `pred` every 2 ms until it holds (true) or `timeout` passes (false).
inline bool wait_for(const std::function<bool()>& pred, std::chrono::milliseconds timeout) {
  const auto end = std::chrono::steady_clock::now() + timeout;
  while (!pred()) {
    if (std::chrono::steady_clock::now() > end) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  return true;
}

/// Spins an executor on its own thread; stop() (or the destructor) cancels and joins.
class Spinner {
 public:
  explicit Spinner(Executor& e) : exec_(e), thread_([this] { exec_.spin(); }) {}
  ~Spinner() { stop(); }
  Spinner(const Spinner&) = delete;
  Spinner& operator=(const Spinner&) = delete;
  void stop() {
    if (!thread_.joinable()) return;
    exec_.cancel();
    thread_.join();
  }

 private:
  Executor& exec_;
  std::thread thread_;
};

/// One component loaded into an in-process ComponentManager whose executor spins on its own thread.
/// `result` says whether the load worked (and why not); start() spins.
class InProcessContainer {
 public:
  explicit InProcessContainer(const std::string& name = "test_container")
      : ctx_(Context::create()), manager_(ctx_, exec_, name, loader_) {}
  LoadResult load(const LoadRequest& req) { return manager_.load(req); }
  void start() { spinner_ = std::make_unique<Spinner>(exec_); }
  void stop() { spinner_.reset(); }
  ~InProcessContainer() { stop(); }
  ComponentManager& manager() { return manager_; }

 private:
  std::shared_ptr<Context> ctx_;
  Executor exec_;
  ComponentLoader loader_;
  ComponentManager manager_;
  std::unique_ptr<Spinner> spinner_;
};

/// A plain node in its own Context and executor (a "remote" peer: nothing it exchanges with components in
/// other contexts is delivered intra-process). Create publishers/subscriptions/clients on node(), then start().
/// Its callbacks run on the spinning thread until stop() or destruction: whatever they write to must be declared
/// before the PeerNode (or outlive a stop()).
class PeerNode {
 public:
  explicit PeerNode(const std::string& name, std::map<std::string, ParameterValue> parameters = {})
      : ctx_(Context::create()) {
    NodeOptions o(name, &exec_);
    o.context = ctx_;
    o.start_parameter_services = false;
    o.parameter_overrides = std::move(parameters);
    node_ = std::make_unique<Node>(o);
  }
  Node& node() { return *node_; }
  void start() { spinner_ = std::make_unique<Spinner>(exec_); }
  void stop() { spinner_.reset(); }
  ~PeerNode() { stop(); }

 private:
  std::shared_ptr<Context> ctx_;
  Executor exec_;
  std::unique_ptr<Node> node_;
  std::unique_ptr<Spinner> spinner_;
};

}  // namespace cairn::testing

#endif  // CAIRN_TEST_SUPPORT_HPP
