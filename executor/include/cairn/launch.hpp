// Launch specs: YAML that declares containers, components, standalone processes and the DDS domain.
// The whole spec is parsed and validated before anything starts; every error is one line naming
// file:line and the key.
#ifndef CAIRN_LAUNCH_HPP
#define CAIRN_LAUNCH_HPP

#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "cairn/component.hpp"
#include "cairn/parameters.hpp"
#include "cairn/qos.hpp"

namespace cairn {

class LaunchError : public std::runtime_error {
 public:
  LaunchError(const std::string& file, int line, const std::string& what)
      : std::runtime_error(file + ":" + std::to_string(line) + ": " + what), file_(file), line_(line) {}
  int line() const { return line_; }
  const std::string& file() const { return file_; }

 private:
  std::string file_;
  int line_;
};

struct LaunchComponent {
  std::string class_name;
  std::string name;
  std::string ns = "/";
  std::map<std::string, ParameterValue> params;
  std::map<std::string, std::string> remaps;
  std::map<std::string, QoSOverride> qos;
  bool isolated = false;
  bool use_intra_process = true;
  int line = 0, params_line = 0, remap_line = 0, qos_line = 0;
  std::string fqn() const { return (ns == "/" ? "" : ns) + "/" + name; }
};

/// Respawn backoff: the k-th respawn in a row waits min(delay * 2^(k-1), max(delay, 30 s)); a process that ran
/// 10 s or longer before it died starts the count again.
struct RespawnPolicy {
  bool respawn = false;
  double delay_s = 0.1;
  double delay_for(int consecutive) const;
};

struct LaunchContainer {
  std::string name;
  std::size_t threads = 1;
  RespawnPolicy respawn{true, 0.1};  ///< keys respawn, respawn_delay; also for its isolated components' containers
  std::vector<LaunchComponent> components;
  int line = 0;
};

struct LaunchProcess {
  std::string name;
  std::vector<std::string> cmd;
  RespawnPolicy respawn;
  int line = 0;
};

struct LaunchSpec {
  std::string file;
  std::optional<int> domain_id;
  double load_timeout_s = 10.0;
  std::vector<LaunchContainer> containers;
  std::vector<LaunchProcess> processes;
};

/// Parses a spec (unknown keys, wrong types, missing names, duplicates are LaunchErrors).
LaunchSpec parse_launch_spec_text(const std::string& text, const std::string& file);
LaunchSpec parse_launch_spec(const std::string& path);

/// Constructs every component in a dry-run context (nothing touches DDS) to check its class, parameter
/// names, types and ranges; then checks the topic graph after remapping: one message type per topic and
/// compatible QoS between publishers and subscriptions.
void validate_launch_spec(const LaunchSpec& spec, ComponentLoader& loader);

/// Parses and validates spec text (component classes from the default ComponentLoader search path): the
/// one-line error "file:line: ..." of the first problem, or "" when the spec is valid.
std::string launch_spec_error(const std::string& text, const std::string& file);

/// Strict number (launch spec values and command-line options): the whole text is a finite decimal number;
/// otherwise std::nullopt ("5 6", "abc", "nan", "inf", "" are not numbers). The parser every cairn package
/// shares (cmake/include/cairn/strict_number.hpp), exported here for code built outside the source tree.
std::optional<double> parse_number(const std::string& text);
/// Bad command-line input ("cairn: <verb>: <what>", exit 2).
class OptionError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};
/// The value of a numeric command-line option: a strict number in [lo, hi], and integral if `integer`;
/// otherwise throws OptionError("<option> expects a number in [lo, hi], got '<text>'").
double option_number(const std::string& option, const std::string& text, double lo, double hi, bool integer = false);

/// `cairn launch <spec> [--duration S] [--check]`: validate, start containers (child processes), load
/// components, supervise (respawn crashed containers and reload their components), stop on SIGINT/SIGTERM.
int run_launch_main(int argc, char** argv);

}  // namespace cairn

#endif  // CAIRN_LAUNCH_HPP
