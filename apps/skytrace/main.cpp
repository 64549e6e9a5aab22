// skytrace: GNSS receiver simulator for robotics.
#include <spdlog/spdlog.h>

#include <csignal>
#include <iostream>

#include "commands.hpp"
#include "skytrace/core/allocator.hpp"
#include "skytrace/core/cancellation.hpp"
#include "skytrace/core/version.hpp"

namespace skytrace::cli {

int report_error(const Error& error) {
  std::cerr << "skytrace: error: " << error.message << "\n";
  return exit_code_for(error);
}

int exit_code_for(const Error& error) {
  switch (error.code) {
    case ErrorCode::kInvalidArgument: return kExitUsage;
    case ErrorCode::kParse:
    case ErrorCode::kIo:
    case ErrorCode::kNotFound:
    case ErrorCode::kUnsupported: return kExitInput;
    case ErrorCode::kOutOfRange: return kExitCoverage;
    case ErrorCode::kNetwork: return kExitNetwork;
    case ErrorCode::kOutput: return kExitOutput;
    case ErrorCode::kCancelled: return 128 + cancellation_signal().value_or(SIGINT);  // as the shell reports a signal
  }
  return kExitRuntime;
}

}  // namespace skytrace::cli

int main(int argc, char** argv) {
  using namespace skytrace::cli;
  skytrace::tune_allocator_for_epochs();
  CLI::App app{"skytrace: simulates what a GNSS receiver records, from real ephemerides and a 3D world"};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("skytrace ") + skytrace::version());
  int exit_code = kExitOk;
  skytrace::install_cancellation_handlers();  // serve and gz install their own stop handlers over these
  register_run_command(app, exit_code);
  register_iq_command(app, exit_code);
  register_orbits_command(app, exit_code);
  register_fetch_command(app, exit_code);
  register_compare_command(app, exit_code);
  register_gz_command(app, exit_code);
  register_serve_command(app, exit_code);
  register_position_command(app, exit_code);
  register_sweep_command(app, exit_code);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? kExitOk : kExitUsage;
  } catch (const skytrace::ErrorException& e) {
    return report_error(e.error());
  } catch (const std::bad_alloc&) {
    std::cerr << "skytrace: error: out of memory (an input asks for more than this machine has; see docs/reliability.md)\n";
    return kExitRuntime;
  } catch (const std::exception& e) {
    std::cerr << "skytrace: internal error: " << e.what() << "\n";
    return kExitRuntime;
  }
  return exit_code;
}
