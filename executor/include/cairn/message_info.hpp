#ifndef CAIRN_MESSAGE_INFO_HPP
#define CAIRN_MESSAGE_INFO_HPP

#include <array>
#include <cstdint>

namespace cairn {

using Gid = std::array<uint8_t, 16>;

/// What a subscription learns about a message besides its content; filled on both paths.
struct MessageInfo {
  int64_t source_timestamp_ns = 0;    ///< publisher's clock when published (DDS source timestamp)
  int64_t received_timestamp_ns = 0;  ///< subscriber's clock when delivered
  Gid publisher_gid{};                ///< DDS GUID of the publisher's writer (a process-unique id if it has none)
  /// Publisher-side sequence number on the intra-process path. Cyclone DDS 0.10 does not expose the
  /// writer sequence number to readers, so on the DDS path this is the per-publisher reception count.
  uint64_t sequence_number = 0;
  bool from_intra_process = false;
};

}  // namespace cairn

#endif  // CAIRN_MESSAGE_INFO_HPP
