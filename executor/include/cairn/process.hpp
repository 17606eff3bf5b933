// Child processes for the launcher and the isolated-component supervisor.
#ifndef CAIRN_PROCESS_HPP
#define CAIRN_PROCESS_HPP

#include <sys/types.h>

#include <string>
#include <vector>

namespace cairn {

/// Starts argv[0] (searched in PATH when it has no '/') in its own process group; the child gets SIGTERM
/// when this process dies. Returns the pid; throws std::runtime_error if the program cannot be started.
pid_t spawn_process(const std::vector<std::string>& argv);
/// Path of the running executable.
std::string self_executable();
/// "exited with code N" / "killed by signal N (SIGSEGV)"
std::string describe_wait_status(int status);

}  // namespace cairn

#endif  // CAIRN_PROCESS_HPP
