#include "cairn/dds.hpp"

// dds/features.h first: it changes the layout of the internal ddsi structs below.
#include "dds/features.h"
// then the rest
#include <cstdlib>
#include <cstring>
#include <functional>
#include <stdexcept>
#include <vector>

#include "cairn/context.hpp"
#include "cairn/logging.hpp"
#include "cairn/msgs/cdr.hpp"
#include "cairn/msgs/type_support.hpp"
#include "dds/dds.h"
#include "dds/ddsi/ddsi_serdata.h"
#include "dds/ddsi/ddsi_sertype.h"
#include "dds/ddsi/q_radmin.h"

namespace cairn {

std::string dds_topic_name(const std::string& resolved) {
  return "rt" + (resolved.empty() || resolved[0] != '/' ? "/" + resolved : resolved);
}

// ---------------- cairn's ddsi_sertype: XCDR1 straight between C++ messages and the wire ----------------
//
// A sample of this sertype is a C++ message object (the TypeSupport's type). Writing serializes it with the
// generated codec into one buffer (sized first, so it is allocated once) that Cyclone sends from directly;
// receiving copies the fragments into one buffer, and the reader decodes it straight into a C++ message at
// take time (DdsReader::take), validating every length against the buffer. The bytes are those idlc's
// serializer produces for the same @final type (test_dds_codec compares them), so plain idlc programs,
// ROS 2 (rmw_cyclonedds, rmw_fastrtps) and DDS tools exchange data with cairn.
namespace {

struct CairnSertype {
  ddsi_sertype c;  // first member: Cyclone hands us ddsi_sertype pointers
  const msgs::TypeSupport* ts;
};

struct CairnSerdata {
  ddsi_serdata c;  // first member
  uint32_t size;   // serialized size including the 4-byte encapsulation header
  unsigned char* data;  // header at data[0..3], payload (8-byte aligned) from data + 4
};

const msgs::TypeSupport& ts_of(const ddsi_sertype* t) { return *reinterpret_cast<const CairnSertype*>(t)->ts; }
const CairnSerdata* sd(const ddsi_serdata* d) { return reinterpret_cast<const CairnSerdata*>(d); }

extern const ddsi_serdata_ops kSerdataOps;

/// One allocation: the struct, 4 bytes of slack so that the payload after the header is 8-byte aligned,
/// and the bytes rounded up to 4 (the protocol may ask for up to alignup4(size)).
CairnSerdata* new_serdata(const ddsi_sertype* type, ddsi_serdata_kind kind, std::size_t size) {
  const std::size_t bytes = (size + 3) & ~std::size_t(3);
  void* mem = std::malloc(sizeof(CairnSerdata) + 4 + bytes);
  if (!mem) return nullptr;
  auto* d = static_cast<CairnSerdata*>(mem);
  ddsi_serdata_init(&d->c, type, kind);
  d->size = static_cast<uint32_t>(size);
  d->data = reinterpret_cast<unsigned char*>(d + 1) + 4;
  std::memset(d->data + size, 0, bytes - size);
  return d;
}

/// A key-only serdata (keyless types: just the header) for dispose/unregister and the instance map.
ddsi_serdata* empty_serdata(const ddsi_sertype* type, ddsi_serdata_kind kind) {
  CairnSerdata* d = new_serdata(type, kind, 4);
  if (!d) return nullptr;
  const unsigned char hdr[4] = {0x00, 0x01, 0x00, 0x00};
  std::memcpy(d->data, hdr, 4);
  return &d->c;
}

thread_local std::string tl_serialize_error;  // why the last from_sample on this thread failed

ddsi_serdata* sd_from_sample(const ddsi_sertype* type, ddsi_serdata_kind kind, const void* sample) {
  if (kind != SDK_DATA) return empty_serdata(type, kind);
  const msgs::TypeSupport& ts = ts_of(type);
  try {
    const std::size_t n = ts.cdr_size(sample);
    if (n > 0xffff'fff0u) throw std::length_error("sample too large for DDS (4 GiB)");
    const std::size_t pad = (4 - n % 4) % 4;
    CairnSerdata* d = new_serdata(type, kind, 4 + n + pad);
    if (!d) throw std::bad_alloc();
    d->data[0] = 0x00;
    d->data[1] = 0x01;  // CDR_LE
    d->data[2] = 0x00;
    d->data[3] = static_cast<unsigned char>(pad);  // XTypes 1.3 7.6.3.1.2: padding count in the options
    ts.cdr_write(sample, d->data + 4);
    return &d->c;
  } catch (const std::exception& e) {
    tl_serialize_error = std::string(ts.ros_type_name) + ": " + e.what();
    return nullptr;
  }
}

ddsi_serdata* sd_from_ser(const ddsi_sertype* type, ddsi_serdata_kind kind, const nn_rdata* frag, size_t size) {
  CairnSerdata* d = new_serdata(type, kind, size);
  if (!d) return nullptr;
  // fragments are in order and may overlap; copy each byte range once
  uint32_t off = 0;
  for (; frag; frag = frag->nextfrag) {
    if (frag->maxp1 <= off) continue;
    if (frag->min > off || frag->maxp1 > size) {  // a hole or an overrun: not a sample we can use
      std::free(d);
      return nullptr;
    }
    const unsigned char* payload = NN_RMSG_PAYLOADOFF(frag->rmsg, NN_RDATA_PAYLOAD_OFF(frag));
    std::memcpy(d->data + off, payload + (off - frag->min), frag->maxp1 - off);
    off = frag->maxp1;
  }
  if (off != size) {
    std::free(d);
    return nullptr;
  }
  return &d->c;
}

ddsi_serdata* sd_from_ser_iov(const ddsi_sertype* type, ddsi_serdata_kind kind, ddsrt_msg_iovlen_t niov,
                              const ddsrt_iovec_t* iov, size_t size) {
  CairnSerdata* d = new_serdata(type, kind, size);
  if (!d) return nullptr;
  std::size_t off = 0;
  for (ddsrt_msg_iovlen_t i = 0; i < niov && off < size; ++i) {
    const std::size_t n = std::min<std::size_t>(iov[i].iov_len, size - off);
    std::memcpy(d->data + off, iov[i].iov_base, n);
    off += n;
  }
  return &d->c;
}

ddsi_serdata* sd_from_keyhash(const ddsi_sertype* type, const ddsi_keyhash*) { return empty_serdata(type, SDK_KEY); }

uint32_t sd_get_size(const ddsi_serdata* d) { return sd(d)->size; }

bool sd_eqkey(const ddsi_serdata*, const ddsi_serdata*) { return true; }  // keyless: one instance

void sd_free(ddsi_serdata* d) { std::free(d); }

void sd_to_ser(const ddsi_serdata* d, size_t off, size_t sz, void* buf) { std::memcpy(buf, sd(d)->data + off, sz); }

ddsi_serdata* sd_to_ser_ref(const ddsi_serdata* d, size_t off, size_t sz, ddsrt_iovec_t* ref) {
  ref->iov_base = sd(d)->data + off;
  ref->iov_len = static_cast<ddsrt_iov_len_t>(sz);
  return ddsi_serdata_ref(d);
}

void sd_to_ser_unref(ddsi_serdata* d, const ddsrt_iovec_t*) { ddsi_serdata_unref(d); }

/// Decodes a serialized sample into a C++ message; false (and the reason) when it is malformed.
bool decode(const CairnSerdata* d, const msgs::TypeSupport& ts, void* cpp, std::string* why) {
  try {
    msgs::deserialize(ts, d->data, d->size, cpp);
    return true;
  } catch (const std::exception& e) {
    if (why) *why = e.what();
    return false;
  }
}

bool sd_to_sample(const ddsi_serdata* d, void* sample, void**, void*) {
  if (d->kind != SDK_DATA) return true;
  return decode(sd(d), ts_of(d->type), sample, nullptr);
}

ddsi_serdata* sd_to_untyped(const ddsi_serdata* d) { return empty_serdata(d->type, SDK_KEY); }

bool sd_untyped_to_sample(const ddsi_sertype*, const ddsi_serdata*, void*, void**, void*) { return true; }

size_t sd_print(const ddsi_sertype* type, const ddsi_serdata* d, char* buf, size_t size) {
  const int n = std::snprintf(buf, size, "(%u bytes of %s)", unsigned(sd(d)->size), ts_of(type).ros_type_name);
  return n < 0 ? 0 : std::min<size_t>(size_t(n), size - 1);
}

void sd_get_keyhash(const ddsi_serdata*, ddsi_keyhash* buf, bool) { std::memset(buf->value, 0, sizeof(buf->value)); }

const ddsi_serdata_ops kSerdataOps = {
    .eqkey = sd_eqkey,
    .get_size = sd_get_size,
    .from_ser = sd_from_ser,
    .from_ser_iov = sd_from_ser_iov,
    .from_keyhash = sd_from_keyhash,
    .from_sample = sd_from_sample,
    .to_ser = sd_to_ser,
    .to_ser_ref = sd_to_ser_ref,
    .to_ser_unref = sd_to_ser_unref,
    .to_sample = sd_to_sample,
    .to_untyped = sd_to_untyped,
    .untyped_to_sample = sd_untyped_to_sample,
    .free = sd_free,
    .print = sd_print,
    .get_keyhash = sd_get_keyhash,
#ifdef DDS_HAS_SHM
    .get_sample_size = nullptr,
    .from_iox_buffer = nullptr,
#endif
};

// Sample arrays (used by Cyclone only for dds_read/dds_take with loans, which cairn does not do on its
// own topics: it takes serialized samples). Contents are not preserved across realloc.
void st_zero_samples(const ddsi_sertype* type, void* samples, size_t count) {
  const msgs::TypeSupport& ts = ts_of(type);
  for (size_t i = 0; i < count; ++i) {
    void* p = static_cast<char*>(samples) + i * ts.cpp_size;
    ts.destruct(p);
    ts.construct(p);
  }
}

void st_realloc_samples(void** ptrs, const ddsi_sertype* type, void* old, size_t oldcount, size_t count) {
  const msgs::TypeSupport& ts = ts_of(type);
  if (old) {
    for (size_t i = 0; i < oldcount; ++i) ts.destruct(static_cast<char*>(old) + i * ts.cpp_size);
    std::free(old);
  }
  char* mem = static_cast<char*>(std::malloc(std::max<size_t>(count, 1) * ts.cpp_size));
  for (size_t i = 0; i < count; ++i) {
    ts.construct(mem + i * ts.cpp_size);
    if (ptrs) ptrs[i] = mem + i * ts.cpp_size;
  }
}

void st_free_samples(const ddsi_sertype* type, void** ptrs, size_t count, dds_free_op_t op) {
  if (count == 0 || !ptrs || !ptrs[0]) return;
  const msgs::TypeSupport& ts = ts_of(type);
  if (op & DDS_FREE_CONTENTS_BIT) {
    for (size_t i = 0; i < count; ++i) ts.destruct(ptrs[i]);
  }
  if (op & DDS_FREE_ALL_BIT) std::free(ptrs[0]);
}

void st_free(ddsi_sertype* t) {
  ddsi_sertype_fini(t);
  delete reinterpret_cast<CairnSertype*>(t);
}

bool st_equal(const ddsi_sertype* a, const ddsi_sertype* b) {
  return reinterpret_cast<const CairnSertype*>(a)->ts == reinterpret_cast<const CairnSertype*>(b)->ts;
}

uint32_t st_hash(const ddsi_sertype* t) {
  return static_cast<uint32_t>(std::hash<std::string_view>{}(ts_of(t).dds_type_name));
}

const ddsi_sertype_ops kSertypeOps = {
    .version = ddsi_sertype_v0,
    .arg = nullptr,
    .free = st_free,
    .zero_samples = st_zero_samples,
    .realloc_samples = st_realloc_samples,
    .free_samples = st_free_samples,
    .equal = st_equal,
    .hash = st_hash,
    .type_id = nullptr,
    .type_map = nullptr,
    .type_info = nullptr,
    .derive_sertype = nullptr,
    .get_serialized_size = nullptr,
    .serialize_into = nullptr,
};

}  // namespace

int32_t create_dds_topic(int32_t participant, const std::string& name, const msgs::TypeSupport& ts) {
  auto* st = new CairnSertype{};
  st->ts = &ts;
  ddsi_sertype_init(&st->c, ts.dds_type_name, &kSertypeOps, &kSerdataOps, /*topickind_no_key=*/true);
  st->c.allowed_data_representation = DDS_DATA_REPRESENTATION_FLAG_XCDR1;  // @final, plain CDR as ROS 2
  ddsi_sertype* type = &st->c;
  const dds_entity_t t = dds_create_topic_sertype(participant, name.c_str(), &type, nullptr, nullptr, nullptr);
  if (t < 0) st_free(&st->c);  // not taken over by Cyclone
  return t;
}

namespace {
std::mutex& writer_creation_mutex() {
  static std::mutex m;
  return m;
}

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
  if (qos.batching) {
    // Cyclone 0.10 reads its process-wide WriteBatch setting when a writer is created: switch it on for this
    // writer only (all cairn writers are created under this lock).
    std::lock_guard lock(writer_creation_mutex());
    dds_write_set_batch(true);
    writer_ = dds_create_writer(ctx.participant(), topic, q, l);
    dds_write_set_batch(false);
  } else {
    std::lock_guard lock(writer_creation_mutex());
    writer_ = dds_create_writer(ctx.participant(), topic, q, l);
  }
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
  // serialized straight from the C++ message by the sertype (sd_from_sample): no intermediate copy
  tl_serialize_error.clear();
  const dds_return_t rc = dds_write_ts(writer_, cpp, source_timestamp_ns);
  if (rc != DDS_RETCODE_OK) {
    throw std::runtime_error(tl_serialize_error.empty() ? std::string("dds_write failed: ") + dds_strretcode(rc)
                                                        : tl_serialize_error);
  }
}

void DdsWriter::flush() { dds_write_flush(writer_); }

DdsReader::DdsReader(Context& ctx, const std::string& dds_topic, const msgs::TypeSupport& ts, const QoS& qos,
                     const DdsEndpointOptions& opts, DataCallback on_data)
    : ts_(ts), on_data_(std::move(on_data)) {
  // keep-last: what waits in the reader's own queue is bounded as the DDS history is
  max_queued_ = qos.history == QoS::History::KeepLast ? std::size_t(std::max(qos.depth, 1)) : SIZE_MAX;
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
    dds_delete(reader_);  // first: no listener runs (and fills the queue) after this
    clear_queue();  // returns once no listener call is in progress
  }
}

void DdsReader::clear_queue() {
  std::lock_guard l(q_mu_);
  while (q_size_ > 0) ddsi_serdata_unref(pop_locked().data);
}

void DdsReader::prefetch() {
  std::lock_guard l(q_mu_);
  fill_locked();
}

void DdsReader::fill_locked() {
  // Serialized samples (references: no copy, no decoding) move from Cyclone's reader into this queue; the
  // consumer decodes them later without touching Cyclone's reader (and its locks) at all.
  constexpr uint32_t kChunk = 64;
  ddsi_serdata* d[kChunk];
  dds_sample_info_t si[kChunk];
  for (;;) {
    const int n = dds_takecdr(reader_, d, kChunk, si, 0);
    for (int i = 0; i < n; ++i) {
      if (q_size_ == ring_.size()) {
        std::vector<Queued> bigger(std::max<std::size_t>(16, ring_.size() * 2));
        for (std::size_t k = 0; k < q_size_; ++k) bigger[k] = ring_[(q_head_ + k) % ring_.size()];
        ring_ = std::move(bigger);
        q_head_ = 0;
      }
      ring_[(q_head_ + q_size_) % ring_.size()] = {d[i], si[i].valid_data, si[i].source_timestamp,
                                                   si[i].publication_handle};
      ++q_size_;
      if (q_size_ > max_queued_) ddsi_serdata_unref(pop_locked().data);  // keep-last: the oldest goes
    }
    if (n < int(kChunk)) return;
  }
}

DdsReader::Queued DdsReader::pop_locked() {
  Queued q = ring_[q_head_];
  q_head_ = (q_head_ + 1) % ring_.size();
  --q_size_;
  return q;
}

DdsReader::Publication& DdsReader::publication(uint64_t handle) {
  if (last_pub_ && last_pub_->first == handle) return last_pub_->second;  // the common case: one writer
  auto it = pubs_.find(handle);
  if (it == pubs_.end()) {
    Publication p;
    if (dds_builtintopic_endpoint_t* ep = dds_get_matched_publication_data(reader_, handle)) {
      std::memcpy(p.gid.data(), ep->key.v, 16);
      dds_builtintopic_free_endpoint(ep);
    }
    it = pubs_.emplace(handle, p).first;
  }
  last_pub_ = &*it;
  return it->second;
}

bool DdsReader::take(void* cpp_out, MessageInfo& info) {
  for (;;) {
    Queued q;
    {
      std::lock_guard l(q_mu_);
      if (q_size_ == 0) fill_locked();
      if (q_size_ == 0) return false;
      q = pop_locked();
    }
    ddsi_serdata* d = q.data;
    bool ok = false;
    if (q.valid) {  // else a dispose/unregister notification
      std::string why;
      ok = decode(sd(d), ts_, cpp_out, &why);
      if (!ok && rejected_.fetch_add(1) % 1000 == 0) {  // garbage from the network: dropped, reported
        log_line(Severity::Error, "cairn.dds",
                 std::string("dropped a malformed ") + ts_.ros_type_name + " sample (" +
                     std::to_string(rejected_.load()) + " so far): " + why);
      }
    }
    ddsi_serdata_unref(d);
    if (!ok) continue;
    Publication& p = publication(q.publication_handle);
    info.source_timestamp_ns = q.source_timestamp;
    info.publisher_gid = p.gid;
    info.sequence_number = ++p.received;
    info.from_intra_process = false;
    return true;
  }
}

int DdsReader::matched() const {
  dds_subscription_matched_status_t st;
  if (dds_get_subscription_matched_status(reader_, &st) != DDS_RETCODE_OK) return 0;
  return static_cast<int>(st.current_count);
}

}  // namespace cairn
