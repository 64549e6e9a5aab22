// Instants just below the end of a minute, hour, day, month (30 days, February of a common and of a
// leap year), year and GPS week, for the tests of every writer that rounds a time for printing:
// the rounding must carry into the next minute, hour, day, month and year, never print second 60.
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include "skytrace/core/time.hpp"

namespace skytrace::test {

struct TimeBoundary {
  const char* name;
  const char* last_second;  // "YYYY-MM-DDThh:mm:ss": the last whole second before the boundary
  const char* next;         // the boundary, same scale
};

// In increasing time order (a writer that needs increasing epochs can take them one after the other).
inline const std::vector<TimeBoundary>& time_boundaries() {
  static const std::vector<TimeBoundary> boundaries = {
      {"end of February of a common year", "2023-02-28T23:59:59", "2023-03-01T00:00:00"},
      {"end of a common year", "2023-12-31T23:59:59", "2024-01-01T00:00:00"},
      {"end of February of a leap year", "2024-02-29T23:59:59", "2024-03-01T00:00:00"},
      {"end of a 30-day month", "2024-04-30T23:59:59", "2024-05-01T00:00:00"},
      {"end of a minute", "2024-05-02T12:34:59", "2024-05-02T12:35:00"},
      {"end of an hour", "2024-05-02T12:59:59", "2024-05-02T13:00:00"},
      {"end of a day", "2024-05-02T23:59:59", "2024-05-03T00:00:00"},
      {"end of GPS week 2312 (Saturday)", "2024-05-04T23:59:59", "2024-05-05T00:00:00"},
      {"end of a leap year", "2024-12-31T23:59:59", "2025-01-01T00:00:00"},
  };
  return boundaries;
}

// The last whole second before the boundary plus `fraction_s`, in `scale`.
inline GnssTime boundary_time(const TimeBoundary& b, TimeScale scale, double fraction_s) {
  return GnssTime::parse_iso8601(b.last_second, scale).value() + fraction_s;
}

// Fractions of a second that round up to the next whole second with `decimals` decimals: 0.4 of
// the last digit below it, 1e-10 s below it (a receiver clock bias of 0.1 ns, as in the NYA1 run
// where truth.csv showed 23:59:60.000000) and the largest double below 1.
inline std::vector<double> fractions_rounding_up(int decimals) {
  std::vector<double> fractions = {1.0 - 0.4 * std::pow(10.0, -decimals)};
  if (decimals <= 9) fractions.push_back(1.0 - 1e-10);
  fractions.push_back(std::nextafter(1.0, 0.0));
  return fractions;
}

// "YYYY-MM-DDThh:mm:ss" with ".000..." (decimals zeros) appended.
inline std::string with_zero_decimals(const std::string& iso, int decimals) {
  return decimals > 0 ? iso + "." + std::string(static_cast<size_t>(decimals), '0') : iso;
}

}  // namespace skytrace::test
