// The program's version (CMake's project version): --version, RINEX and MCAP headers, summary.json,
// the NTRIP user agent. Defined in one source file so that a new version recompiles only that one.
#pragma once

namespace skytrace {

[[nodiscard]] const char* version();  // "0.1.0"

}  // namespace skytrace
