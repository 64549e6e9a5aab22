// Nominal constellation: the generated broadcast records, evaluated with the receiver algorithm
// (evaluate_kepler / evaluate_glonass through BroadcastEphemerides), must give the published
// designs: satellites per system, orbit radius, inclination, period, GEO longitudes, IGSO equator
// crossings, the QZSS figure-8 centre and the GPS slot table at its epoch.
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>

#include "skytrace/core/constants.hpp"
#include "skytrace/orbits/broadcast.hpp"
#include "skytrace/orbits/nominal.hpp"
#include "test_support.hpp"

namespace skytrace::orbits {
namespace {

constexpr double kDeg = 3.14159265358979323846 / 180.0;

GnssTime test_start() {
  return GnssTime::from_calendar(CalendarTime{2020, 6, 25, 0, 0, 0.0}, TimeScale::kGpst);
}

const NavigationData& day_data() {
  static const NavigationData data = make_nominal_constellation(test_start(), 86400.0).value();
  return data;
}

struct Earth {
  double gm_m3ps2;
  double rotation_radps;
};
Earth earth_of(GnssSystem system) {
  namespace k = constants;
  switch (system) {
    case GnssSystem::kGalileo:
      return {k::kGmGalileo_m3ps2, k::kEarthRotationRateGalileo_radps};
    case GnssSystem::kBeiDou:
      return {k::kGmBeiDou_m3ps2, k::kEarthRotationRateBeiDou_radps};
    case GnssSystem::kGlonass:
      return {k::kGmGlonass_m3ps2, k::kEarthRotationRateGlonass_radps};
    default:
      return {k::kGmGps_m3ps2, k::kEarthRotationRateGps_radps};
  }
}

// Osculating elements from an Earth-fixed state: inertial velocity = v + omega x r.
struct Elements {
  double radius_m, semi_major_axis_m, inclination_deg, node_longitude_deg, argument_of_latitude_deg;
};
Elements elements(const SatelliteState& s, GnssSystem system) {
  const Earth e = earth_of(system);
  const Eigen::Vector3d r = s.position_m;
  const Eigen::Vector3d v = s.velocity_mps + Eigen::Vector3d(0, 0, e.rotation_radps).cross(r);
  const Eigen::Vector3d h = r.cross(v);
  const Eigen::Vector3d node = Eigen::Vector3d::UnitZ().cross(h);
  Elements out{};
  out.radius_m = r.norm();
  out.semi_major_axis_m = 1.0 / (2.0 / r.norm() - v.squaredNorm() / e.gm_m3ps2);
  out.inclination_deg = std::acos(h.z() / h.norm()) / kDeg;
  out.node_longitude_deg = std::atan2(node.y(), node.x()) / kDeg;
  const Eigen::Vector3d in_plane = h.normalized().cross(node.normalized());
  out.argument_of_latitude_deg = std::atan2(r.dot(in_plane), r.dot(node.normalized())) / kDeg;
  return out;
}

double wrap_deg(double a) {
  a = std::fmod(a + 180.0, 360.0);
  if (a < 0) a += 360.0;
  return a - 180.0;
}

double longitude_deg(const Eigen::Vector3d& r) { return std::atan2(r.y(), r.x()) / kDeg; }
double latitude_deg(const Eigen::Vector3d& r) { return std::asin(r.z() / r.norm()) / kDeg; }

TEST(NominalConstellation, SatellitesPerSystem) {
  std::map<GnssSystem, std::set<int>> satellites;
  for (const auto& e : day_data().kepler) satellites[e.satellite.system].insert(e.satellite.number);
  for (const auto& g : day_data().glonass)
    satellites[g.satellite.system].insert(g.satellite.number);
  EXPECT_EQ(satellites[GnssSystem::kGps].size(), 24u);
  EXPECT_EQ(satellites[GnssSystem::kGalileo].size(), 24u);
  EXPECT_EQ(satellites[GnssSystem::kBeiDou].size(), 30u);
  EXPECT_EQ(satellites[GnssSystem::kGlonass].size(), 24u);
  EXPECT_EQ(satellites[GnssSystem::kQzss].size(), 4u);
  EXPECT_EQ(satellites[GnssSystem::kNavic].size(), 7u);
  // Real PRN ranges of BDS-3: MEO within C19-C46, IGSO C38-C40, GEO C59-C61.
  const auto& c = satellites[GnssSystem::kBeiDou];
  EXPECT_EQ(*c.begin(), 19);
  EXPECT_EQ(*c.rbegin(), 61);
  for (int prn : {38, 39, 40, 59, 60, 61}) EXPECT_TRUE(c.count(prn)) << "C" << prn;
  EXPECT_EQ(satellites[GnssSystem::kQzss], (std::set<int>{1, 2, 3, 7}));
  EXPECT_FALSE(day_data().ionosphere.gps == std::nullopt);
  EXPECT_EQ(day_data().leap_seconds, 18);
}

TEST(NominalConstellation, RadiusInclinationAndPeriodOfEveryRecord) {
  // Design: semi-major axis (km), inclination (deg), published period (s, tolerance s).
  struct Design {
    double a_km, i_deg, period_s, period_tol_s;
  };
  auto design = [](const SatelliteId& sat) -> Design {
    constexpr double kSidereal_s = 86164.09;
    switch (sat.system) {
      case GnssSystem::kGps:
        return {26559.7, 55.0, 11 * 3600 + 58 * 60, 60};  // 11 h 58 min
      case GnssSystem::kGalileo:
        return {29600.0, 56.0, 14 * 3600 + 4 * 60, 60};  // 14 h 4 min
      case GnssSystem::kBeiDou:
        if (sat.number >= 59) return {42164.0, 0.0, kSidereal_s, 1};
        if (sat.number >= 38 && sat.number <= 40) return {42164.0, 55.0, kSidereal_s, 1};
        return {27906.0, 55.0, 12 * 3600 + 53 * 60, 60};  // 12 h 53 min
      case GnssSystem::kQzss:
        return {42164.0, sat.number == 7 ? 0.0 : 41.0, kSidereal_s, 1};
      case GnssSystem::kNavic:
        return {42164.0, (sat.number == 3 || sat.number >= 6) ? 0.0 : 29.0, kSidereal_s, 1};
      default:
        return {};
    }
  };
  size_t checked = 0;
  for (const auto& record : day_data().kepler) {
    const Design d = design(record.satellite);
    const bool qzo = record.satellite.system == GnssSystem::kQzss && record.satellite.number != 7;
    for (const double dt_s : {-3600.0, 0.0, 1800.0, 3600.0}) {
      const GnssTime t = record.toe + dt_s;
      const SatelliteState s = evaluate_kepler(record, t);
      const Elements el = elements(s, record.satellite.system);
      const std::string what =
          record.satellite.to_string() + " toe " + record.toe.to_iso8601(TimeScale::kGpst, 0);
      EXPECT_NEAR(el.inclination_deg, d.i_deg, 0.01) << what;
      if (qzo) {
        EXPECT_NEAR(record.sqrt_a_sqrtm * record.sqrt_a_sqrtm / 1e3, d.a_km, 1.0) << what;
        EXPECT_NEAR(record.eccentricity, 0.075, 1e-12) << what;
      } else {
        EXPECT_NEAR(el.radius_m / 1e3, d.a_km, 1.0) << what;  // circular orbits
        if (d.i_deg > 0.0) {
          // Period from the rate of the argument of latitude over one minute.
          const Elements later =
              elements(evaluate_kepler(record, t + 60.0), record.satellite.system);
          const double du_deg =
              wrap_deg(later.argument_of_latitude_deg - el.argument_of_latitude_deg);
          EXPECT_NEAR(360.0 * 60.0 / du_deg, d.period_s, d.period_tol_s) << what;
        }
      }
      ++checked;
    }
  }
  EXPECT_GT(checked, 1000u);
}

TEST(NominalConstellation, SynchronousOrbitsRepeatAfterOneSiderealDay) {
  const BroadcastEphemerides eph(day_data());
  for (const auto& sat : eph.satellites()) {
    const bool synchronous = sat.system == GnssSystem::kQzss || sat.system == GnssSystem::kNavic ||
                             (sat.system == GnssSystem::kBeiDou && sat.number >= 38 &&
                              sat.number != 41 && sat.number != 42 && sat.number != 43 &&
                              sat.number != 44 && sat.number != 45 && sat.number != 46);
    if (!synchronous) continue;
    for (double t_s : {0.0, 5000.0}) {
      const auto a = eph.state(sat, test_start() + t_s).value();
      const auto b = eph.state(sat, test_start() + t_s + 86164.09).value();
      EXPECT_LT((a.position_m - b.position_m).norm(), 50.0) << sat.to_string();
    }
  }
}

TEST(NominalConstellation, GeostationarySatellitesStayOverTheirLongitude) {
  const BroadcastEphemerides eph(day_data());
  const std::map<SatelliteId, double> longitudes = {
      {{GnssSystem::kBeiDou, 59}, 140.0}, {{GnssSystem::kBeiDou, 60}, 80.0},
      {{GnssSystem::kBeiDou, 61}, 110.5}, {{GnssSystem::kQzss, 7}, 127.0},
      {{GnssSystem::kNavic, 3}, 83.0},    {{GnssSystem::kNavic, 6}, 32.5},
      {{GnssSystem::kNavic, 7}, 131.5}};
  for (const auto& [sat, lon_deg] : longitudes) {
    double worst_deg = 0.0;
    for (double t_s = 0.0; t_s <= 86400.0; t_s += 600.0) {
      const auto s = eph.state(sat, test_start() + t_s);
      ASSERT_TRUE(s.ok()) << s.error().message;
      worst_deg = std::max({worst_deg, std::fabs(wrap_deg(longitude_deg(s->position_m) - lon_deg)),
                            std::fabs(latitude_deg(s->position_m))});
    }
    EXPECT_LT(worst_deg, 0.1) << sat.to_string();
    char buffer[32];
    std::snprintf(buffer, sizeof buffer, "%.2e", worst_deg);
    RecordProperty(sat.to_string() + "_worst_deg", buffer);
  }
}

TEST(NominalConstellation, IgsoCrossTheEquatorAtTheirLongitude) {
  const BroadcastEphemerides eph(day_data());
  const std::map<SatelliteId, double> crossings = {
      {{GnssSystem::kBeiDou, 38}, 118.0}, {{GnssSystem::kBeiDou, 39}, 118.0},
      {{GnssSystem::kBeiDou, 40}, 118.0}, {{GnssSystem::kNavic, 1}, 55.0},
      {{GnssSystem::kNavic, 2}, 55.0},    {{GnssSystem::kNavic, 4}, 111.75},
      {{GnssSystem::kNavic, 5}, 111.75}};
  for (const auto& [sat, lon_deg] : crossings) {
    int found = 0;
    Eigen::Vector3d previous = eph.state(sat, test_start()).value().position_m;
    for (double t_s = 60.0; t_s <= 86400.0; t_s += 60.0) {
      const Eigen::Vector3d r = eph.state(sat, test_start() + t_s).value().position_m;
      if ((previous.z() < 0.0) != (r.z() < 0.0)) {
        // Both nodes of a circular synchronous orbit lie at the figure-8 crossing.
        const Eigen::Vector3d at =
            previous + (r - previous) * (previous.z() / (previous.z() - r.z()));
        EXPECT_NEAR(wrap_deg(longitude_deg(at) - lon_deg), 0.0, 0.1) << sat.to_string();
        ++found;
      }
      previous = r;
    }
    EXPECT_EQ(found, 2) << sat.to_string();
  }
}

TEST(NominalConstellation, QuasiZenithFigureEightCentredOn135East) {
  const BroadcastEphemerides eph(day_data());
  for (int number : {1, 2, 3}) {
    const SatelliteId sat{GnssSystem::kQzss, static_cast<std::uint8_t>(number)};
    double best_lat = -90.0, best_lon = 0.0, min_r = 1e12, max_r = 0.0;
    for (double t_s = 0.0; t_s <= 86400.0; t_s += 60.0) {
      const Eigen::Vector3d r = eph.state(sat, test_start() + t_s).value().position_m;
      if (latitude_deg(r) > best_lat) {
        best_lat = latitude_deg(r);
        best_lon = longitude_deg(r);
      }
      min_r = std::min(min_r, r.norm());
      max_r = std::max(max_r, r.norm());
    }
    // Apogee (u = 90 deg) is the northernmost point: latitude = inclination, over 135 E.
    EXPECT_NEAR(best_lat, 41.0, 0.05) << sat.to_string();
    EXPECT_NEAR(best_lon, 135.0, 0.3) << sat.to_string();
    // Perigee and apogee radii of a = 42164 km, e = 0.075.
    EXPECT_NEAR(min_r / 1e3, 42164.0 * (1 - 0.075), 2.0) << sat.to_string();
    EXPECT_NEAR(max_r / 1e3, 42164.0 * (1 + 0.075), 2.0) << sat.to_string();
  }
}

TEST(NominalConstellation, GpsSlotsMatchTheSpsTableAtItsEpoch) {
  // GPS SPS PS baseline 24-slot table at 1993-07-01 00:00 UTC; Greenwich hour angle 279.06 deg.
  const GnssTime epoch =
      GnssTime::from_calendar(CalendarTime{1993, 7, 1, 0, 0, 0.0}, TimeScale::kUtc);
  const auto data = make_nominal_constellation(epoch, 0.0);
  ASSERT_TRUE(data.ok());
  const BroadcastEphemerides eph(*data);
  struct Slot {
    int prn;
    double raan_deg, arg_lat_deg;
  };
  // A1, A3, B3, C4, D3, E2, F4 (PRNs in slot order A1..F4 = G01..G24).
  for (const Slot& slot :
       {Slot{1, 272.847, 268.126}, Slot{3, 272.847, 11.676}, Slot{7, 332.847, 309.976},
        Slot{12, 32.847, 241.556}, Slot{15, 92.847, 35.156}, Slot{18, 152.847, 302.596},
        Slot{24, 212.847, 135.346}}) {
    const SatelliteId sat{GnssSystem::kGps, static_cast<std::uint8_t>(slot.prn)};
    const auto s = eph.state(sat, epoch);
    ASSERT_TRUE(s.ok()) << s.error().message;
    const Elements el = elements(*s, GnssSystem::kGps);
    EXPECT_NEAR(wrap_deg(el.node_longitude_deg + 279.06 - slot.raan_deg), 0.0, 0.01)
        << sat.to_string();
    EXPECT_NEAR(wrap_deg(el.argument_of_latitude_deg - slot.arg_lat_deg), 0.0, 0.01)
        << sat.to_string();
  }
}

TEST(NominalConstellation, GpsGroundTrackRepeatsEveryTwoRevolutions) {
  const BroadcastEphemerides eph(day_data());
  const auto& first = day_data().kepler.front();
  ASSERT_EQ(first.satellite, (SatelliteId{GnssSystem::kGps, 1}));
  const double a_m = first.sqrt_a_sqrtm * first.sqrt_a_sqrtm;
  const double repeat_s =
      2.0 * 2.0 * 3.14159265358979 * std::sqrt(a_m * a_m * a_m / constants::kGmGps_m3ps2);
  const GnssTime t = test_start() + 3000.0;
  const auto a = eph.state(first.satellite, t).value();
  const auto b = eph.state(first.satellite, t + repeat_s).value();
  EXPECT_LT((a.position_m - b.position_m).norm(), 1.0);
}

TEST(NominalConstellation, CoversTheSpanWithMargins) {
  const BroadcastEphemerides eph(day_data());
  const auto satellites = eph.satellites();
  EXPECT_EQ(satellites.size(), 24u + 24u + 30u + 24u + 4u + 7u);
  for (const auto& sat : satellites) {
    for (double t_s = -7200.0; t_s <= 86400.0 + 7200.0; t_s += 900.0) {
      const auto s = eph.state(sat, test_start() + t_s);
      EXPECT_TRUE(s.ok()) << sat.to_string() << " at " << t_s
                          << " s: " << (s.ok() ? "" : s.error().message);
    }
  }
}

TEST(NominalConstellation, ConsecutiveRecordsDescribeOneOrbit) {
  // Evaluate each pair of consecutive records of a satellite halfway between their toes.
  std::map<std::pair<SatelliteId, int>, const KeplerEphemeris*> last;
  double worst_m = 0.0, worst_clock_s = 0.0;
  for (const auto& e : day_data().kepler) {
    const auto key = std::make_pair(e.satellite, static_cast<int>(e.message));
    auto it = last.find(key);
    if (it != last.end()) {
      const KeplerEphemeris& p = *it->second;
      const GnssTime mid = p.toe + (e.toe - p.toe) / 2.0;
      const auto sp = evaluate_kepler(p, mid);
      const auto se = evaluate_kepler(e, mid);
      worst_m = std::max(worst_m, (sp.position_m - se.position_m).norm());
      worst_clock_s = std::max(worst_clock_s, std::fabs(sp.clock_bias_s - se.clock_bias_s));
    }
    last[key] = &e;
  }
  EXPECT_LT(worst_m, 0.01);
  EXPECT_LT(worst_clock_s, 1e-15);
  RecordProperty("kepler_switch_worst_m", std::to_string(worst_m));

  // GLONASS: each state is the previous record integrated as receivers do (PZ-90 with J2), so both
  // neighbours give the same position at the switch (design states at every t_b: ~15 m apart).
  std::map<SatelliteId, const GlonassEphemeris*> previous;
  double worst_glonass_m = 0.0;
  for (const auto& g : day_data().glonass) {
    auto it = previous.find(g.satellite);
    if (it != previous.end()) {
      const GnssTime mid = it->second->toe + (g.toe - it->second->toe) / 2.0;
      const auto a = evaluate_glonass(*it->second, mid);
      const auto b = evaluate_glonass(g, mid);
      worst_glonass_m = std::max(worst_glonass_m, (a.position_m - b.position_m).norm());
    }
    previous[g.satellite] = &g;
  }
  EXPECT_LT(worst_glonass_m, 0.01);
  RecordProperty("glonass_switch_worst_m", std::to_string(worst_glonass_m));
}

TEST(NominalConstellation, GlonassSlotsChannelsAndOrbit) {
  const std::map<int, int> expected_channel = {{1, 1},  {2, -4},  {3, 5},  {4, 6},
                                               {9, -2}, {10, -7}, {11, 0}, {12, -1},
                                               {17, 4}, {18, -3}, {19, 3}, {20, 2}};
  std::map<int, int> channel;
  double worst_radius_km = 0.0;
  for (const auto& g : day_data().glonass) {
    channel[g.satellite.number] = g.frequency_channel;
    const Elements el = elements(evaluate_glonass(g, g.toe), GnssSystem::kGlonass);
    worst_radius_km = std::max(worst_radius_km, std::fabs(el.radius_m / 1e3 - 25510.0));
    EXPECT_NEAR(el.radius_m / 1e3, 25510.0, 1.0) << g.satellite.to_string();
    EXPECT_NEAR(el.inclination_deg, 64.8, 0.01) << g.satellite.to_string();
    EXPECT_EQ(g.acceleration_mps2, Eigen::Vector3d::Zero());
    // t_b at hh:15 or hh:45 UTC.
    const CalendarTime c = g.toe.to_calendar(TimeScale::kUtc);
    EXPECT_TRUE(c.minute == 15 || c.minute == 45) << g.toe.to_iso8601(TimeScale::kUtc);
    EXPECT_EQ(c.second, 0.0);
  }
  RecordProperty("glonass_worst_radius_km", std::to_string(worst_radius_km));
  ASSERT_EQ(channel.size(), 24u);
  for (const auto& [slot, k] : expected_channel) {
    EXPECT_EQ(channel[slot], k) << "R" << slot;
    EXPECT_EQ(channel[slot + 4], k) << "antipodal R" << slot + 4;
  }
}

TEST(NominalConstellation, MessagesAndGroupDelays) {
  size_t inav = 0, fnav = 0, d1 = 0, d2 = 0;
  for (const auto& e : day_data().kepler) {
    EXPECT_EQ(e.health, 0);
    switch (e.message) {
      case NavMessage::kGalileoInav:
        ++inav;
        EXPECT_EQ(e.data_source, 517u);
        EXPECT_NE(e.group_delays.bgd_e1e5b_s, 0.0);
        break;
      case NavMessage::kGalileoFnav:
        ++fnav;
        EXPECT_EQ(e.data_source, 258u);
        EXPECT_EQ(e.group_delays.bgd_e1e5b_s, 0.0);
        break;
      case NavMessage::kBeiDouD1:
        ++d1;
        EXPECT_LT(e.satellite.number, 59);
        break;
      case NavMessage::kBeiDouD2:
        ++d2;
        EXPECT_GE(e.satellite.number, 59);
        break;
      default:
        break;
    }
    for (double gd : {e.group_delays.tgd_s, e.group_delays.bgd_e1e5a_s, e.group_delays.tgd1_s,
                      e.group_delays.tgd2_s}) {
      EXPECT_LE(std::fabs(gd), 1.01e-8);
    }
    EXPECT_LE(std::fabs(e.af0_s), 3.1e-4);
    EXPECT_LE(std::fabs(e.af1_s_per_s), 5e-12);
  }
  EXPECT_EQ(inav, fnav);
  EXPECT_GT(inav, 24u * 12u);
  EXPECT_GT(d1, 27u * 24u);
  EXPECT_GT(d2, 3u * 24u);
}

TEST(NominalConstellation, DeterministicFromTheSeed) {
  const auto a = make_nominal_constellation(test_start(), 3600.0).value();
  const auto b = make_nominal_constellation(test_start(), 3600.0).value();
  NominalConstellationOptions other;
  other.seed = 7;
  const auto c = make_nominal_constellation(test_start(), 3600.0, other).value();
  ASSERT_EQ(a.kepler.size(), b.kepler.size());
  ASSERT_EQ(a.kepler.size(), c.kepler.size());
  size_t clock_differs = 0;
  for (size_t i = 0; i < a.kepler.size(); ++i) {
    EXPECT_EQ(a.kepler[i].af0_s, b.kepler[i].af0_s);
    EXPECT_EQ(a.kepler[i].m0_rad, c.kepler[i].m0_rad);  // orbits do not depend on the seed
    clock_differs += a.kepler[i].af0_s != c.kepler[i].af0_s ? 1 : 0;
  }
  EXPECT_EQ(clock_differs, a.kepler.size());
}

TEST(NominalConstellation, RejectsBadArguments) {
  EXPECT_FALSE(make_nominal_constellation(test_start(), -1.0).ok());
  EXPECT_FALSE(make_nominal_constellation(test_start(), std::nan("")).ok());
  EXPECT_FALSE(make_nominal_constellation(test_start(), 400.0 * 86400.0).ok());
  NominalConstellationOptions sbas;
  sbas.systems = {GnssSystem::kSbas};
  const auto r = make_nominal_constellation(test_start(), 3600.0, sbas);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().code, ErrorCode::kUnsupported);
  NominalConstellationOptions gps_only;
  gps_only.systems = {GnssSystem::kGps};
  const auto g = make_nominal_constellation(test_start(), 3600.0, gps_only).value();
  EXPECT_TRUE(g.glonass.empty());
  EXPECT_EQ(g.kepler.size(), 24u * 4u);  // toes 22:00, 00:00, 02:00, 04:00 cover [-2 h, +3 h]
}

TEST(NominalConstellation, DesignStateAgreesWithRecords) {
  const auto orbits = nominal_orbits({GnssSystem::kGps, GnssSystem::kGalileo, GnssSystem::kBeiDou,
                                      GnssSystem::kQzss, GnssSystem::kNavic});
  const BroadcastEphemerides eph(day_data());
  double worst_m = 0.0;
  for (const auto& o : orbits) {
    for (double t_s : {0.0, 12345.0, 43210.0}) {
      const GnssTime t = test_start() + t_s;
      const auto s = eph.state(o.satellite, t).value();
      const NominalState d = nominal_state(o, t);
      worst_m = std::max(worst_m, (s.position_m - d.position_m).norm());
      EXPECT_LT((s.velocity_mps - d.velocity_mps).norm(), 1e-4) << o.satellite.to_string();
    }
  }
  EXPECT_LT(worst_m, 0.01);
}

}  // namespace
}  // namespace skytrace::orbits
