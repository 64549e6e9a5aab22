// Stated limits on what one input may make skytrace allocate, so that a small hostile or broken
// file (a gzip bomb, an IONEX header with a 0.0001 degree grid) fails fast with a clear error
// instead of exhausting memory. Each limit can be raised through its environment variable for a
// legitimate larger input; docs/reliability.md lists them.
#pragma once

#include <cstdint>
#include <string>

namespace skytrace {

struct InputLimits {
  // Decompressed size of one gzip or .Z file (SKYTRACE_MAX_DECOMPRESSED_MB, default 1024 MiB; a
  // day of 1 Hz multi-GNSS RINEX 3 observations is about 600 MiB).
  std::uint64_t max_decompressed_bytes = std::uint64_t{1024} << 20;
  // Grid points of one IONEX map, and of all maps of a file together (SKYTRACE_MAX_GRID_POINTS,
  // default 10^7 per map, 5x that per file; a global 2.5 x 5 degree map has 5,183).
  std::uint64_t max_grid_points = 10'000'000;
  // Rows one `skytrace orbits` table may have (SKYTRACE_MAX_TABLE_ROWS, default 10^8).
  std::uint64_t max_table_rows = 100'000'000;
  // Nodes of one OpenStreetMap way outlining a building (SKYTRACE_MAX_WAY_NODES, default 10,000;
  // the largest real footprints have a few thousand).
  std::uint64_t max_way_nodes = 10'000;
  // Points of one `skytrace sweep` (SKYTRACE_MAX_SWEEP_POINTS, default 10^7; a grid of a few axes
  // multiplies fast).
  std::uint64_t max_sweep_points = 10'000'000;
};

// The limits in force: defaults overridden by the environment, read once.
[[nodiscard]] const InputLimits& input_limits();

// "(limit N; raise it with VARIABLE=...)" for messages.
[[nodiscard]] std::string limit_hint(std::uint64_t limit, const char* variable);

}  // namespace skytrace
