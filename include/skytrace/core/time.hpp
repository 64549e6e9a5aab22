// GNSS time. One continuous timeline (GPS time) inside the program; every other scale is a view
// taken at the boundaries (parsing, file formats, ephemeris reference times).
#pragma once

#include <cstdint>
#include <compare>
#include <string>
#include <string_view>

#include "skytrace/core/error.hpp"

namespace skytrace {

enum class TimeScale {
  kGpst,      // GPS time: continuous, TAI - 19 s, epoch 1980-01-06 00:00:00
  kGst,       // Galileo System Time: aligned to GPST (offset GGTO of a few ns ignored), weeks from 1999-08-22
  kBdt,       // BeiDou Time: GPST - 14 s, weeks from 2006-01-01 00:00:00 BDT
  kGlonasst,  // GLONASS time: UTC(SU) + 3 h, with UTC's leap seconds
  kQzsst,     // QZSS time: aligned to GPST, GPS weeks
  kIrnwt,     // NavIC time: aligned to GPST, weeks from 1999-08-22 (GPS week 1024)
  kUtc,       // Coordinated Universal Time, with leap seconds
  kTai,       // International Atomic Time: GPST + 19 s
};

[[nodiscard]] std::string_view to_string(TimeScale scale);
// Accepts the names above and common aliases (GPS, GAL, BDS, GLO, QZS, IRN), case-insensitive.
[[nodiscard]] Result<TimeScale> parse_time_scale(std::string_view name);

// A civil date and time of day in some time scale. second may be 60.x inside a UTC leap second.
// second is a double: an instant within an ulp (~7e-15 s) of the end of a minute may read 60.0,
// and printing it with fewer decimals rounds it up without a carry. Text formats therefore take
// GnssTime::to_rounded_calendar, never this with printf rounding.
struct CalendarTime {
  int year = 1980;
  int month = 1;
  int day = 6;
  int hour = 0;
  int minute = 0;
  double second = 0.0;
};

// A calendar reading for printing: the instant rounded to 10^-decimals s on the continuous
// timeline first, then split, so that a carry runs through minute, hour, day, month and year
// (23:59:59.9999996 with 6 decimals is 00:00:00.000000 of the next day). All fields exact integers.
struct RoundedCalendarTime {
  int year = 1980;
  int month = 1;
  int day = 6;
  int hour = 0;
  int minute = 0;
  int second = 0;              // 0-59; 60 only inside a real leap second of UTC or GLONASST
  std::int64_t fraction = 0;   // in units of 10^-decimals s: [0, 10^decimals)
  int decimals = 0;            // 0-15
};

// Seconds given as a double to a conversion (time of week, second of a calendar reading, an offset
// added to a GnssTime) are taken within +-kMaxTimeOffset_s, about 31,700 years: far beyond any
// GNSS product, far inside the int64 whole seconds. The plain conversions clamp anything else
// (NaN to the upper limit) instead of invoking undefined behaviour, which only moves garbage to a
// far-away time; input from files goes through time_offset_in_range or the checked_ forms, which
// refuse it with an error.
inline constexpr double kMaxTimeOffset_s = 1.0e12;
// Whether `seconds` is finite and within +-kMaxTimeOffset_s.
[[nodiscard]] constexpr bool time_offset_in_range(double seconds) {
  return seconds >= -kMaxTimeOffset_s && seconds <= kMaxTimeOffset_s;  // false for NaN
}

struct WeekTow {
  int week = 0;        // continuous week number of the scale's own numbering (no rollover)
  double tow_s = 0.0;  // seconds of week [0, 604800)
};

// An instant, held as whole seconds of GPS time since 1980-01-06T00:00:00 GPST plus a fraction in
// [0, 1): exact to far below a picosecond over centuries (a single double would lose microseconds).
class GnssTime {
 public:
  constexpr GnssTime() = default;

