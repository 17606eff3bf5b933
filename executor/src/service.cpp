#include "cairn/service.hpp"

#include <cstring>
#include <vector>

#include "dds/dds.h"

namespace cairn::detail {

uint64_t client_id_from_gid(const Gid& g) {
  // FNV-1a over the 16 GUID bytes
  uint64_t h = 1469598103934665603ull;
  for (uint8_t b : g) {
    h ^= b;
    h *= 1099511628211ull;
  }
  return h;
}

Gid reader_gid(int32_t reader) {
  Gid out{};
  dds_guid_t g;
  if (dds_get_guid(reader, &g) == DDS_RETCODE_OK) std::memcpy(out.data(), g.v, 16);
  return out;
}

bool writer_matches_client(int32_t writer, uint64_t client_id) {
  dds_instance_handle_t handles[64];
  const dds_return_t n = dds_get_matched_subscriptions(writer, handles, 64);
  for (dds_return_t i = 0; i < n && i < 64; ++i) {
    if (dds_builtintopic_endpoint_t* ep = dds_get_matched_subscription_data(writer, handles[i])) {
      Gid g;
      std::memcpy(g.data(), ep->key.v, 16);
      dds_builtintopic_free_endpoint(ep);
      if (client_id_from_gid(g) == client_id) return true;
    }
  }
  return false;
}

std::string request_topic(const std::string& service) {
  return "rq" + (service.rfind('/', 0) == 0 ? service : "/" + service) + "Request";
}

std::string reply_topic(const std::string& service) {
  return "rr" + (service.rfind('/', 0) == 0 ? service : "/" + service) + "Reply";
}

}  // namespace cairn::detail
