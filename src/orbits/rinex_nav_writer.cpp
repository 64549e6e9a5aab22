// RINEX 3.04 mixed navigation writer.
//
// Layout per RINEX 3.04 (IGS/RTCM-SC104, 23 Nov 2018), appendix tables A5-A21:
//   header   60 columns of content + label in columns 61-80;
//   record   "G05 2020 06 25 00 00 00" (A1,I2.2,1X,I4,5(1X,I2.2)) + 3 x D19.12,
//            then "broadcast orbit" lines of 4X + up to 4 x D19.12.
// Numbers are written as "%19.12E" (13 significant digits), the style of current RINEX 3 writers:
// enough for a write -> read round trip to 5e-13 relative.
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "skytrace/orbits/rinex_nav.hpp"

namespace skytrace::orbits {
namespace {

constexpr double kSecondsPerWeek = 604800.0;

// One value in D19.12 style ("-6.528543308377E-04", 19 columns). Values too small for a two-digit
// exponent are written as zero; values too large lose a digit rather than overflow the field.
std::string d19(double value) {
  if (value != 0.0 && std::isfinite(value) && std::fabs(value) < 1e-99) value = 0.0;
  char buffer[64];
  for (int precision = 12; precision >= 6; --precision) {
    const int n = std::snprintf(buffer, sizeof buffer, "%19.*E", precision, value);
    if (n == 19) return buffer;
  }
  return buffer;  // non-finite values: left visible so that a reader rejects the line
}

// Pads `content` to 60 columns and appends the header label.
std::string header_line(std::string content, const char* label) {
  content.resize(60, ' ');
  return content + label + "\n";
}

std::string format_utc_now() {
  using namespace std::chrono;
  const auto now = system_clock::now();
  const auto day = floor<days>(now);
  const year_month_day ymd{day};
  const hh_mm_ss hms{floor<seconds>(now - day)};
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%04d%02u%02u %02d%02d%02d UTC",
                static_cast<int>(ymd.year()), static_cast<unsigned>(ymd.month()),
                static_cast<unsigned>(ymd.day()), static_cast<int>(hms.hours().count()),
                static_cast<int>(hms.minutes().count()), static_cast<int>(hms.seconds().count()));
  return buffer;
}

// The record epoch "G05 2020 06 25 00 00 00" in the given time scale, rounded to the second on the
// timeline first (navigation epochs are whole seconds; 59.6 s carries into the next minute, hour,
// day, month and year; second 60 only inside a real leap second of UTC for GLONASS records).
std::string epoch_field(const SatelliteId& satellite, const GnssTime& t, TimeScale scale) {
  const RoundedCalendarTime c = t.to_rounded_calendar(scale, 0);
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%c%02d %04d %02d %02d %02d %02d %02d",
                system_letter(satellite.system), static_cast<int>(satellite.number), c.year,
                c.month, c.day, c.hour, c.minute, c.second);
  return buffer;
}

// A record: the epoch line with three values, then orbit lines of up to four values each.
// Trailing spare fields are left out (blank), as the format allows.
class RecordWriter {
 public:
  RecordWriter(std::string& out, const std::string& epoch, double v0, double v1, double v2)
      : out_(out) {
    out_ += epoch + d19(v0) + d19(v1) + d19(v2) + "\n";
  }
  RecordWriter& line(std::initializer_list<double> values) {
    out_ += "    ";
    for (const double v : values) out_ += d19(v);
    out_ += "\n";
    return *this;
  }

 private:
  std::string& out_;
};

// Week and seconds of week of toe as the file states them: the stored values when the record has
// them (a round trip keeps what the source file said), else derived from toe.
std::pair<int, double> toe_week_sow(const KeplerEphemeris& eph) {
  if (eph.week > 0) return {eph.week, eph.toe_sow};
  // RINEX 3: GPS weeks for G, E, J and I (Galileo and NavIC weeks are written aligned to GPS);
  // BDT weeks for C.
  const TimeScale scale =
      eph.satellite.system == GnssSystem::kBeiDou ? TimeScale::kBdt : TimeScale::kGpst;
  const WeekTow wt = eph.toe.to_week_tow(scale);
  return {wt.week, wt.tow_s};
}

