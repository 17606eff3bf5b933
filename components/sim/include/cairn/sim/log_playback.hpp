// Streaming playback of a CARMEN log (cairn/sim/carmen.hpp): the records in file order, read as they are
// consumed, with a bounded look-ahead (constant memory whatever the log's length). Shared by the LogPlayer
// component (which publishes them) and `cairn log play --print`; pacing is the caller's (wall clock or
// consumers' acknowledgments).
#pragma once

#include <cstddef>
#include <deque>
#include <memory>
#include <optional>
#include <string>

#include "cairn/sim/carmen.hpp"

namespace cairn::sim {

struct LogPlaybackOptions {
  CarmenReaderOptions reader;
  std::size_t lookahead = 32;  ///< records read ahead of the one being played (>= 1): memory bound
  std::size_t limit = 0;       ///< records per pass; 0 = the whole log
};

class LogPlayback {
 public:
  /// Opens the log and reads the first `lookahead` records, so a missing or empty log, or a malformed line
  /// among the first records, throws InputError (file:line) here, before anything is played.
  explicit LogPlayback(std::string path, LogPlaybackOptions options = {});

  /// The next record without consuming it; nullptr at the end of the pass (end of log or `limit`). A
  /// malformed line further on (without skip_malformed) throws InputError when playback reaches it, after
  /// every record before it was played.
  const CarmenRecord* peek();
  /// Consumes the record peek() returned and reads one more record ahead.
  void pop();
  /// Starts a new pass at the first record (reopens the file).
  void rewind();

  std::size_t buffered() const { return ahead_.size(); }   ///< records held in memory now
  std::size_t maxBuffered() const { return max_buffered_; } ///< high-water mark over all passes
  std::size_t played() const { return played_; }            ///< records consumed in this pass
  const CarmenStats& readerStats() const { return reader_->stats(); }
  const std::string& path() const { return path_; }

 private:
  void fill();
  std::string path_;
  LogPlaybackOptions options_;
  std::unique_ptr<CarmenReader> reader_;
  std::deque<CarmenRecord> ahead_;
  std::optional<InputError> error_;  ///< malformed line met by the look-ahead, raised when reached
  bool eof_ = false;
  std::size_t read_ = 0, played_ = 0, max_buffered_ = 0;
};

}  // namespace cairn::sim
