// Observability: the status-transition event stream of a tree, written to a file (FileLogger) and read back
// (TraceReplay). Text format, one record per line:
//   # cairn-bt-trace 1
//   N <uid> <path>                              node table (written when the logger attaches)
//   E <step> <time_ns> <uid> <OLD> <NEW>        one status transition
#pragma once

#include <cstdint>
#include <iosfwd>
#include <memory>
#include <string>
#include <vector>

#include "cairn/bt_executive/tree.hpp"

namespace cairn::bt {

/// `<step> <path> <OLD> -> <NEW>` (the `cairn bt run --trace` line).
std::string formatTransition(std::uint64_t step, std::string_view path, NodeStatus old_s, NodeStatus new_s);

class FileLogger {
 public:
  /// Writes to `os` (which must outlive the logger) from now on.
  FileLogger(Tree& tree, std::ostream& os);
  ~FileLogger();
  FileLogger(const FileLogger&) = delete;
  FileLogger& operator=(const FileLogger&) = delete;
  void flush();

 private:
  Tree& tree_;
  std::ostream& os_;
  std::size_t handle_;
};

struct RecordedTransition {
  std::uint64_t step;
  std::int64_t time_ns;
  std::uint32_t uid;
  NodeStatus old_status;
  NodeStatus new_status;
};

class TraceReplay {
 public:
  /// Parses a trace; throws std::runtime_error("line N: ...") on malformed input: no '# cairn-bt-trace 1' first
  /// line (also an empty stream or another version), a record with missing or extra fields, a negative time.
  static TraceReplay read(std::istream& is);
  const std::vector<std::string>& paths() const { return paths_; }
  const std::vector<RecordedTransition>& transitions() const { return events_; }
  /// Status of every node (by uid) after all transitions of steps <= `step`.
  std::vector<NodeStatus> statusesAfter(std::uint64_t step) const;
  std::uint64_t lastStep() const { return events_.empty() ? 0 : events_.back().step; }

 private:
  std::vector<std::string> paths_;
  std::vector<RecordedTransition> events_;
};

/// Indented tree view with statuses (used by `cairn bt watch` / `replay`).
std::string renderTree(const std::vector<std::string>& paths, const std::vector<NodeStatus>& statuses,
                       bool color = false);

}  // namespace cairn::bt