// Galileo data-source bits when a hand-made record leaves them at zero: I/NAV E1-B + E5b with
// clock for E5b/E1 (517), F/NAV E5a with clock for E5a/E1 (258).
double galileo_data_source(const KeplerEphemeris& eph) {
  if (eph.data_source != 0) return static_cast<double>(eph.data_source);
  return eph.message == NavMessage::kGalileoFnav ? 258.0 : 517.0;
}

// QZSS line 7 carries a fit-interval *flag* (0: 2 hours, 1: more than 2 hours; IS-QZSS 4.1.2.7).
// Records hold hours: up to 2 h is flag 0; more, or 0 (not quantified, as read from flag 1), is 1.
double qzss_fit_flag(double fit_interval_h) {
  return fit_interval_h > 0.0 && fit_interval_h <= 2.0 ? 0.0 : 1.0;
}

void write_kepler(std::string& out, const KeplerEphemeris& e) {
  const GnssSystem system = e.satellite.system;
  const auto [week, toe_sow] = toe_week_sow(e);
  const std::string epoch = epoch_field(e.satellite, e.toc, system_time_scale(system));
  RecordWriter w(out, epoch, e.af0_s, e.af1_s_per_s, e.af2_s_per_s2);
  // Lines 1-4 are common to all Keplerian systems.
  w.line({static_cast<double>(e.iode), e.crs_m, e.delta_n_rad_per_s, e.m0_rad})
      .line({e.cuc_rad, e.eccentricity, e.cus_rad, e.sqrt_a_sqrtm})
      .line({toe_sow, e.cic_rad, e.omega0_rad, e.cis_rad})
      .line({e.i0_rad, e.crc_m, e.omega_rad, e.omega_dot_rad_per_s});
  const double wk = static_cast<double>(week);
  const double health = static_cast<double>(e.health);
  const GroupDelays& gd = e.group_delays;
  switch (system) {
    case GnssSystem::kGps:
      w.line({e.idot_rad_per_s, static_cast<double>(e.codes_on_l2), wk,
              static_cast<double>(e.l2p_data_flag)})
          .line({e.accuracy_m, health, gd.tgd_s, static_cast<double>(e.iodc)})
          .line({e.transmission_time_sow, e.fit_interval_h});
      break;
    case GnssSystem::kQzss:
      w.line({e.idot_rad_per_s, static_cast<double>(e.codes_on_l2), wk,
              static_cast<double>(e.l2p_data_flag)})
          .line({e.accuracy_m, health, gd.tgd_s, static_cast<double>(e.iodc)})
          .line({e.transmission_time_sow, qzss_fit_flag(e.fit_interval_h)});
      break;
    case GnssSystem::kGalileo:
      w.line({e.idot_rad_per_s, galileo_data_source(e), wk})
          .line({e.accuracy_m, health, gd.bgd_e1e5a_s, gd.bgd_e1e5b_s})
          .line({e.transmission_time_sow});
      break;
    case GnssSystem::kBeiDou:
      w.line({e.idot_rad_per_s, 0.0, wk})
          .line({e.accuracy_m, health, gd.tgd1_s, gd.tgd2_s})
          .line({e.transmission_time_sow, static_cast<double>(e.iodc)});
      break;
    case GnssSystem::kNavic:
      w.line({e.idot_rad_per_s, 0.0, wk})
          .line({e.accuracy_m, health, gd.tgd_s})
          .line({e.transmission_time_sow});
      break;
    default:
      break;  // not Keplerian: excluded before we get here
  }
}

// RINEX 3 gives the GLONASS message frame time in seconds of the UTC week. A record may hold
// seconds of the UTC day (RINEX 2 style); those are placed in the week of t_b, within half a day
// of it (t_k precedes t_b by up to a few minutes, possibly across midnight).
double glonass_frame_time_of_week(const GlonassEphemeris& g) {
  const double tk = g.message_frame_time_s;
  if (tk >= 86400.0 || tk < 0.0) return tk;
  const double tb_sow = g.toe.to_week_tow(TimeScale::kUtc).tow_s;
  const double day_start = std::floor(tb_sow / 86400.0) * 86400.0;
  double sow = day_start + tk;
  if (sow - tb_sow > 43200.0) sow -= 86400.0;
  if (tb_sow - sow > 43200.0) sow += 86400.0;
  // Keep it in [0, 604800) as RINEX writers do (readers place it within a day of t_b).
  if (sow >= kSecondsPerWeek) sow -= kSecondsPerWeek;
  if (sow < 0.0) sow += kSecondsPerWeek;
  return sow;
}

