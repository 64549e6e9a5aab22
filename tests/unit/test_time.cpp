// GNSS time scales: conversions, leap seconds, week numbering and rollover.
#include <gtest/gtest.h>

#include "skytrace/core/time.hpp"

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
  EXPECT_FALSE(GnssTime::parse_iso8601("2020-06-25T00:00:00Z", TimeScale::kGpst).ok());
  EXPECT_TRUE(GnssTime::parse_iso8601("2020-06-25T00:00:00Z", TimeScale::kUtc).ok());
  EXPECT_TRUE(GnssTime::parse_iso8601("2020-06-25", TimeScale::kGpst).ok());
  const auto r = GnssTime::parse_iso8601("2020-02-30T00:00:00", TimeScale::kGpst);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("2020-02-30"), std::string::npos);
  EXPECT_FALSE(parse_time_scale("XYZ").ok());
  EXPECT_EQ(parse_time_scale("gps").value(), TimeScale::kGpst);
}

}  // namespace
}  // namespace skytrace
