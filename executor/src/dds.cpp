#include "cairn/dds.hpp"

#include <cstring>
#include <stdexcept>
#include <vector>

#include "cairn/context.hpp"
#include "cairn/msgs/type_support.hpp"
#include "dds/dds.h"

namespace cairn {

std::string dds_topic_name(const std::string& resolved) {
  return "rt" + (resolved.empty() || resolved[0] != '/' ? "/" + resolved : resolved);
}

namespace {
dds_qos_t* endpoint_qos(const QoS& qos, const DdsEndpointOptions& opts) {
  dds_qos_t* q = qos.to_dds();
  if (opts.ignore_local) dds_qset_ignorelocal(q, DDS_IGNORELOCAL_PARTICIPANT);
  if (!opts.node.empty()) {
    const std::string ud = "cairn:node=" + opts.node + ";";
    dds_qset_userdata(q, ud.data(), ud.size());
  }
  static const dds_data_representation_id_t xcdr1[] = {DDS_DATA_REPRESENTATION_XCDR1};  // as ROS 2
  dds_qset_data_representation(q, 1, xcdr1);
  return q;
}

Gid to_gid(const dds_guid_t& g) {
  Gid out;
  std::memcpy(out.data(), g.v, 16);
  return out;
}
}  // namespace

DdsWriter::DdsWriter(Context& ctx, const std::string& dds_topic, const msgs::TypeSupport& ts, const QoS& qos,
                     const DdsEndpointOptions& opts)
    : ts_(ts) {
  const int32_t topic = ctx.topic(dds_topic, ts);
  dds_qos_t* q = endpoint_qos(qos, opts);
  dds_listener_t* l = dds_create_listener(&matched_);
  dds_lset_publication_matched(l, [](dds_entity_t, const dds_publication_matched_status_t st, void* arg) {
    static_cast<std::atomic<int>*>(arg)->store(static_cast<int>(st.current_count));
  });
  writer_ = dds_create_writer(ctx.participant(), topic, q, l);
  dds_delete_listener(l);
  dds_delete_qos(q);
  if (writer_ < 0) {
    throw std::runtime_error("cannot create DDS writer on '" + dds_topic + "': " + dds_strretcode(writer_));
  }
  dds_guid_t g;
  if (dds_get_guid(writer_, &g) == DDS_RETCODE_OK) guid_ = to_gid(g);
  dds_publication_matched_status_t st;  // readers matched before the listener was in place
  if (dds_get_publication_matched_status(writer_, &st) == DDS_RETCODE_OK) matched_.store(int(st.current_count));
}

DdsWriter::~DdsWriter() {
  if (writer_ > 0) dds_delete(writer_);
}

bool DdsWriter::wait_for_acks(int64_t timeout_ns) const {
  const dds_return_t rc = dds_wait_for_acks(writer_, timeout_ns < 0 ? DDS_INFINITY : timeout_ns);
  if (rc == DDS_RETCODE_OK) return true;
  if (rc == DDS_RETCODE_TIMEOUT) return false;
  throw std::runtime_error(std::string("dds_wait_for_acks failed: ") + dds_strretcode(rc));
}

void DdsWriter::write(const void* cpp, int64_t source_timestamp_ns) {
  // The C sample borrows the C++ message's buffers (strings, primitive sequences): nothing is copied
  // before Cyclone serializes it.
  thread_local std::vector<std::max_align_t> sample;
  thread_local msgs::Scratch scratch;
  const std::size_t words = (ts_.c_size + sizeof(std::max_align_t) - 1) / sizeof(std::max_align_t);
  if (sample.size() < words) sample.resize(words);
  std::memset(sample.data(), 0, ts_.c_size);
  scratch.clear();
  ts_.to_c(cpp, sample.data(), scratch);
  const dds_return_t rc = dds_write_ts(writer_, sample.data(), source_timestamp_ns);
  scratch.clear();
  if (rc != DDS_RETCODE_OK) {
    throw std::runtime_error(std::string("dds_write failed: ") + dds_strretcode(rc));
  }
}


struct DdsReader::Batch {
  static constexpr int kSize = 32;
  void* samples[kSize] = {};
  dds_sample_info_t info[kSize];
  int n = 0, next = 0;
};

DdsReader::DdsReader(Context& ctx, const std::string& dds_topic, const msgs::TypeSupport& ts, const QoS& qos,
                     const DdsEndpointOptions& opts, DataCallback on_data)
    : batch_(std::make_unique<Batch>()), ts_(ts), on_data_(std::move(on_data)) {
  const int32_t topic = ctx.topic(dds_topic, ts);
  dds_qos_t* q = endpoint_qos(qos, opts);
  const dds_entity_t r = dds_create_reader(ctx.participant(), topic, q, nullptr);
  dds_delete_qos(q);
  if (r < 0) {
    throw std::runtime_error("cannot create DDS reader on '" + dds_topic + "': " + dds_strretcode(r));
  }
  reader_ = r;
  if (on_data_) {
    // attached only now that the object is complete: the callback may run at once on a Cyclone thread
    dds_listener_t* l = dds_create_listener(this);
    dds_lset_data_available(l, [](dds_entity_t, void* arg) {
      auto* self = static_cast<DdsReader*>(arg);
      self->on_data_(*self);
    });
    dds_set_listener(reader_, l);
    dds_delete_listener(l);
    on_data_(*this);  // whatever arrived before the listener was attached
  }
}

DdsReader::~DdsReader() {
  if (reader_ > 0) {
    return_batch();
    dds_delete(reader_);  // returns once no listener call is in progress
  }
}

void DdsReader::return_batch() {
  if (batch_->n > 0) dds_return_loan(reader_, batch_->samples, batch_->n);
  batch_->n = batch_->next = 0;
}

Gid DdsReader::publisher_gid(uint64_t handle) {
  auto it = pubs_.find(handle);
  if (it != pubs_.end()) return it->second.first;
  Gid gid{};
  if (dds_builtintopic_endpoint_t* ep = dds_get_matched_publication_data(reader_, handle)) {
    std::memcpy(gid.data(), ep->key.v, 16);
    dds_builtintopic_free_endpoint(ep);
  }
  pubs_[handle] = {gid, 0};
  return gid;
}

bool DdsReader::take(void* cpp_out, MessageInfo& info) {
  for (;;) {
    Batch& b = *batch_;
    if (b.next == b.n) {
      return_batch();
      b.samples[0] = nullptr;  // loaned samples: no allocation on our side
      const int n = dds_take(reader_, b.samples, b.info, Batch::kSize, Batch::kSize);
      if (n <= 0) return false;
      b.n = n;
    }
    const int i = b.next++;
    const dds_sample_info_t& si = b.info[i];
    if (!si.valid_data) continue;  // dispose/unregister notifications
    ts_.from_c(b.samples[i], cpp_out);
    info.source_timestamp_ns = si.source_timestamp;
    info.publisher_gid = publisher_gid(si.publication_handle);
    info.sequence_number = ++pubs_[si.publication_handle].second;
    info.from_intra_process = false;
    if (b.next == b.n) return_batch();  // give the loan back promptly
    return true;
  }
}

int DdsReader::matched() const {
  dds_subscription_matched_status_t st;
  if (dds_get_subscription_matched_status(reader_, &st) != DDS_RETCODE_OK) return 0;
  return static_cast<int>(st.current_count);
}

}  // namespace cairn
