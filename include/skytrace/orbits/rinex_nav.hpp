// RINEX navigation files: readers for 2.x (GPS, GLONASS), 3.0x (mixed and single-system) and
// 4.00 (EPH, ION, STO records), plain or gzip-compressed; a RINEX 3.04 writer.
#pragma once

#include <filesystem>
#include <string>

#include "skytrace/core/error.hpp"
#include "skytrace/orbits/ephemeris.hpp"

namespace skytrace::orbits {

// Reads one navigation file (version detected from the header). Errors name the file, the line
// and the field.
[[nodiscard]] Result<NavigationData> read_rinex_nav(const std::filesystem::path& path);
// Parses navigation-file content held in memory; `name` is used in error messages.
[[nodiscard]] Result<NavigationData> parse_rinex_nav(const std::string& name, std::string content);

struct RinexNavWriteOptions {
  std::string program = "skytrace";
  std::string run_by = "";
  // File creation date written into PGM / RUN BY / DATE (UTC, "YYYYMMDD HHMMSS UTC"); empty = now.
  std::string creation_date = "";
};

// Writes a RINEX 3.04 mixed navigation file holding every record of `data` (header ionosphere
// coefficients, time-system corrections and leap seconds included). The text is returned; use
// write_file_atomically to store it.
[[nodiscard]] std::string format_rinex3_nav(const NavigationData& data, const RinexNavWriteOptions& options = {});

}  // namespace skytrace::orbits
