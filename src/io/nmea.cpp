#include "skytrace/io/nmea.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <set>

namespace skytrace::io {
namespace {

constexpr double kKnotsPerMps = 3600.0 / 1852.0;
constexpr double kKmhPerMps = 3.6;

GnssSystem reporting_system(GnssSystem system) {
  return system == GnssSystem::kSbas ? GnssSystem::kGps : system;
}

// hhmmss.ss and the calendar of the instant rounded to 10 ms (UTC).
struct UtcStamp {
  std::string hhmmss;
  RoundedCalendarTime calendar;
};

UtcStamp utc_stamp(const GnssTime& t) {
  // Rounded to 10 ms on the continuous timeline first, then split, so that 59.995 s carries into
  // the minute, hour and date (ZDA, RMC); second 60 only inside a real UTC leap second.
  UtcStamp stamp;
  stamp.calendar = t.to_rounded_calendar(TimeScale::kUtc, 2);
  const RoundedCalendarTime& c = stamp.calendar;
  stamp.hhmmss = fmt::format("{:02d}{:02d}{:02d}.{:02d}", c.hour, c.minute, c.second, c.fraction);
  return stamp;
}

// ddmm.mmmmmmm (latitude, 2 degree digits) or dddmm.mmmmmmm (longitude) and the hemisphere.
std::string angle_field(double angle_deg, int degree_digits, char positive, char negative) {
  constexpr std::int64_t kScale = 10'000'000;  // 1e-7 minute (0.2 mm)
  const std::int64_t total = std::llround(std::abs(angle_deg) * 60.0 * static_cast<double>(kScale));
  const std::int64_t degrees = total / (60 * kScale);
  const std::int64_t minutes_scaled = total % (60 * kScale);
  return fmt::format("{:0{}d}{:02d}.{:07d},{}", degrees, degree_digits, minutes_scaled / kScale,
                     minutes_scaled % kScale, angle_deg < 0.0 ? negative : positive);
}

bool has_fix(const positioning::PositionFix& fix) { return fix.type != positioning::FixType::kNone; }

std::string talker_of_fix(const positioning::PositionFix& fix) {
  std::set<GnssSystem> systems;
  for (const auto& s : fix.satellites) {
    if (s.used || !has_fix(fix)) systems.insert(reporting_system(s.satellite.system));
  }
  if (systems.size() == 1) return std::string(nmea_talker(*systems.begin()));
  return "GN";
}

// GGA quality: 1 single point, 2 differential, 4 RTK fixed, 5 RTK float (NMEA 0183 4.11).
int gga_quality(const positioning::PositionFix& fix) {
  switch (fix.type) {
    case positioning::FixType::kDgnss: return 2;
    case positioning::FixType::kRtkFixed: return 4;
    case positioning::FixType::kRtkFloat: return 5;
    default: return 1;
  }
}

// Mode indicator of RMC and VTG: A autonomous, D differential, R RTK fixed, F RTK float.
char mode_indicator(const positioning::PositionFix& fix) {
  switch (fix.type) {
    case positioning::FixType::kDgnss: return 'D';
    case positioning::FixType::kRtkFixed: return 'R';
    case positioning::FixType::kRtkFloat: return 'F';
    default: return 'A';
  }
}

struct Motion {
  double speed_mps = 0.0;
  double course_deg = 0.0;
};

std::optional<Motion> motion_of(const positioning::PositionFix& fix) {
  if (!has_fix(fix) || !fix.velocity_valid) return std::nullopt;
  const double east = fix.velocity_enu_mps.x();
  const double north = fix.velocity_enu_mps.y();
  Motion m;
  m.speed_mps = std::hypot(east, north);
  m.course_deg = std::atan2(east, north) * 180.0 / M_PI;
  if (m.course_deg < 0.0) m.course_deg += 360.0;
  if (m.course_deg >= 359.995) m.course_deg = 0.0;
  return m;
}

std::string gga(const positioning::PositionFix& fix, const std::string& talker, const UtcStamp& stamp,
                const GeoidGrid* geoid) {
  if (!has_fix(fix)) return fmt::format("{}GGA,{},,,,,0,00,,,M,,M,,", talker, stamp.hhmmss);
  // Altitude above mean sea level and the geoid separation N, as receivers give them (the
  // ellipsoidal height is altitude + N, what gpsd and nmea_navsat_driver add up). Without a geoid
  // model: the ellipsoidal height with separation 0, so the sum is still exact.
  // Differential fixes give the age of the corrections (s); the base's station id is not known here.
  const std::string age = fix.relative && gga_quality(fix) != 1 ? fmt::format("{:.1f}", fix.relative->age_s) : "";
  double separation_m = geoid != nullptr ? geoid->undulation_m(fix.position.latitude_deg, fix.position.longitude_deg)
                                         : 0.0;
  if (!std::isfinite(separation_m)) separation_m = 0.0;
  return fmt::format("{}GGA,{},{},{},{},{:02d},{:.2f},{:.3f},M,{:.3f},M,{},", talker, stamp.hhmmss,
                     angle_field(fix.position.latitude_deg, 2, 'N', 'S'),
                     angle_field(fix.position.longitude_deg, 3, 'E', 'W'), gga_quality(fix), fix.satellites_used,
                     fix.hdop, fix.position.height_m - separation_m, separation_m, age);
}

std::string rmc(const positioning::PositionFix& fix, const std::string& talker, const UtcStamp& stamp) {
  const std::string date =
      fmt::format("{:02d}{:02d}{:02d}", stamp.calendar.day, stamp.calendar.month, stamp.calendar.year % 100);
  if (!has_fix(fix)) return fmt::format("{}RMC,{},V,,,,,,,{},,,N,V", talker, stamp.hhmmss, date);
  const auto motion = motion_of(fix);
  const std::string speed = motion ? fmt::format("{:.3f}", motion->speed_mps * kKnotsPerMps) : "";
  const std::string course = motion ? fmt::format("{:.2f}", motion->course_deg) : "";
  // Navigational status V: the receiver makes no integrity statement (NMEA 4.11 field 13).
  return fmt::format("{}RMC,{},A,{},{},{},{},{},,,{},V", talker, stamp.hhmmss,
                     angle_field(fix.position.latitude_deg, 2, 'N', 'S'),
                     angle_field(fix.position.longitude_deg, 3, 'E', 'W'), speed, course, date, mode_indicator(fix));
}

std::string vtg(const positioning::PositionFix& fix, const std::string& talker) {
  const auto motion = motion_of(fix);
  if (!motion) return fmt::format("{}VTG,,T,,M,,N,,K,N", talker);
  return fmt::format("{}VTG,{:.2f},T,,M,{:.3f},N,{:.3f},K,{}", talker, motion->course_deg,
                     motion->speed_mps * kKnotsPerMps, motion->speed_mps * kKmhPerMps, mode_indicator(fix));
}

std::string zda(const std::string& talker, const UtcStamp& stamp) {
  return fmt::format("{}ZDA,{},{:02d},{:02d},{:04d},00,00", talker, stamp.hhmmss, stamp.calendar.day,
                     stamp.calendar.month, stamp.calendar.year);
}

std::string gst(const positioning::PositionFix& fix, const std::string& talker, const UtcStamp& stamp) {
  if (!has_fix(fix)) return fmt::format("{}GST,{},,,,,,,", talker, stamp.hhmmss);
  double sum_sq = 0.0;
  int used = 0;
  for (const auto& s : fix.satellites) {
    if (!s.used) continue;
    sum_sq += s.residual_m * s.residual_m;
    ++used;
  }
  const double rms_m = used > 0 ? std::sqrt(sum_sq / used) : 0.0;
  const Eigen::Matrix3d& c = fix.covariance_enu_m2;
  const double ee = c(0, 0), nn = c(1, 1), en = c(0, 1);
  const double mean = 0.5 * (ee + nn);
  const double radius = std::sqrt(0.25 * (ee - nn) * (ee - nn) + en * en);
  const double major_m = std::sqrt(std::max(0.0, mean + radius));
  const double minor_m = std::sqrt(std::max(0.0, mean - radius));
  // Orientation of the semi-major axis, degrees from true north towards east, [0, 180).
  double orientation_deg = 0.5 * std::atan2(2.0 * en, nn - ee) * 180.0 / M_PI;
  if (orientation_deg < 0.0) orientation_deg += 180.0;
  if (orientation_deg >= 179.995) orientation_deg = 0.0;
  return fmt::format("{}GST,{},{:.3f},{:.3f},{:.3f},{:.2f},{:.3f},{:.3f},{:.3f}", talker, stamp.hhmmss, rms_m,
                     major_m, minor_m, orientation_deg, std::sqrt(std::max(0.0, nn)),
                     std::sqrt(std::max(0.0, ee)), std::sqrt(std::max(0.0, c(2, 2))));
}

std::vector<std::string> gsa(const positioning::PositionFix& fix, const std::string& talker) {
  // Systems in view, by NMEA system ID; the used satellites of each.
  std::map<int, std::vector<int>> used_by_system;
  for (const auto& s : fix.satellites) {
    const int system_id = nmea_system_id(s.satellite.system);
    auto& ids = used_by_system[system_id];
    const auto id = nmea_satellite_id(s.satellite);
    if (s.used && has_fix(fix) && id) ids.push_back(*id);
  }
  if (used_by_system.empty()) used_by_system[1] = {};
  const char mode = positioning::is_3d(fix.type) ? '3' : fix.type == positioning::FixType::kFix2D ? '2' : '1';
  const std::string dops =
      has_fix(fix) ? fmt::format("{:.2f},{:.2f},{:.2f}", fix.pdop, fix.hdop, fix.vdop) : std::string(",,");
  std::vector<std::string> bodies;
  for (auto& [system_id, ids] : used_by_system) {
    std::sort(ids.begin(), ids.end());
    ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
    // Twelve slots per sentence; more used satellites of a system continue in another sentence.
    size_t start = 0;
    do {
      std::string body = fmt::format("{}GSA,A,{}", talker, mode);
      for (size_t slot = 0; slot < 12; ++slot) {
        body += ',';
        if (start + slot < ids.size()) body += fmt::format("{:02d}", ids[start + slot]);
      }
      body += fmt::format(",{},{:X}", dops, system_id);
      bodies.push_back(std::move(body));
      start += 12;
    } while (start < ids.size());
  }
  return bodies;
}

std::vector<std::string> gsv(const positioning::PositionFix& fix) {
  struct InView {
    int id;
    int elevation_deg;
    int azimuth_deg;
    std::optional<int> cn0_dbhz;
  };
  // (system ID, signal ID) -> satellites, in the system order GPS, GLONASS, Galileo, BeiDou, QZSS, NavIC.
  std::map<std::pair<int, int>, std::vector<InView>> groups;
  std::map<int, std::string_view> talkers;
  for (const auto& s : fix.satellites) {
    const auto id = nmea_satellite_id(s.satellite);
    if (!id) continue;
    const int system_id = nmea_system_id(s.satellite.system);
    talkers[system_id] = nmea_talker(s.satellite.system);
    InView v;
    v.id = *id;
    v.elevation_deg = std::clamp(static_cast<int>(std::lround(s.direction.elevation_deg)), 0, 90);
    v.azimuth_deg = static_cast<int>(std::lround(s.direction.azimuth_deg)) % 360;
    if (v.azimuth_deg < 0) v.azimuth_deg += 360;
    if (s.cn0_dbhz > 0.0) v.cn0_dbhz = std::clamp(static_cast<int>(std::lround(s.cn0_dbhz)), 0, 99);
    groups[{system_id, nmea_signal_id(s.signal)}].push_back(v);
  }
  std::vector<std::string> bodies;
  for (auto& [key, satellites] : groups) {
    std::sort(satellites.begin(), satellites.end(), [](const InView& a, const InView& b) { return a.id < b.id; });
    const size_t count = satellites.size();
    const size_t sentences = (count + 3) / 4;
    for (size_t k = 0; k < sentences; ++k) {
      std::string body = fmt::format("{}GSV,{},{},{:02d}", talkers[key.first], sentences, k + 1, count);
      for (size_t j = 4 * k; j < std::min(count, 4 * k + 4); ++j) {
        const auto& v = satellites[j];
        body += fmt::format(",{:02d},{:02d},{:03d},", v.id, v.elevation_deg, v.azimuth_deg);
        if (v.cn0_dbhz) body += fmt::format("{:02d}", *v.cn0_dbhz);
      }
      body += fmt::format(",{:X}", key.second);
      bodies.push_back(std::move(body));
    }
  }
  return bodies;
}

}  // namespace

std::string nmea_checksum(std::string_view body) {
  unsigned char sum = 0;
  for (const char c : body) sum ^= static_cast<unsigned char>(c);
  return fmt::format("{:02X}", sum);
}

std::string nmea_sentence(std::string_view body) {
  std::string sentence;
  sentence.reserve(body.size() + 6);
  sentence += '$';
  sentence += body;
  sentence += '*';
  sentence += nmea_checksum(body);
  sentence += "\r\n";
  return sentence;
}

bool nmea_checksum_valid(std::string_view line) {
  while (!line.empty() && (line.back() == '\n' || line.back() == '\r')) line.remove_suffix(1);
  if (line.size() < 4 || line.front() != '$') return false;
  const size_t star = line.rfind('*');
  if (star == std::string_view::npos || star + 3 != line.size()) return false;
  return nmea_checksum(line.substr(1, star - 1)) == line.substr(star + 1);
}

int nmea_system_id(GnssSystem system) {
  switch (system) {
    case GnssSystem::kGps:
    case GnssSystem::kSbas: return 1;
    case GnssSystem::kGlonass: return 2;
    case GnssSystem::kGalileo: return 3;
    case GnssSystem::kBeiDou: return 4;
    case GnssSystem::kQzss: return 5;
    case GnssSystem::kNavic: return 6;
  }
  return 1;
}

std::string_view nmea_talker(GnssSystem system) {
  switch (system) {
    case GnssSystem::kGps:
    case GnssSystem::kSbas: return "GP";
    case GnssSystem::kGlonass: return "GL";
    case GnssSystem::kGalileo: return "GA";
    case GnssSystem::kBeiDou: return "GB";
    case GnssSystem::kQzss: return "GQ";
    case GnssSystem::kNavic: return "GI";
  }
  return "GN";
}

std::optional<int> nmea_satellite_id(const SatelliteId& satellite) {
  const int n = satellite.number;
  const auto in = [n](int low, int high) { return n >= low && n <= high; };
  switch (satellite.system) {
    case GnssSystem::kGps: return in(1, 32) ? std::optional<int>(n) : std::nullopt;
    case GnssSystem::kSbas: {
      const int prn = satellite.prn();
      return prn >= 120 && prn <= 151 ? std::optional<int>(prn - 87) : std::nullopt;
    }
    case GnssSystem::kGlonass: return in(1, 32) ? std::optional<int>(n + 64) : std::nullopt;
    case GnssSystem::kGalileo: return in(1, 36) ? std::optional<int>(n) : std::nullopt;
    case GnssSystem::kBeiDou: return in(1, 63) ? std::optional<int>(n) : std::nullopt;
    case GnssSystem::kQzss: return in(1, 10) ? std::optional<int>(n) : std::nullopt;
    case GnssSystem::kNavic: return in(1, 14) ? std::optional<int>(n) : std::nullopt;
  }
  return std::nullopt;
}

int nmea_signal_id(const Signal& signal) {
  const char b = signal.band;
  const char a = signal.attribute;
  const auto any = [a](std::string_view letters) { return letters.find(a) != std::string_view::npos; };
  switch (signal.system) {
    case GnssSystem::kGps:
    case GnssSystem::kSbas:
      if (b == '1') return a == 'C' ? 1 : any("PWY") ? 2 : a == 'M' ? 3 : 0;
      if (b == '2') return any("PWYD") ? 4 : a == 'S' ? 5 : any("LX") ? 6 : 0;
      if (b == '5') return a == 'I' ? 7 : any("QX") ? 8 : 0;
      return 0;
    case GnssSystem::kGlonass:
      if (b == '1') return a == 'C' ? 1 : a == 'P' ? 2 : 0;
      if (b == '2') return a == 'C' ? 3 : a == 'P' ? 4 : 0;
      return 0;
    case GnssSystem::kGalileo:
      if (b == '5') return 1;
      if (b == '7') return 2;
      if (b == '8') return 3;
      if (b == '6') return a == 'A' ? 4 : 5;
      if (b == '1') return a == 'A' ? 6 : 7;
      return 0;
    case GnssSystem::kBeiDou:
      if (b == '2') return a == 'I' ? 1 : a == 'Q' ? 2 : 1;
      if (b == '1') return a == 'A' ? 4 : 3;
      if (b == '5') return 5;
      if (b == '7') return any("DPZ") ? 6 : a == 'Q' ? 0xC : 0xB;
      if (b == '8') return 7;
      if (b == '6') return a == 'I' ? 8 : a == 'Q' ? 9 : a == 'A' ? 0xA : 8;
      return 0;
    case GnssSystem::kQzss:
      if (b == '1') return a == 'C' ? 1 : a == 'S' ? 2 : any("LX") ? 3 : a == 'Z' ? 4 : 0;
      if (b == '2') return a == 'S' ? 5 : 6;
      if (b == '5') return a == 'I' ? 7 : any("QX") ? 8 : 0;
      if (b == '6') return a == 'S' ? 9 : 0xA;
      return 0;
    case GnssSystem::kNavic:
      if (b == '5') return a == 'A' ? 1 : a == 'B' ? 3 : 0;
      if (b == '9') return a == 'A' ? 2 : a == 'B' ? 4 : 0;
      if (b == '1') return 5;
      return 0;
  }
  return 0;
}

std::vector<std::string> nmea_epoch(const positioning::PositionFix& fix, const NmeaSettings& settings) {
  const UtcStamp stamp = utc_stamp(has_fix(fix) ? fix.time : fix.receiver_time);
  const std::string talker = talker_of_fix(fix);
  std::vector<std::string> sentences;
  if (settings.gga) sentences.push_back(nmea_sentence(gga(fix, talker, stamp, settings.geoid)));
  if (settings.gsa) {
    for (const auto& body : gsa(fix, talker)) sentences.push_back(nmea_sentence(body));
  }
  if (settings.gsv) {
    for (const auto& body : gsv(fix)) sentences.push_back(nmea_sentence(body));
  }
  if (settings.rmc) sentences.push_back(nmea_sentence(rmc(fix, talker, stamp)));
  if (settings.vtg) sentences.push_back(nmea_sentence(vtg(fix, talker)));
  if (settings.zda) sentences.push_back(nmea_sentence(zda(talker, stamp)));
  if (settings.gst) sentences.push_back(nmea_sentence(gst(fix, talker, stamp)));
  // A moving-base rover's heading: HDT (true heading) and THS (with mode A, autonomous).
  if (fix.relative && fix.relative->heading_deg) {
    sentences.push_back(nmea_sentence(fmt::format("{}HDT,{:.3f},T", talker, *fix.relative->heading_deg)));
    sentences.push_back(nmea_sentence(fmt::format("{}THS,{:.2f},A", talker, *fix.relative->heading_deg)));
  }
  return sentences;
}

}  // namespace skytrace::io