void write_glonass(std::string& out, const GlonassEphemeris& g) {
  const std::string epoch = epoch_field(g.satellite, g.toe, TimeScale::kUtc);
  constexpr double kKm = 1e-3;
  // RINEX 3.04 has three orbit lines; the 3.05 fourth line (group delay, status) is not written.
  RecordWriter(out, epoch, g.minus_tau_n_s, g.gamma_n, glonass_frame_time_of_week(g))
      .line({g.position_m.x() * kKm, g.velocity_mps.x() * kKm, g.acceleration_mps2.x() * kKm,
             static_cast<double>(g.health)})
      .line({g.position_m.y() * kKm, g.velocity_mps.y() * kKm, g.acceleration_mps2.y() * kKm,
             static_cast<double>(g.frequency_channel)})
      .line({g.position_m.z() * kKm, g.velocity_mps.z() * kKm, g.acceleration_mps2.z() * kKm,
             g.age_days});
}

void write_sbas(std::string& out, const SbasEphemeris& s) {
  const std::string epoch = epoch_field(s.satellite, s.toe, TimeScale::kGpst);
  constexpr double kKm = 1e-3;
  RecordWriter(out, epoch, s.agf0_s, s.agf1_s_per_s, s.transmission_time_sow)
      .line({s.position_m.x() * kKm, s.velocity_mps.x() * kKm, s.acceleration_mps2.x() * kKm,
             static_cast<double>(s.health)})
      .line({s.position_m.y() * kKm, s.velocity_mps.y() * kKm, s.acceleration_mps2.y() * kKm,
             s.accuracy_m})
      .line({s.position_m.z() * kKm, s.velocity_mps.z() * kKm, s.acceleration_mps2.z() * kKm,
             static_cast<double>(s.iodn)});
}

bool rinex3_can_hold(NavMessage message) {
  switch (message) {
    case NavMessage::kGpsLnav:
    case NavMessage::kGalileoInav:
    case NavMessage::kGalileoFnav:
    case NavMessage::kBeiDouD1:
    case NavMessage::kBeiDouD2:
    case NavMessage::kQzssLnav:
    case NavMessage::kNavicLnav:
      return true;
    default:
      return false;
  }
}

int system_rank(GnssSystem system) {
  const auto it = std::find(kAllSystems.begin(), kAllSystems.end(), system);
  return static_cast<int>(it - kAllSystems.begin());
}

// Sort key of one record in the output: system (G R E C J I S), satellite, message rank, toe.
// Galileo I/NAV comes before F/NAV of the same satellite: RTKLIB takes group delays from the first
// record of a satellite, and F/NAV records carry no BGD(E1,E5b).
struct RecordRef {
  int system = 0;
  int number = 0;
  int message_rank = 0;
  GnssTime toe;
  int kind = 0;  // 0 Kepler, 1 GLONASS, 2 SBAS
  size_t index = 0;
  friend bool operator<(const RecordRef& a, const RecordRef& b) {
    if (a.system != b.system) return a.system < b.system;
    if (a.number != b.number) return a.number < b.number;
    if (a.message_rank != b.message_rank) return a.message_rank < b.message_rank;
    return a.toe < b.toe;
  }
};

void write_klobuchar(std::string& out, const char* alpha_name, const char* beta_name,
                     const KlobucharCoefficients& k) {
  auto line = [&](const char* name, const std::array<double, 4>& v) {
    char buffer[96];
    std::snprintf(buffer, sizeof buffer, "%-4s %12.4E%12.4E%12.4E%12.4E", name, v[0], v[1], v[2],
                  v[3]);
    out += header_line(buffer, "IONOSPHERIC CORR");
  };
  line(alpha_name, k.alpha);
  line(beta_name, k.beta);
}

