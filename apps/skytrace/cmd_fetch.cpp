// Placeholder replaced by the fetch implementation.
#include "commands.hpp"
namespace skytrace::cli {
void register_fetch_command(CLI::App& /*app*/, int& /*exit_code*/) {}
}  // namespace skytrace::cli
