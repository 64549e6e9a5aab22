// Running the project's executables and external programs from tests.
#pragma once

#include <filesystem>
#include <string>

namespace skytrace::test {

struct ProcessResult {
  int exit_code = -1;
  std::string output;  // stdout and stderr together
};

// Runs a shell command line (arguments must already be quoted) and captures its output.
ProcessResult run_command(const std::string& command_line);

struct MeasuredProcess {
  int exit_code = -1;       // -1 when killed by a signal or the timeout
  int signal = 0;           // the signal that ended it, if any
  bool timed_out = false;   // killed (with its process group) after the timeout
  double wall_s = 0.0;
  long max_rss_kib = 0;     // peak resident memory of the process and the children it waited for
  std::string output;       // stdout and stderr together
};
// Runs `command_line` through /bin/sh in a process group of its own, killing the group after
// `timeout_s`; the peak memory comes from wait4's rusage.
MeasuredProcess run_measured(const std::string& command_line, double timeout_s);
// Quotes one argument for the shell.
std::string shell_quote(const std::string& argument);
// build/bin/skytrace
std::filesystem::path skytrace_executable();
// A free port of the loopback for SOCK_STREAM or SOCK_DGRAM (closed again: a short race with other
// programs, fine in tests).
int free_loopback_port(int socket_type);
// Whether a program is on PATH.
bool program_available(const std::string& name);

// A program running in the background through /bin/sh in a process group of its own, its output
// in `log`; stopped (the signal, then SIGKILL after 10 s) when destroyed.
class Background {
 public:
  Background(const std::string& command, const std::filesystem::path& log);
  ~Background() { stop(); }
  Background(const Background&) = delete;
  Background& operator=(const Background&) = delete;
  // Sends the signal and waits up to 10 s; the exit status (-1 when it ended by a signal or had to
  // be killed).
  int stop(int signal_number = 15 /* SIGTERM */);
  // Whether it is still running (reaps it when it has ended).
  [[nodiscard]] bool running();

 private:
  int pid_ = -1;
  int status_ = -1;
};

}  // namespace skytrace::test