  // From whole and fractional seconds of GPST since the GPS epoch; any split is normalised.
  [[nodiscard]] static GnssTime from_gpst_seconds(std::int64_t whole_s, double fraction_s = 0.0);
  // From a week and time of week in the given scale's own week numbering.
  [[nodiscard]] static GnssTime from_week_tow(TimeScale scale, int week, double tow_s);
  [[nodiscard]] static GnssTime from_calendar(const CalendarTime& calendar, TimeScale scale);
  // The same for values read from outside: a time of week or a second out of time_offset_in_range,
  // a month outside 1-12 or a day outside 1-31 is a kInvalidArgument error.
  [[nodiscard]] static Result<GnssTime> checked_week_tow(TimeScale scale, int week, double tow_s);
  [[nodiscard]] static Result<GnssTime> checked_calendar(const CalendarTime& calendar, TimeScale scale);
  // "YYYY-MM-DDThh:mm:ss[.fff]" (a space may replace T; a trailing Z is accepted for UTC).
  [[nodiscard]] static Result<GnssTime> parse_iso8601(std::string_view text, TimeScale scale);

  [[nodiscard]] std::int64_t whole_seconds() const { return whole_s_; }
  [[nodiscard]] double fraction_s() const { return fraction_s_; }
  // Seconds of GPST since the GPS epoch as a double (sub-microsecond only near the epoch: use for
  // coarse purposes such as sorting keys and plots, never for physics).
  [[nodiscard]] double gpst_seconds_approx() const { return static_cast<double>(whole_s_) + fraction_s_; }

  [[nodiscard]] WeekTow to_week_tow(TimeScale scale) const;
  [[nodiscard]] CalendarTime to_calendar(TimeScale scale) const;
  [[nodiscard]] int day_of_year(TimeScale scale) const;
  // The instant rounded to the nearest multiple of 10^-decimals s (decimals clamped to 0-15; halves
  // away from zero), the carry going into the whole seconds. Every scale differs from GPST by whole
  // seconds, so this is the same rounding in every scale. Round with this before taking a week and
  // time of week or calendar fields that are printed with `decimals` decimals.
  [[nodiscard]] GnssTime rounded_to(int decimals) const;
  // Calendar fields of rounded_to(decimals) in the given scale (see RoundedCalendarTime).
  [[nodiscard]] RoundedCalendarTime to_rounded_calendar(TimeScale scale, int decimals) const;
  // ISO 8601 text in the given scale with the given number of decimals of the second (0-15),
  // rounded on the timeline first (to_rounded_calendar). UTC and GLONASST show second 60 only
  // inside a real leap second.
  [[nodiscard]] std::string to_iso8601(TimeScale scale, int decimals = 3) const;

  GnssTime& operator+=(double dt_s);
  GnssTime& operator-=(double dt_s) { return *this += -dt_s; }
  [[nodiscard]] friend GnssTime operator+(GnssTime t, double dt_s) { return t += dt_s; }
  [[nodiscard]] friend GnssTime operator-(GnssTime t, double dt_s) { return t -= dt_s; }
  // Difference in seconds, exact to double precision of the difference itself.
  [[nodiscard]] friend double operator-(const GnssTime& a, const GnssTime& b) {
    return static_cast<double>(a.whole_s_ - b.whole_s_) + (a.fraction_s_ - b.fraction_s_);
  }
  friend auto operator<=>(const GnssTime&, const GnssTime&) = default;
  friend bool operator==(const GnssTime&, const GnssTime&) = default;

 private:
  std::int64_t whole_s_ = 0;
  double fraction_s_ = 0.0;
};

// GPS - UTC in whole seconds at the given instant (0 before 1981-07-01, 18 since 2017-01-01).
[[nodiscard]] int gps_minus_utc_s(const GnssTime& t);

// The full week number nearest to `reference` whose value modulo `modulus` (1024, 4096, 8192) is
// `truncated_week`, for week fields broadcast with few bits.
[[nodiscard]] int resolve_week_rollover(int truncated_week, int modulus, int reference_week);

}  // namespace skytrace
