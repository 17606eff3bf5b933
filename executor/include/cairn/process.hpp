// Child processes for the launcher and the isolated-component supervisor.
#ifndef CAIRN_PROCESS_HPP
#define CAIRN_PROCESS_HPP

#include <sys/types.h>

#include <chrono>
#include <string>
#include <vector>

namespace cairn {

/// Starts argv[0] (searched in PATH when it has no '/') in its own process group; the child gets SIGTERM
/// when this process dies. Returns the pid; throws std::runtime_error if the program cannot be started.
pid_t spawn_process(const std::vector<std::string>& argv);
/// Stops processes started by spawn_process: SIGTERM to each one's process group, then waits (reaps) up to
/// `grace` in total and sends SIGKILL to the groups of those still running; members of a group that outlive its
/// leader are killed too.
void stop_processes(const std::vector<pid_t>& pids, std::chrono::milliseconds grace = std::chrono::seconds(5));
/// Path of the running executable.
std::string self_executable();
/// "exited with code N" / "killed by signal N (SIGSEGV)"
std::string describe_wait_status(int status);

}  // namespace cairn

#endif  // CAIRN_PROCESS_HPP
