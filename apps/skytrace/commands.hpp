// Subcommands of the skytrace command-line tool. Each registers itself on the CLI11 app and
// returns its exit code through `exit_code` when selected.
#pragma once

#include <CLI/CLI.hpp>

#include "skytrace/core/error.hpp"

namespace skytrace::cli {


// Documented exit codes (README "Exit codes").
enum ExitCode : int {
  kExitOk = 0,
  kExitRuntime = 1,     // unexpected internal failure
  kExitUsage = 2,       // bad command line
  kExitInput = 3,       // bad or missing input file, bad scenario
  kExitCoverage = 4,    // time or position outside what the data covers
  kExitOutput = 5,      // outputs could not be written
  kExitNetwork = 6,     // a download failed, or a service (Slurm) could not be reached
  kExitSweepFailed = 7, // a sweep ended with failed points (its manifest lists them)
};

// Maps a library error to the exit code and prints it on stderr.
int report_error(const Error& error);
// The exit code of an error, without printing it.
int exit_code_for(const Error& error);

void register_orbits_command(CLI::App& app, int& exit_code);
void register_fetch_command(CLI::App& app, int& exit_code);
void register_run_command(CLI::App& app, int& exit_code);
void register_iq_command(CLI::App& app, int& exit_code);
void register_compare_command(CLI::App& app, int& exit_code);
void register_gz_command(CLI::App& app, int& exit_code);
void register_serve_command(CLI::App& app, int& exit_code);
void register_position_command(CLI::App& app, int& exit_code);
void register_sweep_command(CLI::App& app, int& exit_code);

}  // namespace skytrace::cli
