#include "skytrace/core/time.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <string>

namespace skytrace {
namespace {

constexpr std::int64_t kSecondsPerDay = 86400;
constexpr std::int64_t kSecondsPerWeek = 604800;
constexpr std::int64_t kGpsEpochDaysSinceUnix = 3657;  // 1980-01-06
constexpr std::int64_t kGstWeekOffset = 1024;           // GST week 0 = GPS week 1024 (1999-08-22)
constexpr std::int64_t kIrnWeekOffset = 1024;           // NavIC week 0 = GPS week 1024
constexpr std::int64_t kBdtWeekOffset = 1356;           // BDT week 0 = GPS week 1356 (2006-01-01)
constexpr std::int64_t kBdtMinusGpst_s = -14;
constexpr std::int64_t kTaiMinusGpst_s = 19;
constexpr std::int64_t kGlonasstMinusUtc_s = 3 * 3600;

// Days since 1970-01-01 of a proleptic Gregorian date (H. Hinnant's algorithm).
constexpr std::int64_t days_from_civil(std::int64_t y, unsigned m, unsigned d) {
  y -= m <= 2;
  const std::int64_t era = (y >= 0 ? y : y - 399) / 400;
  const auto yoe = static_cast<unsigned>(y - era * 400);
  const unsigned doy = (153 * (m + (m > 2 ? -3 : 9)) + 2) / 5 + d - 1;
  const unsigned doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
  return era * 146097 + static_cast<std::int64_t>(doe) - 719468;
}

struct CivilDate {
  int year;
  int month;
  int day;
};

constexpr CivilDate civil_from_days(std::int64_t z) {
  z += 719468;
  const std::int64_t era = (z >= 0 ? z : z - 146096) / 146097;
  const auto doe = static_cast<unsigned>(z - era * 146097);
  const unsigned yoe = (doe - doe / 1460 + doe / 36524 - doe / 146096) / 365;
  const std::int64_t y = static_cast<std::int64_t>(yoe) + era * 400;
  const unsigned doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
  const unsigned mp = (5 * doy + 2) / 153;
  const unsigned d = doy - (153 * mp + 2) / 5 + 1;
  const unsigned m = mp < 10 ? mp + 3 : mp - 9;
  return {static_cast<int>(y + (m <= 2)), static_cast<int>(m), static_cast<int>(d)};
}

// Seconds since 1980-01-06T00:00:00 of a calendar reading, counting every day as 86400 s.
constexpr std::int64_t calendar_count_s(int year, int month, int day) {
  return (days_from_civil(year, static_cast<unsigned>(month), static_cast<unsigned>(day)) -
          kGpsEpochDaysSinceUnix) *
         kSecondsPerDay;
}

// GPS - UTC from the UTC date it takes effect (IERS Bulletin C). A constant table, never mutated.
struct LeapSecondStep {
  std::int64_t utc_count_s;  // calendar_count_s of the UTC date at 00:00:00
  int gps_minus_utc_s;       // value from that instant on
};
constexpr std::array<LeapSecondStep, 18> kLeapSeconds = {{
    {calendar_count_s(1981, 7, 1), 1},  {calendar_count_s(1982, 7, 1), 2},
    {calendar_count_s(1983, 7, 1), 3},  {calendar_count_s(1985, 7, 1), 4},
    {calendar_count_s(1988, 1, 1), 5},  {calendar_count_s(1990, 1, 1), 6},
    {calendar_count_s(1991, 1, 1), 7},  {calendar_count_s(1992, 7, 1), 8},
    {calendar_count_s(1993, 7, 1), 9},  {calendar_count_s(1994, 7, 1), 10},
    {calendar_count_s(1996, 1, 1), 11}, {calendar_count_s(1997, 7, 1), 12},
    {calendar_count_s(1999, 1, 1), 13}, {calendar_count_s(2006, 1, 1), 14},
    {calendar_count_s(2009, 1, 1), 15}, {calendar_count_s(2012, 7, 1), 16},
    {calendar_count_s(2015, 7, 1), 17}, {calendar_count_s(2017, 1, 1), 18},
}};

// GPS - UTC in force at a UTC calendar count (leap second itself excluded).
int gps_minus_utc_at_utc_count(std::int64_t utc_count_s) {
  int leap = 0;
  for (const auto& step : kLeapSeconds) {
    if (utc_count_s >= step.utc_count_s) leap = step.gps_minus_utc_s;
  }
  return leap;
}

// A GPST instant seen on a UTC-like calendar: whole count, and whether it falls inside an
// inserted leap second (then the calendar shows second 60 of the last minute of the day before).
struct UtcView {
  std::int64_t count_s;
  bool in_leap_second;
};

UtcView gpst_to_utc_count(std::int64_t gpst_whole_s) {
  int leap = 0;
  for (const auto& step : kLeapSeconds) {
    const std::int64_t boundary_gpst = step.utc_count_s + step.gps_minus_utc_s;
    if (gpst_whole_s >= boundary_gpst) {
      leap = step.gps_minus_utc_s;
    } else if (gpst_whole_s == boundary_gpst - 1) {
      // 23:59:60 UTC: shown as 23:59:59 with the second incremented.
      return {gpst_whole_s - (step.gps_minus_utc_s - 1) - 1, true};
    }
  }
  return {gpst_whole_s - leap, false};
}

// Offset (scale count - GPST whole seconds) for the scales without leap seconds.
std::int64_t fixed_offset_s(TimeScale scale) {
  switch (scale) {
    case TimeScale::kBdt: return kBdtMinusGpst_s;
    case TimeScale::kTai: return kTaiMinusGpst_s;
    default: return 0;
  }
}

bool has_leap_seconds(TimeScale scale) {
  return scale == TimeScale::kUtc || scale == TimeScale::kGlonasst;
}

std::int64_t week_offset(TimeScale scale) {
  switch (scale) {
    case TimeScale::kGst: return kGstWeekOffset;
    case TimeScale::kIrnwt: return kIrnWeekOffset;
    case TimeScale::kBdt: return kBdtWeekOffset;
    default: return 0;
  }
}

std::int64_t floor_div(std::int64_t a, std::int64_t b) {
  std::int64_t q = a / b;
  if ((a % b != 0) && ((a < 0) != (b < 0))) --q;
  return q;
}

// The scale's calendar count (whole seconds since 1980-01-06 on its own clock) and leap flag.
UtcView to_scale_count(const GnssTime& t, TimeScale scale) {
  if (!has_leap_seconds(scale)) return {t.whole_seconds() + fixed_offset_s(scale), false};
  UtcView view = gpst_to_utc_count(t.whole_seconds());
  if (scale == TimeScale::kGlonasst) view.count_s += kGlonasstMinusUtc_s;
  return view;
}

// A scale's whole-second count split into calendar fields; second 60 inside a leap second.
struct CalendarFields {
  CivilDate date;
  int hour = 0;
  int minute = 0;
  int second = 0;
};

CalendarFields calendar_fields(const UtcView& view) {
  const std::int64_t days = floor_div(view.count_s, kSecondsPerDay);
  const std::int64_t sod = view.count_s - days * kSecondsPerDay;
  return {civil_from_days(days + kGpsEpochDaysSinceUnix), static_cast<int>(sod / 3600),
          static_cast<int>((sod % 3600) / 60), static_cast<int>(sod % 60) + (view.in_leap_second ? 1 : 0)};
}

// Seconds limited to +-kMaxTimeOffset_s (NaN to the upper limit), so that their whole part
// always has an int64 (a cast of 1e40 or NaN would be undefined).
double clamped_offset_s(double seconds) {
  if (std::isnan(seconds)) return kMaxTimeOffset_s;
  return std::clamp(seconds, -kMaxTimeOffset_s, kMaxTimeOffset_s);
}

}  // namespace

std::string_view to_string(TimeScale scale) {
  switch (scale) {
    case TimeScale::kGpst: return "GPST";
    case TimeScale::kGst: return "GST";
    case TimeScale::kBdt: return "BDT";
    case TimeScale::kGlonasst: return "GLONASST";
    case TimeScale::kQzsst: return "QZSST";
    case TimeScale::kIrnwt: return "IRNWT";
    case TimeScale::kUtc: return "UTC";
    case TimeScale::kTai: return "TAI";
  }
  return "?";
}

Result<TimeScale> parse_time_scale(std::string_view name) {
  std::string upper(name);
  for (auto& c : upper) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  if (upper == "GPST" || upper == "GPS") return TimeScale::kGpst;
  if (upper == "GST" || upper == "GAL") return TimeScale::kGst;
  if (upper == "BDT" || upper == "BDS") return TimeScale::kBdt;
  if (upper == "GLONASST" || upper == "GLO" || upper == "GLONASS") return TimeScale::kGlonasst;
  if (upper == "QZSST" || upper == "QZS") return TimeScale::kQzsst;
  if (upper == "IRNWT" || upper == "IRN" || upper == "NAVIC") return TimeScale::kIrnwt;
  if (upper == "UTC") return TimeScale::kUtc;
  if (upper == "TAI") return TimeScale::kTai;
  return make_error(ErrorCode::kInvalidArgument,
                    "unknown time scale '" + std::string(name) +
                        "' (expected GPST, GST, BDT, GLONASST, QZSST, IRNWT, UTC or TAI)");
}

GnssTime GnssTime::from_gpst_seconds(std::int64_t whole_s, double fraction_s) {
  GnssTime t;
  fraction_s = clamped_offset_s(fraction_s);
  const double whole_of_fraction = std::floor(fraction_s);
  t.whole_s_ = whole_s + static_cast<std::int64_t>(whole_of_fraction);
  t.fraction_s_ = fraction_s - whole_of_fraction;
  if (t.fraction_s_ >= 1.0) {  // rounding of a value just below an integer
    t.fraction_s_ -= 1.0;
    ++t.whole_s_;
  }
  return t;
}

GnssTime& GnssTime::operator+=(double dt_s) {
  *this = from_gpst_seconds(whole_s_, fraction_s_ + dt_s);
  return *this;
}

GnssTime GnssTime::from_week_tow(TimeScale scale, int week, double tow_s) {
  tow_s = clamped_offset_s(tow_s);
  const std::int64_t whole_tow = static_cast<std::int64_t>(std::floor(tow_s));
  const std::int64_t scale_count = (week + week_offset(scale)) * kSecondsPerWeek + whole_tow;
  const double fraction = tow_s - static_cast<double>(whole_tow);
  if (!has_leap_seconds(scale)) return from_gpst_seconds(scale_count - fixed_offset_s(scale), fraction);
  // Weeks counted on a UTC-like calendar: go through the calendar conversion.
  const CalendarFields f = calendar_fields(UtcView{scale_count, false});
  CalendarTime cal{f.date.year, f.date.month, f.date.day, f.hour, f.minute, static_cast<double>(f.second) + fraction};
  return from_calendar(cal, scale);
}

GnssTime GnssTime::from_calendar(const CalendarTime& c, TimeScale scale) {
  const double second = clamped_offset_s(c.second);
  const double whole_second = std::floor(second);
  const double fraction = second - whole_second;
  const std::int64_t count = calendar_count_s(c.year, c.month, c.day) + c.hour * 3600LL +
                             c.minute * 60LL + static_cast<std::int64_t>(whole_second);
  if (!has_leap_seconds(scale)) return from_gpst_seconds(count - fixed_offset_s(scale), fraction);
  std::int64_t utc_count = count;
  if (scale == TimeScale::kGlonasst) utc_count -= kGlonasstMinusUtc_s;
  // Inside a leap second (second >= 60) the offset still has its old value.
  const std::int64_t lookup = whole_second >= 60.0 ? utc_count - 1 : utc_count;
  return from_gpst_seconds(utc_count + gps_minus_utc_at_utc_count(lookup), fraction);
}

Result<GnssTime> GnssTime::checked_week_tow(TimeScale scale, int week, double tow_s) {
  if (!time_offset_in_range(tow_s)) {
    return make_error(ErrorCode::kInvalidArgument,
                      "time of week " + std::to_string(tow_s) + " s is not a time (expected a finite number of seconds)");
  }
  return from_week_tow(scale, week, tow_s);
}

Result<GnssTime> GnssTime::checked_calendar(const CalendarTime& c, TimeScale scale) {
  if (c.month < 1 || c.month > 12 || c.day < 1 || c.day > 31) {
    return make_error(ErrorCode::kInvalidArgument, "invalid date: month " + std::to_string(c.month) + ", day " +
                                                       std::to_string(c.day) + " (expected 1-12 and 1-31)");
  }
  if (!time_offset_in_range(c.second)) {
    return make_error(ErrorCode::kInvalidArgument,
                      "second " + std::to_string(c.second) + " is not a time (expected a finite number of seconds)");
  }
  return from_calendar(c, scale);
}

Result<GnssTime> GnssTime::parse_iso8601(std::string_view text, TimeScale scale) {
  auto fail = [&](const std::string& why) -> Result<GnssTime> {
    return make_error(ErrorCode::kInvalidArgument,
                      "invalid time '" + std::string(text) + "': " + why +
                          " (expected YYYY-MM-DDThh:mm:ss[.fff])");
  };
  std::string s(text);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.pop_back();
  if (!s.empty() && (s.back() == 'Z' || s.back() == 'z')) {
    if (scale != TimeScale::kUtc) return fail("a trailing Z means UTC but the scale is " + std::string(to_string(scale)));
    s.pop_back();
  }
  int year = 0, month = 0, day = 0, hour = 0, minute = 0;
  char sep = 0;
  int consumed = 0;
  if (std::sscanf(s.c_str(), "%4d-%2d-%2d%c%2d:%2d:%n", &year, &month, &day, &sep, &hour, &minute,
                  &consumed) != 6 ||
      consumed == 0) {
    // Date only is allowed.
    if (std::sscanf(s.c_str(), "%4d-%2d-%2d%n", &year, &month, &day, &consumed) == 3 &&
        static_cast<size_t>(consumed) == s.size()) {
      sep = 'T';
    } else {
      return fail("not an ISO 8601 date and time");
    }
  }
  if (sep != 'T' && sep != 't' && sep != ' ') return fail("date and time must be separated by T");
  double second = 0.0;
  if (static_cast<size_t>(consumed) < s.size()) {
    const char* begin = s.c_str() + consumed;
    const char* end = s.c_str() + s.size();
    auto [ptr, ec] = std::from_chars(begin, end, second);
    if (ec != std::errc() || ptr != end) return fail("bad seconds field");
  }
  if (month < 1 || month > 12) return fail("month out of range");
  static constexpr int kDaysInMonth[] = {31, 29, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
  if (day < 1 || day > kDaysInMonth[month - 1]) return fail("day out of range");
  if (hour < 0 || hour > 23 || minute < 0 || minute > 59) return fail("hour or minute out of range");
  const double max_second = has_leap_seconds(scale) ? 61.0 : 60.0;
  if (second < 0.0 || second >= max_second) return fail("second out of range");
  const GnssTime t = from_calendar(CalendarTime{year, month, day, hour, minute, second}, scale);
  // Every GNSS time scale counts from 1980 or later; earlier readings only produced output dated
  // before any satellite (the nominal constellation ran silently in 1900).
  if (t.whole_seconds() < 0) return fail("before GPS time began (1980-01-06T00:00:00 GPST)");
  return t;
}

WeekTow GnssTime::to_week_tow(TimeScale scale) const {
  const UtcView view = to_scale_count(*this, scale);
  const std::int64_t count = view.count_s + (view.in_leap_second ? 1 : 0) -
                             week_offset(scale) * kSecondsPerWeek;
  const std::int64_t week = floor_div(count, kSecondsPerWeek);
  return {static_cast<int>(week),
          static_cast<double>(count - week * kSecondsPerWeek) + fraction_s_};
}

CalendarTime GnssTime::to_calendar(TimeScale scale) const {
  const CalendarFields f = calendar_fields(to_scale_count(*this, scale));
  CalendarTime c;
  c.year = f.date.year;
  c.month = f.date.month;
  c.day = f.date.day;
  c.hour = f.hour;
  c.minute = f.minute;
  c.second = static_cast<double>(f.second) + fraction_s_;
  return c;
}

int GnssTime::day_of_year(TimeScale scale) const {
  const CalendarTime c = to_calendar(scale);
  return static_cast<int>(days_from_civil(c.year, static_cast<unsigned>(c.month), static_cast<unsigned>(c.day)) -
                          days_from_civil(c.year, 1, 1)) +
         1;
}

namespace {

constexpr int kMaxDecimals = 15;  // 1e15 units of a second still fit an int64 many times over

int clamp_decimals(int decimals) { return std::clamp(decimals, 0, kMaxDecimals); }

std::int64_t pow10(int decimals) {
  std::int64_t p = 1;
  for (int i = 0; i < decimals; ++i) p *= 10;
  return p;
}

// The instant rounded to units of 10^-decimals s: whole GPST seconds and the count of units in
// [0, 10^decimals). Rounding the fraction alone is rounding the whole value (the whole seconds are
// exact); a fraction that rounds to a full second carries into the whole seconds.
struct RoundedSeconds {
  std::int64_t whole_s;
  std::int64_t units;
};

RoundedSeconds round_seconds(std::int64_t whole_s, double fraction_s, int decimals) {
  const std::int64_t per_second = pow10(decimals);
  std::int64_t units = std::llround(fraction_s * static_cast<double>(per_second));
  if (units >= per_second) {
    units -= per_second;
    ++whole_s;
  }
  return {whole_s, units};
}

}  // namespace

GnssTime GnssTime::rounded_to(int decimals) const {
  decimals = clamp_decimals(decimals);
  const RoundedSeconds r = round_seconds(whole_s_, fraction_s_, decimals);
  GnssTime t;
  t.whole_s_ = r.whole_s;
  t.fraction_s_ = static_cast<double>(r.units) / static_cast<double>(pow10(decimals));
  return t;
}

RoundedCalendarTime GnssTime::to_rounded_calendar(TimeScale scale, int decimals) const {
  decimals = clamp_decimals(decimals);
  // Round first on the continuous timeline, then split the whole second into calendar fields with
  // integer arithmetic only: the carry runs through minute, hour, day, month and year by itself.
  // Every scale is GPST shifted by whole seconds, so this rounding is the same in every scale. A
  // leap second of UTC / GLONASST is a whole GPST second of its own: an instant that rounds into
  // it shows second 60 (a real 23:59:60), one that rounds past it shows 00:00:00 of the next day.
  const RoundedSeconds r = round_seconds(whole_s_, fraction_s_, decimals);
  const CalendarFields f = calendar_fields(to_scale_count(from_gpst_seconds(r.whole_s), scale));
  RoundedCalendarTime c;
  c.year = f.date.year;
  c.month = f.date.month;
  c.day = f.date.day;
  c.hour = f.hour;
  c.minute = f.minute;
  c.second = f.second;
  c.fraction = r.units;
  c.decimals = decimals;
  return c;
}

std::string GnssTime::to_iso8601(TimeScale scale, int decimals) const {
  const RoundedCalendarTime c = to_rounded_calendar(scale, decimals);
  char buf[64];
  int n = std::snprintf(buf, sizeof buf, "%04d-%02d-%02dT%02d:%02d:%02d", c.year, c.month, c.day, c.hour, c.minute,
                        c.second);
  if (c.decimals > 0 && n > 0) {
    std::snprintf(buf + n, sizeof buf - static_cast<size_t>(n), ".%0*lld", c.decimals,
                  static_cast<long long>(c.fraction));
  }
  return buf;
}

int gps_minus_utc_s(const GnssTime& t) {
  const UtcView view = gpst_to_utc_count(t.whole_seconds());
  return static_cast<int>(t.whole_seconds() - view.count_s) - (view.in_leap_second ? 1 : 0);
}

int resolve_week_rollover(int truncated_week, int modulus, int reference_week) {
  const int base = reference_week - (reference_week % modulus);
  int best = base + (truncated_week % modulus);
  for (int candidate : {best - modulus, best + modulus}) {
    if (std::abs(candidate - reference_week) < std::abs(best - reference_week)) best = candidate;
  }
  return best;
}

}  // namespace skytrace