void write_time_correction(std::string& out, const TimeSystemCorrection& c) {
  // Reference time as seconds of week and week: BDT weeks for BeiDou corrections, GPS weeks for
  // the rest (RINEX 3.04 table A5: GAL, QZS, IRN and SBAS weeks are aligned to GPS).
  // Rounded to the second before the split into week and seconds of week, so that 604799.6 s
  // becomes second 0 of the next week rather than second 604800.
  const bool beidou = c.type.rfind("BD", 0) == 0;
  const WeekTow wt = c.reference_time.rounded_to(0).to_week_tow(beidou ? TimeScale::kBdt : TimeScale::kGpst);
  int week = wt.week;
  long sow = std::lround(wt.tow_s);
  if (c.reference_time == GnssTime{}) {  // not given (e.g. GLUT): RINEX writes zeros
    week = 0;
    sow = 0;
  }
  char buffer[96];
  std::snprintf(buffer, sizeof buffer, "%-4.4s %17.10E%16.9E %6ld %4d", c.type.c_str(), c.a0_s,
                c.a1_s_per_s, sow, week);
  out += header_line(buffer, "TIME SYSTEM CORR");
}

}  // namespace

std::string format_rinex3_nav(const NavigationData& data, const RinexNavWriteOptions& options) {
  std::vector<RecordRef> records;
  records.reserve(data.record_count());
  size_t omitted = 0;
  for (size_t i = 0; i < data.kepler.size(); ++i) {
    const KeplerEphemeris& e = data.kepler[i];
    if (!rinex3_can_hold(e.message)) {
      ++omitted;
      continue;
    }
    const int rank = e.message == NavMessage::kGalileoFnav ? 1 : 0;
    records.push_back({system_rank(e.satellite.system), e.satellite.number, rank, e.toe, 0, i});
  }
  for (size_t i = 0; i < data.glonass.size(); ++i) {
    const GlonassEphemeris& g = data.glonass[i];
    records.push_back({system_rank(g.satellite.system), g.satellite.number, 0, g.toe, 1, i});
  }
  for (size_t i = 0; i < data.sbas.size(); ++i) {
    const SbasEphemeris& s = data.sbas[i];
    records.push_back({system_rank(s.satellite.system), s.satellite.number, 0, s.toe, 2, i});
  }
  std::stable_sort(records.begin(), records.end());

  std::string out;
  out.reserve(80 * (12 + 8 * records.size()));
  out += header_line("     3.04           N: GNSS NAV DATA    M: MIXED", "RINEX VERSION / TYPE");
  {
    const std::string date =
        options.creation_date.empty() ? format_utc_now() : options.creation_date;
    char buffer[96];
    std::snprintf(buffer, sizeof buffer, "%-20.20s%-20.20s%-20.20s", options.program.c_str(),
                  options.run_by.c_str(), date.c_str());
    out += header_line(buffer, "PGM / RUN BY / DATE");
  }
  if (omitted > 0) {
    const std::string note = std::to_string(omitted) + " CNAV/CNAV-2/B-CNAV records left out";
    out += header_line(note, "COMMENT");
    out += header_line("(RINEX 3.04 has no layout for them)", "COMMENT");
  }
  const IonosphereCoefficients& ion = data.ionosphere;
  if (ion.galileo) {
    char buffer[96];
    std::snprintf(buffer, sizeof buffer, "GAL  %12.4E%12.4E%12.4E%12.4E", ion.galileo->ai0_sfu,
                  ion.galileo->ai1_sfu_per_deg, ion.galileo->ai2_sfu_per_deg2, 0.0);
    out += header_line(buffer, "IONOSPHERIC CORR");
  }
  if (ion.gps) write_klobuchar(out, "GPSA", "GPSB", *ion.gps);
  if (ion.qzss) write_klobuchar(out, "QZSA", "QZSB", *ion.qzss);
  if (ion.beidou) write_klobuchar(out, "BDSA", "BDSB", *ion.beidou);
  if (ion.navic) write_klobuchar(out, "IRNA", "IRNB", *ion.navic);
  for (const auto& correction : data.time_corrections) write_time_correction(out, correction);
  if (data.leap_seconds) {
    char buffer[16];
    std::snprintf(buffer, sizeof buffer, "%6d", *data.leap_seconds);
    out += header_line(buffer, "LEAP SECONDS");
  }
  out += header_line("", "END OF HEADER");

  for (const RecordRef& r : records) {
    switch (r.kind) {
      case 0:
        write_kepler(out, data.kepler[r.index]);
        break;
      case 1:
        write_glonass(out, data.glonass[r.index]);
        break;
      default:
        write_sbas(out, data.sbas[r.index]);
        break;
    }
  }
  return out;
}

}  // namespace skytrace::orbits
