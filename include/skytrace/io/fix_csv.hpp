// Position fixes as CSV: one row per epoch (`skytrace position`, `skytrace run`'s fix.csv).
#pragma once

#include <string>

#include "skytrace/positioning/spp.hpp"

namespace skytrace::io {

// The header line (with its newline).
[[nodiscard]] const char* fix_csv_header();
// One row (with its newline); a fix of type none has empty position cells and the reason.
[[nodiscard]] std::string fix_csv_row(const positioning::PositionFix& fix);

}  // namespace skytrace::io
