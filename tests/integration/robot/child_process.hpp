// Long-running processes of the robot-integration tests (roscore, the ROS node, the Gazebo bridge):
// started in a process group of their own with extra environment, output to a log file, and ended
// (SIGINT, then SIGKILL) with their whole group when the owning object goes away, even when a test
// fails half-way.
#pragma once

#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace skytrace::test {

class ChildProcess {
 public:
  ChildProcess() = default;
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;
  ~ChildProcess() { stop(); }

  // Starts argv[0] (searched on PATH) with `env` added to this process's environment.
  bool start(const std::vector<std::string>& argv, const std::map<std::string, std::string>& env,
             const std::filesystem::path& log) {
    log_ = log;
    pid_ = fork();
    if (pid_ < 0) return false;
    if (pid_ == 0) {
      setpgid(0, 0);
      for (const auto& [key, value] : env) setenv(key.c_str(), value.c_str(), 1);
      const std::string log_path = log.string();
      FILE* out = std::fopen(log_path.c_str(), "w");
      if (out != nullptr) {
        dup2(fileno(out), STDOUT_FILENO);
        dup2(fileno(out), STDERR_FILENO);
      }
      std::vector<char*> args;
      for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
      args.push_back(nullptr);
      execvp(args[0], args.data());
      std::perror("execvp");
      _exit(127);
    }
    setpgid(pid_, pid_);  // also from the parent: no race with the child's own call
    group_ = pid_;
    return true;
  }

  // Whether the process still runs (reaps it when it has ended).
  bool running() {
    if (pid_ <= 0) return false;
    int status = 0;
    const pid_t r = waitpid(pid_, &status, WNOHANG);
    if (r == pid_) {
      exit_status_ = status;
      pid_ = -1;
      return false;
    }
    return true;
  }

  // SIGINT to the group (the ROS way to ask a node to stop), SIGKILL after `grace`; returns the
  // wait status (or -1 when it had already been reaped).
  int stop(std::chrono::milliseconds grace = std::chrono::milliseconds(5000)) {
    if (pid_ > 0) kill(-pid_, SIGINT);
    const auto deadline = std::chrono::steady_clock::now() + grace;
    while (pid_ > 0 && std::chrono::steady_clock::now() < deadline) {
      if (!running()) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    if (pid_ > 0) {
      kill(-pid_, SIGKILL);
      int status = 0;
      waitpid(pid_, &status, 0);
      exit_status_ = status;
      pid_ = -1;
    }
    // Children that outlived the leader (roscore's rosmaster and rosout) share its group.
    if (group_ > 0) kill(-group_, SIGKILL);
    group_ = -1;
    return exit_status_;
  }

  [[nodiscard]] std::string log_text() const {
    std::ifstream in(log_);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  }

 private:
  pid_t pid_ = -1;
  pid_t group_ = -1;  // kept after the leader is reaped
  int exit_status_ = -1;
  std::filesystem::path log_;
};

// A TCP port no one listens on now (the kernel's pick).
inline int free_tcp_port() {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  addr.sin_port = 0;
  bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof(addr));
  socklen_t len = sizeof(addr);
  getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &len);
  close(fd);
  return ntohs(addr.sin_port);
}

// Polls `condition` every 50 ms until it holds or `timeout` passes.
template <typename F>
bool wait_until(F condition, std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < deadline) {
    if (condition()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return condition();
}

}  // namespace skytrace::test
