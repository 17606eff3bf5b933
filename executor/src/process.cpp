#include "cairn/process.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <thread>

namespace cairn {

pid_t spawn_process(const std::vector<std::string>& argv) {
  if (argv.empty()) throw std::runtime_error("empty command");
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  int err_pipe[2];
  if (pipe2(err_pipe, O_CLOEXEC) != 0) throw std::runtime_error("pipe failed");
  const pid_t parent = getpid();
  const pid_t pid = fork();
  if (pid < 0) throw std::runtime_error(std::string("fork failed: ") + std::strerror(errno));
  if (pid == 0) {
    close(err_pipe[0]);
    setpgid(0, 0);
    prctl(PR_SET_PDEATHSIG, SIGTERM);
    if (getppid() != parent) _exit(127);
    sigset_t none;
    sigemptyset(&none);
    sigprocmask(SIG_SETMASK, &none, nullptr);
    signal(SIGINT, SIG_DFL);
    signal(SIGTERM, SIG_DFL);
    execvp(args[0], args.data());
    const int e = errno;
    [[maybe_unused]] auto r = write(err_pipe[1], &e, sizeof e);
    _exit(127);
  }
  close(err_pipe[1]);
  setpgid(pid, pid);  // also here: a stop right after the fork must reach the group (the child may not have run yet)
  int child_errno = 0;
  const ssize_t n = read(err_pipe[0], &child_errno, sizeof child_errno);
  close(err_pipe[0]);
  if (n == sizeof child_errno) {
    waitpid(pid, nullptr, 0);
    throw std::runtime_error("cannot start '" + argv[0] + "': " + std::strerror(child_errno));
  }
  return pid;
}

void stop_processes(const std::vector<pid_t>& pids, std::chrono::milliseconds grace) {
  // The whole group: a child's own children (a shell's commands) go too, not re-parented to init.
  auto signal_group = [](pid_t p, int sig) {
    if (kill(-p, sig) != 0) kill(p, sig);  // not (yet) a group leader: the process itself
  };
  for (pid_t p : pids)
    if (p > 0) signal_group(p, SIGTERM);
  const auto deadline = std::chrono::steady_clock::now() + grace;
  for (pid_t p : pids) {
    if (p <= 0) continue;
    int st;
    while (waitpid(p, &st, WNOHANG) == 0) {
      if (std::chrono::steady_clock::now() > deadline) {
        signal_group(p, SIGKILL);
        waitpid(p, &st, 0);
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    // Members of its group that outlived it (not our children: polled, not reaped) get the rest of the grace.
    while (kill(-p, 0) == 0 && std::chrono::steady_clock::now() <= deadline)
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    kill(-p, SIGKILL);
  }
}

std::string self_executable() {
  std::error_code ec;
  auto p = std::filesystem::read_symlink("/proc/self/exe", ec);
  return ec ? std::string("cairn") : p.string();
}

std::string describe_wait_status(int status) {
  if (WIFEXITED(status)) return "exited with code " + std::to_string(WEXITSTATUS(status));
  if (WIFSIGNALED(status)) {
    const int s = WTERMSIG(status);
    return "killed by signal " + std::to_string(s) + " (" + (sigabbrev_np(s) ? std::string("SIG") + sigabbrev_np(s) : "?") + ")";
  }
  return "stopped";
}

}  // namespace cairn
