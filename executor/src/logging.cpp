#include "cairn/logging.hpp"

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <mutex>

namespace cairn {

std::optional<Severity> parse_severity(std::string_view s) {
  if (s == "debug" || s == "DEBUG") return Severity::Debug;
  if (s == "info" || s == "INFO") return Severity::Info;
  if (s == "warn" || s == "WARN" || s == "warning") return Severity::Warn;
  if (s == "error" || s == "ERROR") return Severity::Error;
  if (s == "fatal" || s == "FATAL") return Severity::Fatal;
  return std::nullopt;
}

static std::atomic<int>& threshold() {
  static std::atomic<int> t = [] {
    const char* env = std::getenv("CAIRN_LOG_LEVEL");
    auto s = env ? parse_severity(env) : std::nullopt;
    return static_cast<int>(s.value_or(Severity::Info));
  }();
  return t;
}

void set_log_threshold(Severity s) { threshold().store(static_cast<int>(s)); }
Severity log_threshold() { return static_cast<Severity>(threshold().load(std::memory_order_relaxed)); }

void log_line(Severity s, std::string_view logger, std::string_view text) {
  static std::mutex mu;
  const char* lv = s == Severity::Debug ? "DEBUG" : s == Severity::Info ? "INFO" : s == Severity::Warn ? "WARN"
                                                : s == Severity::Error ? "ERROR" : "FATAL";
  const double t = std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
  std::lock_guard lock(mu);
  std::fprintf(stderr, "[%s] [%.6f] [%.*s]: %.*s\n", lv, t, static_cast<int>(logger.size()), logger.data(),
               static_cast<int>(text.size()), text.data());
  std::fflush(stderr);
}

}  // namespace cairn
