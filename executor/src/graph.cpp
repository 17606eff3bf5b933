#include "cairn/graph.hpp"

#include <cstdio>
#include <cstring>
#include <set>
#include <thread>

#include "dds/dds.h"

namespace cairn {

std::string ros_topic_name(const std::string& t) { return t.rfind("rt/", 0) == 0 ? t.substr(2) : t; }

std::string ros_type_name(const std::string& t) {
  const auto p = t.find("::dds_::");
  if (p == std::string::npos || t.empty() || t.back() != '_') return t;
  std::string pkg = t.substr(0, p);  // pkg::msg
  std::string name = t.substr(p + 8, t.size() - p - 9);
  std::string out;
  for (std::size_t i = 0; i < pkg.size(); ++i) {
    if (pkg.compare(i, 2, "::") == 0) {
      out += '/';
      ++i;
    } else {
      out += pkg[i];
    }
  }
  return out + "/" + name;
}

std::string gid_to_string(const Gid& g) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%02x%02x%02x%02x:%02x%02x%02x%02x:%02x%02x%02x%02x:%02x%02x%02x%02x", g[0], g[1],
                g[2], g[3], g[4], g[5], g[6], g[7], g[8], g[9], g[10], g[11], g[12], g[13], g[14], g[15]);
  return buf;
}

GraphView::GraphView(Context& ctx) : ctx_(ctx) {
  const dds_entity_t pp = ctx_.participant();
  pub_reader_ = dds_create_reader(pp, DDS_BUILTIN_TOPIC_DCPSPUBLICATION, nullptr, nullptr);
  sub_reader_ = dds_create_reader(pp, DDS_BUILTIN_TOPIC_DCPSSUBSCRIPTION, nullptr, nullptr);
  part_reader_ = dds_create_reader(pp, DDS_BUILTIN_TOPIC_DCPSPARTICIPANT, nullptr, nullptr);
  dds_guid_t g;
  if (dds_get_guid(pp, &g) == DDS_RETCODE_OK) std::memcpy(self_.data(), g.v, 16);
}

GraphView::~GraphView() {
  for (int32_t r : {pub_reader_, sub_reader_, part_reader_})
    if (r > 0) dds_delete(r);
}

namespace {
Gid gid(const dds_guid_t& g) {
  Gid out;
  std::memcpy(out.data(), g.v, 16);
  return out;
}

std::string node_from_userdata(const dds_qos_t* qos) {
  void* ud = nullptr;
  size_t sz = 0;
  if (!qos || !dds_qget_userdata(qos, &ud, &sz) || !ud) return "";
  std::string s(static_cast<const char*>(ud), sz);
  dds_free(ud);
  const std::string key = "cairn:node=";
  const auto p = s.find(key);
  if (p == std::string::npos) return "";
  const auto e = s.find(';', p);
  return s.substr(p + key.size(), e == std::string::npos ? std::string::npos : e - p - key.size());
}
}  // namespace

std::vector<GraphEndpoint> GraphView::endpoints() {
  std::vector<GraphEndpoint> out;
  for (const bool is_pub : {true, false}) {
    const int32_t reader = is_pub ? pub_reader_ : sub_reader_;
    constexpr int kMax = 4096;
    std::vector<void*> buf(kMax, nullptr);
    std::vector<dds_sample_info_t> info(kMax);
    const int n = dds_read_mask(reader, buf.data(), info.data(), kMax, kMax, DDS_ALIVE_INSTANCE_STATE);
    for (int i = 0; i < n; ++i) {
      if (!info[i].valid_data) continue;
      const auto* ep = static_cast<const dds_builtintopic_endpoint_t*>(buf[i]);
      if (gid(ep->participant_key) == self_) continue;
      GraphEndpoint e;
      e.is_publisher = is_pub;
      e.dds_topic = ep->topic_name ? ep->topic_name : "";
      e.dds_type = ep->type_name ? ep->type_name : "";
      e.node = node_from_userdata(ep->qos);
      e.guid = gid(ep->key);
      e.participant = gid(ep->participant_key);
      if (ep->qos) e.qos = QoS::from_dds(ep->qos);
      out.push_back(std::move(e));
    }
    if (n > 0) dds_return_loan(reader, buf.data(), n);
  }
  return out;
}

std::vector<GraphParticipant> GraphView::participants() {
  std::vector<GraphParticipant> out;
  constexpr int kMax = 1024;
  std::vector<void*> buf(kMax, nullptr);
  std::vector<dds_sample_info_t> info(kMax);
  const int n = dds_read_mask(part_reader_, buf.data(), info.data(), kMax, kMax, DDS_ALIVE_INSTANCE_STATE);
  for (int i = 0; i < n; ++i) {
    if (!info[i].valid_data) continue;
    const auto* p = static_cast<const dds_builtintopic_participant_t*>(buf[i]);
    if (gid(p->key) == self_) continue;
    GraphParticipant gp;
    gp.guid = gid(p->key);
    void* ud = nullptr;
    size_t sz = 0;
    if (p->qos && dds_qget_userdata(p->qos, &ud, &sz) && ud) {
      gp.cairn = std::string(static_cast<const char*>(ud), sz).rfind("cairn:", 0) == 0;
      dds_free(ud);
    }
    out.push_back(gp);
  }
  if (n > 0) dds_return_loan(part_reader_, buf.data(), n);
  return out;
}

void GraphView::wait_for_discovery(std::chrono::milliseconds settle, std::chrono::milliseconds timeout) {
  const auto t0 = std::chrono::steady_clock::now();
  auto last_change = t0;
  std::set<std::pair<Gid, std::string>> prev;
  while (std::chrono::steady_clock::now() - t0 < timeout) {
    std::set<std::pair<Gid, std::string>> cur;
    for (const auto& e : endpoints()) cur.insert({e.guid, e.dds_topic});
    for (const auto& p : participants()) cur.insert({p.guid, ""});
    if (cur != prev) {
      prev = std::move(cur);
      last_change = std::chrono::steady_clock::now();
    } else if (!prev.empty() && std::chrono::steady_clock::now() - last_change >= settle) {
      return;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

}  // namespace cairn
