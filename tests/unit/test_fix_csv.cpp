// fix.csv rows: the time columns (ISO 8601 GPST, GPS week, seconds of week to 1 ms) at the ends of
// minutes, hours, days, months, years and GPS weeks.
#include <gtest/gtest.h>

#include <string>

#include "skytrace/io/fix_csv.hpp"
#include "time_boundaries.hpp"

namespace skytrace::io {
namespace {

// The first three cells of a fix.csv row: time_gpst, week, tow_s.
std::string time_cells(const GnssTime& t) {
  positioning::PositionFix fix;
  fix.receiver_time = fix.time = t;
  fix.type = positioning::FixType::kNone;
  const std::string row = fix_csv_row(fix);
  size_t comma = 0;
  for (int k = 0; k < 3; ++k) comma = row.find(',', comma + 1);
  return row.substr(0, comma);
}

TEST(FixCsv, TimeColumnsRoundedToMillisecondsCarryIntoMinuteHourDayMonthYearAndWeek) {
  for (const auto& b : test::time_boundaries()) {
    const GnssTime next = GnssTime::parse_iso8601(b.next, TimeScale::kGpst).value();
    const WeekTow wt = next.to_week_tow(TimeScale::kGpst);
    char expected[96];
    std::snprintf(expected, sizeof expected, "%s.000,%d,%.3f", b.next, wt.week, wt.tow_s);
    for (const double fraction : test::fractions_rounding_up(3)) {
      EXPECT_EQ(time_cells(test::boundary_time(b, TimeScale::kGpst, fraction)), expected)
          << b.name << ", fraction 1 - " << 1.0 - fraction;
    }
  }
  // The GPS week end itself: second 0 of week 2313, never 604800.000 of week 2312.
  const GnssTime week_end = GnssTime::from_week_tow(TimeScale::kGpst, 2312, 604799.9996);
  EXPECT_EQ(time_cells(week_end), "2024-05-05T00:00:00.000,2313,0.000");
  EXPECT_EQ(time_cells(GnssTime::from_week_tow(TimeScale::kGpst, 2312, 604799.9994)),
            "2024-05-04T23:59:59.999,2312,604799.999");
}

}  // namespace
}  // namespace skytrace::io
