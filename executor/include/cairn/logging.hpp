// Logging with severity. One line per record on stderr: [LEVEL] [wall time] [logger]: text
#ifndef CAIRN_LOGGING_HPP
#define CAIRN_LOGGING_HPP

#include <sstream>
#include <string>
#include <optional>
#include <string_view>

namespace cairn {

enum class Severity { Debug = 10, Info = 20, Warn = 30, Error = 40, Fatal = 50 };

/// Process-wide threshold (CAIRN_LOG_LEVEL=debug|info|warn|error at start-up).
void set_log_threshold(Severity s);
Severity log_threshold();
std::optional<Severity> parse_severity(std::string_view s);
void log_line(Severity s, std::string_view logger, std::string_view text);

class Logger {
 public:
  Logger() = default;
  explicit Logger(std::string name) : name_(std::move(name)) {}
  const std::string& name() const { return name_; }
  bool enabled(Severity s) const { return s >= log_threshold(); }
  void log(Severity s, std::string_view text) const {
    if (enabled(s)) log_line(s, name_, text);
  }

 private:
  std::string name_ = "cairn";
};

}  // namespace cairn

#define CAIRN_LOG(logger, severity, expr)                  \
  do {                                                     \
    const ::cairn::Logger& cairn_lg_ = (logger);           \
    if (cairn_lg_.enabled(severity)) {                     \
      std::ostringstream cairn_os_;                        \
      cairn_os_ << expr;                                   \
      ::cairn::log_line(severity, cairn_lg_.name(), cairn_os_.str()); \
    }                                                      \
  } while (0)
#define CAIRN_DEBUG(logger, expr) CAIRN_LOG(logger, ::cairn::Severity::Debug, expr)
#define CAIRN_INFO(logger, expr) CAIRN_LOG(logger, ::cairn::Severity::Info, expr)
#define CAIRN_WARN(logger, expr) CAIRN_LOG(logger, ::cairn::Severity::Warn, expr)
#define CAIRN_ERROR(logger, expr) CAIRN_LOG(logger, ::cairn::Severity::Error, expr)

#endif  // CAIRN_LOGGING_HPP
