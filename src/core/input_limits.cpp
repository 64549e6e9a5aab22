#include "skytrace/core/input_limits.hpp"

#include <cerrno>
#include <cstdlib>

namespace skytrace {
namespace {

// A positive whole number from the environment times `unit`, else `fallback` (already in units).
std::uint64_t from_environment(const char* variable, std::uint64_t fallback, std::uint64_t unit) {
  const char* text = std::getenv(variable);
  if (text == nullptr || *text == '\0') return fallback;
  errno = 0;
  char* end = nullptr;
  const unsigned long long value = std::strtoull(text, &end, 10);
  if (errno != 0 || end == text || *end != '\0' || value == 0 || value > UINT64_MAX / unit) return fallback;
  return static_cast<std::uint64_t>(value) * unit;
}

InputLimits read_limits() {
  InputLimits limits;
  limits.max_decompressed_bytes =
      from_environment("SKYTRACE_MAX_DECOMPRESSED_MB", limits.max_decompressed_bytes, std::uint64_t{1} << 20);
  limits.max_grid_points = from_environment("SKYTRACE_MAX_GRID_POINTS", limits.max_grid_points, 1);
  limits.max_table_rows = from_environment("SKYTRACE_MAX_TABLE_ROWS", limits.max_table_rows, 1);
  limits.max_way_nodes = from_environment("SKYTRACE_MAX_WAY_NODES", limits.max_way_nodes, 1);
  limits.max_sweep_points = from_environment("SKYTRACE_MAX_SWEEP_POINTS", limits.max_sweep_points, 1);
  return limits;
}

}  // namespace

const InputLimits& input_limits() {
  static const InputLimits limits = read_limits();
  return limits;
}

std::string limit_hint(std::uint64_t limit, const char* variable) {
  return "(limit " + std::to_string(limit) + "; raise it with " + variable + "=...)";
}

}  // namespace skytrace
