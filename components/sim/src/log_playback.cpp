#include "cairn/sim/log_playback.hpp"

#include <algorithm>
#include <utility>

namespace cairn::sim {

LogPlayback::LogPlayback(std::string path, LogPlaybackOptions options)
    : path_(std::move(path)), options_(std::move(options)) {
  options_.lookahead = std::max<std::size_t>(options_.lookahead, 1);
  rewind();
  if (error_) throw *error_;  // within the first `lookahead` records: rejected before anything is played
  if (ahead_.empty()) throw InputError(path_, 0, "no laser or odometry records");
}

void LogPlayback::rewind() {
  reader_ = std::make_unique<CarmenReader>(path_, options_.reader);
  ahead_.clear();
  error_.reset();
  eof_ = false;
  read_ = played_ = 0;
  fill();
}

void LogPlayback::fill() {
  while (!eof_ && ahead_.size() < options_.lookahead) {
    if (options_.limit > 0 && read_ >= options_.limit) {
      eof_ = true;
      break;
    }
    CarmenRecord rec;
    try {
      if (!reader_->next(rec)) {
        eof_ = true;
        break;
      }
    } catch (const InputError& e) {
      error_ = e;  // raised once the records before it have been played
      eof_ = true;
      break;
    }
    ahead_.push_back(std::move(rec));
    ++read_;
  }
  max_buffered_ = std::max(max_buffered_, ahead_.size());
}

const CarmenRecord* LogPlayback::peek() {
  if (!ahead_.empty()) return &ahead_.front();
  if (error_) {
    const InputError e = *error_;
    error_.reset();
    throw e;
  }
  return nullptr;
}

void LogPlayback::pop() {
  if (ahead_.empty()) return;
  ahead_.pop_front();
  ++played_;
  fill();
}

}  // namespace cairn::sim
