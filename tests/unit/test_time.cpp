// GNSS time scales: conversions, leap seconds, week numbering and rollover.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "skytrace/core/time.hpp"
#include "time_boundaries.hpp"

namespace skytrace {
namespace {

GnssTime parse(const char* text, TimeScale scale) { return GnssTime::parse_iso8601(text, scale).value(); }

TEST(GnssTime, GpsEpochIsZero) {
  const GnssTime t = parse("1980-01-06T00:00:00", TimeScale::kGpst);
  EXPECT_EQ(t.whole_seconds(), 0);
  EXPECT_EQ(t.fraction_s(), 0.0);
}

TEST(GnssTime, WeekAndTowOfKnownDates) {
  // 2020-06-25 is a Thursday of GPS week 2111 (IGS product names use week 2111, day 4).
  const WeekTow w = parse("2020-06-25T00:00:00", TimeScale::kGpst).to_week_tow(TimeScale::kGpst);
  EXPECT_EQ(w.week, 2111);
  EXPECT_DOUBLE_EQ(w.tow_s, 4 * 86400.0);
  // Galileo week = GPS week - 1024; BeiDou week = GPS week - 1356 with BDT 14 s behind.
  const GnssTime t = GnssTime::from_week_tow(TimeScale::kGpst, 2111, 345600.0);
  EXPECT_EQ(t.to_week_tow(TimeScale::kGst).week, 1087);
  const WeekTow bdt = t.to_week_tow(TimeScale::kBdt);
  EXPECT_EQ(bdt.week, 755);
  EXPECT_DOUBLE_EQ(bdt.tow_s, 345600.0 - 14.0);
  EXPECT_EQ(t.to_week_tow(TimeScale::kIrnwt).week, 1087);
}

TEST(GnssTime, BeiDouEpochIsGpsWeek1356Plus14s) {
  const GnssTime bdt0 = GnssTime::from_week_tow(TimeScale::kBdt, 0, 0.0);
  const WeekTow w = bdt0.to_week_tow(TimeScale::kGpst);
  EXPECT_EQ(w.week, 1356);
  EXPECT_DOUBLE_EQ(w.tow_s, 14.0);
  // BDT 2006-01-01T00:00:00 is UTC 2006-01-01T00:00:00 (GPS-UTC was 14 s then).
  EXPECT_EQ(bdt0, parse("2006-01-01T00:00:00", TimeScale::kUtc));
}

TEST(GnssTime, LeapSecondTable) {
  EXPECT_EQ(gps_minus_utc_s(parse("1981-06-30T23:59:59", TimeScale::kUtc)), 0);
  EXPECT_EQ(gps_minus_utc_s(parse("1981-07-01T00:00:00", TimeScale::kUtc)), 1);
  EXPECT_EQ(gps_minus_utc_s(parse("2016-12-31T23:59:59", TimeScale::kUtc)), 17);
  EXPECT_EQ(gps_minus_utc_s(parse("2017-01-01T00:00:00", TimeScale::kUtc)), 18);
  EXPECT_EQ(gps_minus_utc_s(parse("2026-11-22T00:00:00", TimeScale::kUtc)), 18);
}

TEST(GnssTime, UtcAcrossTheLeapSecondOf2016) {
  // UTC 2016-12-31T23:59:59, 23:59:60 and 2017-01-01T00:00:00 are three consecutive GPST seconds.
  const GnssTime before = parse("2016-12-31T23:59:59", TimeScale::kUtc);
  const GnssTime leap = parse("2016-12-31T23:59:60.5", TimeScale::kUtc);
  const GnssTime after = parse("2017-01-01T00:00:00", TimeScale::kUtc);
  EXPECT_DOUBLE_EQ(leap - before, 1.5);
  EXPECT_DOUBLE_EQ(after - before, 2.0);
  // And they print back as such.
  EXPECT_EQ(before.to_iso8601(TimeScale::kUtc, 1), "2016-12-31T23:59:59.0");
  EXPECT_EQ(leap.to_iso8601(TimeScale::kUtc, 1), "2016-12-31T23:59:60.5");
  EXPECT_EQ(after.to_iso8601(TimeScale::kUtc, 1), "2017-01-01T00:00:00.0");
  // GPST keeps counting without a gap: 2017-01-01T00:00:00 UTC = 00:00:18 GPST.
  EXPECT_EQ(after.to_iso8601(TimeScale::kGpst, 0), "2017-01-01T00:00:18");
  EXPECT_EQ(after.to_iso8601(TimeScale::kTai, 0), "2017-01-01T00:00:37");
}

TEST(GnssTime, GlonassTimeIsUtcPlusThreeHours) {
  const GnssTime t = parse("2020-06-25T00:00:00", TimeScale::kGpst);
  EXPECT_EQ(t.to_iso8601(TimeScale::kUtc, 0), "2020-06-24T23:59:42");
  EXPECT_EQ(t.to_iso8601(TimeScale::kGlonasst, 0), "2020-06-25T02:59:42");
  EXPECT_EQ(parse("2020-06-25T02:59:42", TimeScale::kGlonasst), t);
  // The GLONASS leap second happens at 03:00 Moscow time: 02:59:60 GLONASST.
  const GnssTime leap = parse("2017-01-01T02:59:60", TimeScale::kGlonasst);
  EXPECT_EQ(leap.to_iso8601(TimeScale::kUtc, 0), "2016-12-31T23:59:60");
}

TEST(GnssTime, SubNanosecondExactOverDecades) {
  const GnssTime t = parse("2040-01-01T12:00:00.123456789", TimeScale::kGpst);
  const GnssTime u = t + 1e-12;
  EXPECT_NEAR(u - t, 1e-12, 1e-16);
  // A week of 1-ns steps accumulates no error in the whole seconds.
  GnssTime s = GnssTime::from_week_tow(TimeScale::kGpst, 3000, 0.0);
  const GnssTime start = s;
  for (int i = 0; i < 1000; ++i) s += 604.8;
  EXPECT_NEAR(s - start, 604800.0, 1e-9);
  EXPECT_NEAR(GnssTime::from_week_tow(TimeScale::kGpst, 3001, 0.0) - s, 0.0, 1e-9);
}

TEST(GnssTime, ArithmeticNormalisesFraction) {
  GnssTime t = GnssTime::from_gpst_seconds(100, 0.75);
  t += 0.5;
  EXPECT_EQ(t.whole_seconds(), 101);
  EXPECT_DOUBLE_EQ(t.fraction_s(), 0.25);
  t -= 1.5;
  EXPECT_EQ(t.whole_seconds(), 99);
  EXPECT_DOUBLE_EQ(t.fraction_s(), 0.75);
  EXPECT_LT(GnssTime::from_gpst_seconds(5, 0.1), GnssTime::from_gpst_seconds(5, 0.2));
}

TEST(GnssTime, DayOfYearAndCalendar) {
  const GnssTime t = parse("2020-06-25T13:14:15.5", TimeScale::kGpst);
  EXPECT_EQ(t.day_of_year(TimeScale::kGpst), 177);
  const CalendarTime c = t.to_calendar(TimeScale::kGpst);
  EXPECT_EQ(c.year, 2020);
  EXPECT_EQ(c.month, 6);
  EXPECT_EQ(c.day, 25);
  EXPECT_EQ(c.hour, 13);
  EXPECT_EQ(c.minute, 14);
  EXPECT_DOUBLE_EQ(c.second, 15.5);
  EXPECT_EQ(parse("2016-12-31T00:00:00", TimeScale::kGpst).day_of_year(TimeScale::kGpst), 366);
}

TEST(GnssTime, WeekRollover) {
  // GPS week 2111 broadcast in 10 bits is 63; resolved against a reference near 2020.
  EXPECT_EQ(resolve_week_rollover(63, 1024, 2100), 2111);
  EXPECT_EQ(resolve_week_rollover(1023, 1024, 2049), 2047);  // just before the 2019-04-06 rollover
  EXPECT_EQ(resolve_week_rollover(1, 1024, 2047), 2049);     // just after it
  EXPECT_EQ(resolve_week_rollover(2111 % 8192, 8192, 2000), 2111);
  // The 2019-04-07 rollover instant: week 2048 TOW 0 = 2019-04-07T00:00:00 GPST.
  EXPECT_EQ(GnssTime::from_week_tow(TimeScale::kGpst, 2048, 0.0).to_iso8601(TimeScale::kGpst, 0),
            "2019-04-07T00:00:00");
  EXPECT_EQ(GnssTime::from_week_tow(TimeScale::kGpst, 1024, 0.0).to_iso8601(TimeScale::kGpst, 0),
            "1999-08-22T00:00:00");
}

TEST(GnssTime, ParseErrors) {
  EXPECT_FALSE(GnssTime::parse_iso8601("2020-13-01T00:00:00", TimeScale::kGpst).ok());
  EXPECT_FALSE(GnssTime::parse_iso8601("2020-06-25 25:00:00", TimeScale::kGpst).ok());
  EXPECT_FALSE(GnssTime::parse_iso8601("yesterday", TimeScale::kGpst).ok());
  EXPECT_FALSE(GnssTime::parse_iso8601("2020-06-25T00:00:60", TimeScale::kGpst).ok());
  // Before GPS time began: no GNSS time scale is defined there.
  const auto early = GnssTime::parse_iso8601("1900-01-01T00:00:00", TimeScale::kUtc);
  ASSERT_FALSE(early.ok());
  EXPECT_NE(early.error().message.find("before GPS time began"), std::string::npos) << early.error().message;
  EXPECT_FALSE(GnssTime::parse_iso8601("1980-01-05T23:59:59", TimeScale::kGpst).ok());
  EXPECT_TRUE(GnssTime::parse_iso8601("1980-01-06T00:00:00", TimeScale::kGpst).ok());
  EXPECT_FALSE(GnssTime::parse_iso8601("2020-06-25T00:00:00Z", TimeScale::kGpst).ok());
  EXPECT_TRUE(GnssTime::parse_iso8601("2020-06-25T00:00:00Z", TimeScale::kUtc).ok());
  EXPECT_TRUE(GnssTime::parse_iso8601("2020-06-25", TimeScale::kGpst).ok());
  const auto r = GnssTime::parse_iso8601("2020-02-30T00:00:00", TimeScale::kGpst);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("2020-02-30"), std::string::npos);
  EXPECT_FALSE(parse_time_scale("XYZ").ok());
  EXPECT_EQ(parse_time_scale("gps").value(), TimeScale::kGpst);
}

// ---- printing: rounding carries through minute, hour, day, month, year (truth.csv once showed
// 2024-05-02T23:59:60.000000 for a true time 0.1 ns before midnight)

TEST(GnssTimeIso8601, RoundingUpCarriesIntoTheNextMinuteHourDayMonthAndYear) {
  for (const auto& b : test::time_boundaries()) {
    for (const TimeScale scale : {TimeScale::kGpst, TimeScale::kUtc, TimeScale::kBdt, TimeScale::kGlonasst}) {
      for (const int decimals : {0, 1, 3, 6, 7, 9}) {
        for (const double fraction : test::fractions_rounding_up(decimals)) {
          const GnssTime t = test::boundary_time(b, scale, fraction);
          EXPECT_EQ(t.to_iso8601(scale, decimals), test::with_zero_decimals(b.next, decimals))
              << b.name << ", " << to_string(scale) << ", " << decimals << " decimals, fraction 1 - "
              << 1.0 - fraction;
        }
      }
    }
  }
}

TEST(GnssTimeIso8601, JustBelowTheRoundingStepStaysInTheLastSecond) {
  for (const auto& b : test::time_boundaries()) {
    const GnssTime t = test::boundary_time(b, TimeScale::kGpst, 0.9999994);
    EXPECT_EQ(t.to_iso8601(TimeScale::kGpst, 6), std::string(b.last_second) + ".999999") << b.name;
    EXPECT_EQ(t.to_iso8601(TimeScale::kGpst, 0), b.next) << b.name;
    EXPECT_EQ(test::boundary_time(b, TimeScale::kGpst, 0.4999).to_iso8601(TimeScale::kGpst, 0), b.last_second)
        << b.name;
  }
}

TEST(GnssTimeIso8601, SixtyOnlyInsideARealLeapSecond) {
  // 2016-12-31 ended with the leap second 23:59:60 UTC (02:59:60 GLONASST on 2017-01-01).
  const GnssTime before_leap = parse("2016-12-31T23:59:59", TimeScale::kUtc);
  const GnssTime leap = parse("2016-12-31T23:59:60", TimeScale::kUtc);
  for (const double fraction : test::fractions_rounding_up(6)) {
    EXPECT_EQ((before_leap + fraction).to_iso8601(TimeScale::kUtc, 6), "2016-12-31T23:59:60.000000");
    EXPECT_EQ((before_leap + fraction).to_iso8601(TimeScale::kGlonasst, 6), "2017-01-01T02:59:60.000000");
    EXPECT_EQ((leap + fraction).to_iso8601(TimeScale::kUtc, 6), "2017-01-01T00:00:00.000000");
    EXPECT_EQ((leap + fraction).to_iso8601(TimeScale::kGlonasst, 6), "2017-01-01T03:00:00.000000");
    // The same instants in GPST have no leap second: 00:00:16 and 00:00:17.
    EXPECT_EQ((before_leap + fraction).to_iso8601(TimeScale::kGpst, 6), "2017-01-01T00:00:17.000000");
    EXPECT_EQ((leap + fraction).to_iso8601(TimeScale::kGpst, 6), "2017-01-01T00:00:18.000000");
  }
  EXPECT_EQ((leap + 0.9999994).to_iso8601(TimeScale::kUtc, 6), "2016-12-31T23:59:60.999999");
  EXPECT_EQ((leap + 0.5).to_iso8601(TimeScale::kUtc, 0), "2017-01-01T00:00:00");
  EXPECT_EQ((before_leap + 0.5).to_iso8601(TimeScale::kUtc, 0), "2016-12-31T23:59:60");
  // A year end without a leap second: no 60.
  EXPECT_EQ((parse("2017-12-31T23:59:59", TimeScale::kUtc) + std::nextafter(1.0, 0.0)).to_iso8601(TimeScale::kUtc, 6),
            "2018-01-01T00:00:00.000000");
}

TEST(GnssTimeRounding, RoundedToCarriesIntoTheWholeSeconds) {
  const GnssTime t = parse("2024-05-04T23:59:59", TimeScale::kGpst);
  const GnssTime next = parse("2024-05-05T00:00:00", TimeScale::kGpst);
  for (const int decimals : {0, 3, 7, 15}) {
    for (const double fraction : test::fractions_rounding_up(decimals)) {
      const GnssTime r = (t + fraction).rounded_to(decimals);
      EXPECT_EQ(r, next) << decimals << " decimals, fraction 1 - " << 1.0 - fraction;
      EXPECT_EQ(r.to_week_tow(TimeScale::kGpst).week, 2313);
      EXPECT_EQ(r.to_week_tow(TimeScale::kGpst).tow_s, 0.0);
    }
  }
  const GnssTime down = (t + 0.1234564).rounded_to(6);
  EXPECT_EQ(down.whole_seconds(), t.whole_seconds());
  EXPECT_DOUBLE_EQ(down.fraction_s(), 0.123456);
  EXPECT_DOUBLE_EQ((t + 0.1234565001).rounded_to(6).fraction_s(), 0.123457);
  // Out-of-range decimals are clamped to 0..15.
  EXPECT_EQ((t + 0.6).rounded_to(-2), next);
  EXPECT_EQ((t + 0.25).rounded_to(40).fraction_s(), 0.25);
}

TEST(GnssTimeRounding, RoundedCalendarFieldsAreExactIntegers) {
  for (const auto& b : test::time_boundaries()) {
    const RoundedCalendarTime c = test::boundary_time(b, TimeScale::kGpst, 1.0 - 4e-8).to_rounded_calendar(TimeScale::kGpst, 7);
    char text[32];
    std::snprintf(text, sizeof text, "%04d-%02d-%02dT%02d:%02d:%02d", c.year, c.month, c.day, c.hour, c.minute, c.second);
    EXPECT_EQ(std::string(text), b.next) << b.name;
    EXPECT_EQ(c.fraction, 0);
    EXPECT_EQ(c.decimals, 7);
    const RoundedCalendarTime below =
        test::boundary_time(b, TimeScale::kGpst, 1.0 - 6e-8).to_rounded_calendar(TimeScale::kGpst, 7);
    EXPECT_EQ(below.second, 59) << b.name;
    EXPECT_EQ(below.fraction, 9999999) << b.name;
  }
  // The leap second is a second of its own in UTC: 23:59:60 rounds into it and out of it.
  const GnssTime leap = parse("2016-12-31T23:59:60", TimeScale::kUtc);
  const RoundedCalendarTime in = (leap - 0.3).to_rounded_calendar(TimeScale::kUtc, 0);
  EXPECT_EQ(in.day, 31);
  EXPECT_EQ(in.second, 60);
  const RoundedCalendarTime out = (leap + 0.7).to_rounded_calendar(TimeScale::kUtc, 0);
  EXPECT_EQ(out.year, 2017);
  EXPECT_EQ(out.month, 1);
  EXPECT_EQ(out.day, 1);
  EXPECT_EQ(out.hour, 0);
  EXPECT_EQ(out.minute, 0);
  EXPECT_EQ(out.second, 0);
}

}  // namespace
}  // namespace skytrace
