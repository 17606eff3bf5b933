// Running the cairn CLI from tests.
#ifndef CAIRN_TEST_SUBPROCESS_HPP
#define CAIRN_TEST_SUBPROCESS_HPP

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>

#include "cairn/process.hpp"

namespace cairn::testing {

struct RunResult {
  int exit_code = -1;
  std::string output;  ///< stdout and stderr
};

/// Runs a shell command line, capturing stdout+stderr.
inline RunResult run(const std::string& cmd) {
  RunResult r;
  FILE* p = popen((cmd + " 2>&1").c_str(), "r");
  if (!p) return r;
  std::array<char, 4096> buf;
  size_t n;
  while ((n = fread(buf.data(), 1, buf.size(), p)) > 0) r.output.append(buf.data(), n);
  const int st = pclose(p);
  r.exit_code = WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
  return r;
}

/// Starts `cmd` in the background with stdout+stderr into `log`; returns the pid of the shell's exec.
/// The log is emptied here, before the child exists: the shell's own `>` truncates only once it runs, so a caller
/// polling the log at once could read a stale file left by an earlier test process with the same pid (CI saw a
/// "wait for 5 lines" pass in 1 ms on an old log and SIGTERM the launch before it had installed its handler).
inline pid_t start(const std::string& cmd, const std::string& log) {
  std::ofstream(log, std::ios::trunc).flush();
  return spawn_process({"/bin/sh", "-c", "exec " + cmd + " >> " + log + " 2>&1"});
}

inline std::string slurp(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

inline int count(const std::string& hay, const std::string& needle) {
  int n = 0;
  for (size_t p = hay.find(needle); p != std::string::npos; p = hay.find(needle, p + 1)) ++n;
  return n;
}

}  // namespace cairn::testing

#endif  // CAIRN_TEST_SUBPROCESS_HPP
