#include "skytrace/orbits/ephemeris.hpp"

#include <algorithm>
#include <cmath>

namespace skytrace::orbits {

bool is_cnav(NavMessage message) {
  return message == NavMessage::kGpsCnav || message == NavMessage::kGpsCnav2 || message == NavMessage::kQzssCnav ||
         message == NavMessage::kQzssCnav2;
}

std::string_view to_string(NavMessage message) {
  switch (message) {
    case NavMessage::kGpsLnav: return "LNAV";
    case NavMessage::kGpsCnav: return "CNAV";
    case NavMessage::kGpsCnav2: return "CNV2";
    case NavMessage::kGalileoInav: return "INAV";
    case NavMessage::kGalileoFnav: return "FNAV";
    case NavMessage::kBeiDouD1: return "D1";
    case NavMessage::kBeiDouD2: return "D2";
    case NavMessage::kBeiDouCnav1: return "CNV1";
    case NavMessage::kBeiDouCnav2: return "CNV2";
    case NavMessage::kBeiDouCnav3: return "CNV3";
    case NavMessage::kQzssLnav: return "LNAV";
    case NavMessage::kQzssCnav: return "CNAV";
    case NavMessage::kQzssCnav2: return "CNV2";
    case NavMessage::kNavicLnav: return "LNAV";
    case NavMessage::kGlonassFdma: return "FDMA";
    case NavMessage::kSbas: return "SBAS";
  }
  return "?";
}

double ephemeris_decode_time_s(NavMessage message) {
  // Why each value: ephemeris.hpp.
  switch (message) {
    case NavMessage::kGpsLnav:
    case NavMessage::kQzssLnav: return 30.0;
    case NavMessage::kGpsCnav:
    case NavMessage::kQzssCnav: return 48.0;
    case NavMessage::kGpsCnav2:
    case NavMessage::kQzssCnav2: return 18.0;
    case NavMessage::kGalileoInav: return 30.0;
    case NavMessage::kGalileoFnav: return 50.0;
    case NavMessage::kBeiDouD1:
    case NavMessage::kBeiDouD2: return 30.0;
    case NavMessage::kBeiDouCnav1: return 18.0;
    case NavMessage::kBeiDouCnav2:
    case NavMessage::kBeiDouCnav3: return 48.0;
    case NavMessage::kNavicLnav: return 48.0;
    case NavMessage::kGlonassFdma: return 30.0;
    case NavMessage::kSbas: return 12.0;
  }
  return 30.0;
}

namespace {

constexpr double kWeek_s = 604800.0;
constexpr double kDay_s = 86400.0;

// A transmission time of message the file actually gives: not blank (the readers store
// kUnknownTransmissionTime_s), not RINEX's 0.9999E9, not beyond two weeks either way.
bool known_seconds(double value_s) { return std::isfinite(value_s) && std::fabs(value_s) <= 2.0 * kWeek_s; }

// Seconds of a week on the GPST timeline, taken within half a week of `reference`.
GnssTime within_half_week(TimeScale scale, int week, double seconds_of_week, const GnssTime& reference) {
  const GnssTime t = GnssTime::from_week_tow(scale, week, seconds_of_week);
  const double weeks = std::round((t - reference) / kWeek_s);
  return weeks == 0.0 ? t : t - weeks * kWeek_s;
}

}  // namespace

std::optional<GnssTime> transmission_time(const KeplerEphemeris& eph) {
  const double tt = eph.transmission_time_sow;
  if (!known_seconds(tt) || tt == 0.0) return std::nullopt;
  // The week of the record (RINEX "to go with toe"): GPS weeks for GPS, QZSS, Galileo and NavIC
  // in RINEX 3/4, BDT weeks for BeiDou, as the readers take them.
  const TimeScale scale = eph.satellite.system == GnssSystem::kBeiDou ? TimeScale::kBdt : TimeScale::kGpst;
  return within_half_week(scale, eph.week, tt, eph.toe);
}

std::optional<GnssTime> transmission_time(const SbasEphemeris& eph) {
  const double tt = eph.transmission_time_sow;
  if (!known_seconds(tt) || tt == 0.0) return std::nullopt;
  return within_half_week(TimeScale::kGpst, eph.toe.to_week_tow(TimeScale::kGpst).week, tt, eph.toe);
}

std::optional<GnssTime> transmission_time(const GlonassEphemeris& eph) {
  const double tk = eph.message_frame_time_s;
  if (!std::isfinite(tk) || tk < 0.0 || tk >= kDay_s) return std::nullopt;
  // t_k counts the UTC day (RINEX; the satellite counts Moscow time, RINEX converts): the UTC day
  // of t_b, or the one before or after, whichever puts it within 12 h of t_b.
  CalendarTime day = eph.toe.to_calendar(TimeScale::kUtc);
  day.hour = 0;
  day.minute = 0;
  day.second = 0.0;
  GnssTime t = GnssTime::from_calendar(day, TimeScale::kUtc) + tk;
  if (t - eph.toe > kDay_s / 2.0) t -= kDay_s;
  if (eph.toe - t > kDay_s / 2.0) t += kDay_s;
  return t;
}

namespace {

bool same_record(const KeplerEphemeris& a, const KeplerEphemeris& b) {
  return a.satellite == b.satellite && a.message == b.message && a.toe == b.toe && a.toc == b.toc &&
         a.iode == b.iode && a.af0_s == b.af0_s && a.m0_rad == b.m0_rad && a.data_source == b.data_source;
}
bool same_record(const GlonassEphemeris& a, const GlonassEphemeris& b) {
  return a.satellite == b.satellite && a.toe == b.toe && a.position_m == b.position_m &&
         a.minus_tau_n_s == b.minus_tau_n_s;
}
bool same_record(const SbasEphemeris& a, const SbasEphemeris& b) {
  return a.satellite == b.satellite && a.toe == b.toe && a.position_m == b.position_m;
}

template <typename Record>
void append_unique(std::vector<Record>& into, std::vector<Record>&& from) {
  const size_t existing = into.size();
  for (auto& record : from) {
    const auto begin = into.begin();
    const auto end = into.begin() + static_cast<std::ptrdiff_t>(existing);
    if (std::none_of(begin, end, [&](const Record& r) { return same_record(r, record); })) {
      into.push_back(std::move(record));
    }
  }
}

template <typename T>
void keep_first(std::optional<T>& mine, const std::optional<T>& theirs) {
  if (!mine && theirs) mine = theirs;
}

}  // namespace

void NavigationData::merge(NavigationData other) {
  append_unique(kepler, std::move(other.kepler));
  append_unique(glonass, std::move(other.glonass));
  append_unique(sbas, std::move(other.sbas));
  keep_first(ionosphere.gps, other.ionosphere.gps);
  keep_first(ionosphere.qzss, other.ionosphere.qzss);
  keep_first(ionosphere.beidou, other.ionosphere.beidou);
  keep_first(ionosphere.navic, other.ionosphere.navic);
  keep_first(ionosphere.galileo, other.ionosphere.galileo);
  for (auto& correction : other.time_corrections) {
    const bool known = std::any_of(time_corrections.begin(), time_corrections.end(),
                                   [&](const TimeSystemCorrection& c) { return c.type == correction.type; });
    if (!known) time_corrections.push_back(std::move(correction));
  }
  keep_first(leap_seconds, other.leap_seconds);
  for (auto& file : other.source_files) source_files.push_back(std::move(file));
  for (auto& warning : other.warnings) warnings.push_back(std::move(warning));
}

}  // namespace skytrace::orbits
