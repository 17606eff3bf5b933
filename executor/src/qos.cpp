#include "cairn/qos.hpp"

#include <limits>
#include <sstream>

#include "cairn/strict_number.hpp"

#include "dds/dds.h"

namespace cairn {

QoS QoS::sensor_data() {
  QoS q;
  q.keep_last(5).best_effort();
  return q;
}

QoS QoS::latched(int depth) {
  QoS q;
  q.keep_last(depth).reliable().transient_local();
  return q;
}

QoS QoS::services() {
  QoS q;
  q.keep_last(10).reliable();
  return q;
}

static dds_duration_t to_dds_duration(std::chrono::nanoseconds d) {
  return d.count() <= 0 ? DDS_INFINITY : static_cast<dds_duration_t>(d.count());
}

static std::chrono::nanoseconds from_dds_duration(dds_duration_t d) {
  return d == DDS_INFINITY ? std::chrono::nanoseconds{0} : std::chrono::nanoseconds{d};
}

dds_qos* QoS::to_dds() const {
  dds_qos_t* q = dds_create_qos();
  if (history == History::KeepAll) {
    dds_qset_history(q, DDS_HISTORY_KEEP_ALL, 0);
  } else {
    dds_qset_history(q, DDS_HISTORY_KEEP_LAST, depth);
  }
  dds_qset_reliability(q, reliability == Reliability::Reliable ? DDS_RELIABILITY_RELIABLE : DDS_RELIABILITY_BEST_EFFORT,
                       DDS_SECS(1));
  dds_qset_durability(q, durability == Durability::TransientLocal ? DDS_DURABILITY_TRANSIENT_LOCAL
                                                                   : DDS_DURABILITY_VOLATILE);
  dds_qset_deadline(q, to_dds_duration(deadline));
  dds_qset_lifespan(q, to_dds_duration(lifespan));
  dds_qset_liveliness(q, liveliness == Liveliness::Automatic ? DDS_LIVELINESS_AUTOMATIC : DDS_LIVELINESS_MANUAL_BY_TOPIC,
                      to_dds_duration(liveliness_lease));
  return q;
}

QoS QoS::from_dds(const dds_qos* q) {
  QoS out;
  dds_history_kind_t hk;
  int32_t d;
  if (dds_qget_history(q, &hk, &d)) {
    out.history = hk == DDS_HISTORY_KEEP_ALL ? History::KeepAll : History::KeepLast;
    out.depth = d;
  }
  dds_reliability_kind_t rk;
  dds_duration_t block;
  if (dds_qget_reliability(q, &rk, &block)) {
    out.reliability = rk == DDS_RELIABILITY_RELIABLE ? Reliability::Reliable : Reliability::BestEffort;
  }
  dds_durability_kind_t dk;
  if (dds_qget_durability(q, &dk)) {
    out.durability = dk == DDS_DURABILITY_VOLATILE ? Durability::Volatile : Durability::TransientLocal;
  }
  dds_duration_t dur;
  if (dds_qget_deadline(q, &dur)) out.deadline = from_dds_duration(dur);
  if (dds_qget_lifespan(q, &dur)) out.lifespan = from_dds_duration(dur);
  dds_liveliness_kind_t lk;
  if (dds_qget_liveliness(q, &lk, &dur)) {
    out.liveliness = lk == DDS_LIVELINESS_MANUAL_BY_TOPIC ? Liveliness::ManualByTopic : Liveliness::Automatic;
    out.liveliness_lease = from_dds_duration(dur);
  }
  return out;
}

std::string QoS::to_string() const {
  std::ostringstream o;
  o << (reliability == Reliability::Reliable ? "reliable" : "best_effort") << ", "
    << (durability == Durability::TransientLocal ? "transient_local" : "volatile") << ", ";
  if (history == History::KeepAll) {
    o << "keep_all";
  } else {
    o << "keep_last(" << depth << ")";
  }
  if (deadline.count() > 0) o << ", deadline " << deadline.count() * 1e-9 << " s";
  if (lifespan.count() > 0) o << ", lifespan " << lifespan.count() * 1e-9 << " s";
  if (batching) o << ", batching";
  return o.str();
}

void QoSOverride::apply(QoS& q) const {
  if (history) q.history = *history;
  if (depth) q.depth = *depth;
  if (reliability) q.reliability = *reliability;
  if (durability) q.durability = *durability;
  if (deadline) q.deadline = *deadline;
  if (lifespan) q.lifespan = *lifespan;
}

namespace {
constexpr double kMaxQoSSeconds = 9e9;  // < 2^63 ns
}  // namespace

std::optional<std::string> QoSOverride::set(const std::string& key, const std::string& value) {
  auto seconds = [&](std::optional<std::chrono::nanoseconds>& out) -> std::optional<std::string> {
    // At most kMaxQoSSeconds: the duration must fit DDS's 64-bit nanoseconds ("inf" or 1e300 used to overflow).
    const auto s = strict_number::parse_finite(value);
    if (!s || *s < 0 || *s > kMaxQoSSeconds)
      return "qos " + key + " expects seconds in [0, 9e9], got '" + value + "'";
    out = std::chrono::nanoseconds(static_cast<int64_t>(*s * 1e9));
    return std::nullopt;
  };
  if (key == "history") {
    if (value == "keep_last") history = QoS::History::KeepLast;
    else if (value == "keep_all") history = QoS::History::KeepAll;
    else return "qos history expects keep_last or keep_all, got '" + value + "'";
  } else if (key == "depth") {
    const auto d = strict_number::parse_integer(value);
    if (!d || *d < 1 || *d > std::numeric_limits<int>::max())
      return "qos depth expects an integer >= 1, got '" + value + "'";
    depth = static_cast<int>(*d);
  } else if (key == "reliability") {
    if (value == "reliable") reliability = QoS::Reliability::Reliable;
    else if (value == "best_effort") reliability = QoS::Reliability::BestEffort;
    else return "qos reliability expects reliable or best_effort, got '" + value + "'";
  } else if (key == "durability") {
    if (value == "volatile") durability = QoS::Durability::Volatile;
    else if (value == "transient_local") durability = QoS::Durability::TransientLocal;
    else return "qos durability expects volatile or transient_local, got '" + value + "'";
  } else if (key == "deadline") {
    return seconds(deadline);
  } else if (key == "lifespan") {
    return seconds(lifespan);
  } else {
    return "unknown qos key '" + key + "' (history, depth, reliability, durability, deadline, lifespan)";
  }
  return std::nullopt;
}

std::optional<std::string> qos_incompatibility(const QoS& pub, const QoS& sub) {
  if (pub.reliability == QoS::Reliability::BestEffort && sub.reliability == QoS::Reliability::Reliable) {
    return "subscription requests reliable delivery but the publisher offers best effort";
  }
  if (pub.durability == QoS::Durability::Volatile && sub.durability == QoS::Durability::TransientLocal) {
    return "subscription requests transient_local durability but the publisher offers volatile";
  }
  auto inf = [](std::chrono::nanoseconds d) { return d.count() <= 0; };
  if (!inf(sub.deadline) && (inf(pub.deadline) || pub.deadline > sub.deadline)) {
    return "subscription requests a deadline shorter than the publisher offers";
  }
  if (pub.liveliness == QoS::Liveliness::Automatic && sub.liveliness == QoS::Liveliness::ManualByTopic) {
    return "subscription requests manual_by_topic liveliness but the publisher offers automatic";
  }
  if (!inf(sub.liveliness_lease) && (inf(pub.liveliness_lease) || pub.liveliness_lease > sub.liveliness_lease)) {
    return "subscription requests a liveliness lease shorter than the publisher offers";
  }
  return std::nullopt;
}

}  // namespace cairn
