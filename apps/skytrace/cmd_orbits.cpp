// Placeholder replaced by the orbits implementation.
#include "commands.hpp"
namespace skytrace::cli {
void register_orbits_command(CLI::App& /*app*/, int& /*exit_code*/) {}
}  // namespace skytrace::cli
