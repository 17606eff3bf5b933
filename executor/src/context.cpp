#include "cairn/context.hpp"

#include <algorithm>
#include <unistd.h>

#include <cstdlib>
#include <random>
#include <stdexcept>

#include "cairn/dds.hpp"
#include "cairn/intra_process.hpp"
#include "cairn/msgs/type_support.hpp"
#include "dds/dds.h"

namespace cairn {

int domain_id_from_env() {
  for (const char* var : {"CAIRN_DOMAIN_ID", "ROS_DOMAIN_ID"}) {
    if (const char* v = std::getenv(var); v && *v) {
      char* end = nullptr;
      long id = std::strtol(v, &end, 10);
      if (*end != 0 || id < 0 || id > 232) {
        throw std::invalid_argument(std::string(var) + "='" + v + "' is not a DDS domain id (0..232)");
      }
      return static_cast<int>(id);
    }
  }
  return 0;
}

std::shared_ptr<Context> Context::create(ContextOptions opts) {
  return std::shared_ptr<Context>(new Context(opts));
}

std::shared_ptr<Context> Context::default_context() {
  static std::shared_ptr<Context> ctx = create();
  return ctx;
}

Context::Context(ContextOptions opts)
    : opts_(opts), intra_(std::make_unique<IntraProcessManager>()), ros_clock_(std::make_shared<Clock>(ClockType::Ros)) {
  domain_id_ = opts_.domain_id >= 0 ? opts_.domain_id : domain_id_from_env();
}

Context::~Context() {
  if (participant_ > 0) dds_delete(participant_);
}

int32_t Context::participant() {
  if (opts_.dry_run) throw std::logic_error("a dry-run context has no DDS participant");
  std::lock_guard l(mu_);
  if (participant_ <= 0) {
    // USER_DATA marks cairn processes, so that `cairn node list` can tell them from other DDS participants
    dds_qos_t* q = dds_create_qos();
    const std::string ud = "cairn:pid=" + std::to_string(getpid()) + ";";
    dds_qset_userdata(q, ud.data(), ud.size());
    participant_ = dds_create_participant(static_cast<dds_domainid_t>(domain_id_), q, nullptr);
    dds_delete_qos(q);
    if (participant_ < 0) {
      throw std::runtime_error(std::string("cannot create DDS participant on domain ") + std::to_string(domain_id_) +
                               ": " + dds_strretcode(participant_) + " (check CYCLONEDDS_URI)");
    }
  }
  return participant_;
}

int32_t Context::topic(const std::string& name, const msgs::TypeSupport& ts) {
  const int32_t pp = participant();
  std::lock_guard l(mu_);
  auto it = topics_.find(name);
  if (it != topics_.end()) {
    if (it->second.second != ts.dds_type_name) {
      throw std::invalid_argument("topic '" + name + "' is used with type " + it->second.second +
                                  " in this process, not " + ts.dds_type_name);
    }
    return it->second.first;
  }
  dds_entity_t t = create_dds_topic(pp, name, ts);
  if (t < 0) {
    throw std::runtime_error("cannot create DDS topic '" + name + "' (" + ts.dds_type_name +
                             "): " + dds_strretcode(t));
  }
  topics_[name] = {t, ts.dds_type_name};
  return t;
}

Gid Context::make_local_gid() {
  static const uint64_t process_salt = [] {
    std::random_device rd;
    return (static_cast<uint64_t>(rd()) << 32) ^ rd();
  }();
  Gid g{};
  const uint64_t id = next_id();
  for (int i = 0; i < 8; ++i) g[i] = static_cast<uint8_t>(process_salt >> (8 * i));
  for (int i = 0; i < 8; ++i) g[8 + i] = static_cast<uint8_t>(id >> (8 * i));
  return g;
}

void Context::record(const EndpointRecord& r) {
  std::lock_guard l(rec_mu_);
  records_.push_back(r);
}

std::vector<EndpointRecord> Context::records() const {
  std::lock_guard l(rec_mu_);
  return records_;
}

void Context::add_node(const std::string& fqn) {
  std::lock_guard l(rec_mu_);
  nodes_.push_back(fqn);
}

void Context::remove_node(const std::string& fqn) {
  std::lock_guard l(rec_mu_);
  auto it = std::find(nodes_.begin(), nodes_.end(), fqn);
  if (it != nodes_.end()) nodes_.erase(it);
  records_.erase(std::remove_if(records_.begin(), records_.end(), [&](const auto& r) { return r.node == fqn; }),
                 records_.end());
}

void Context::note_unused_parameters(UnusedParameters u) {
  std::lock_guard l(rec_mu_);
  unused_.push_back(std::move(u));
}

std::vector<Context::UnusedParameters> Context::unused_parameters() const {
  std::lock_guard l(rec_mu_);
  return unused_;
}

std::vector<std::string> Context::nodes() const {
  std::lock_guard l(rec_mu_);
  return nodes_;
}

}  // namespace cairn
