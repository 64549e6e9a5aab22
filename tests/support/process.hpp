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
// Quotes one argument for the shell.
std::string shell_quote(const std::string& argument);
// build/bin/skytrace
std::filesystem::path skytrace_executable();
// Whether a program is on PATH.
bool program_available(const std::string& name);

}  // namespace skytrace::test
