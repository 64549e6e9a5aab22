// The observation generator with models.multipath and a stub world whose paths are known: NLOS
// satellites carry their reflected path's excess in code and phase and its rate in Doppler, C/N0
// drops by the path's power, and satellites in view with a reflection stay within the envelope.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <map>
#include <numbers>

#include "skytrace/orbits/nominal.hpp"
#include "skytrace/receiver/observation_generator.hpp"

namespace skytrace::receiver {
namespace {

constexpr double kWallDistance_m = 20.0;
constexpr double kNlosAmplitude = 0.5;
constexpr double kSecondaryAmplitude = 0.3;
constexpr double kSecondaryDelay_m = 3.0;

// Northern satellites are hidden and arrive only off a wall 20 m south (normal +y); southern
// ones arrive directly plus a fixed 3 m reflection.
class MirrorWorld final : public PathQuery {
 public:
  std::vector<RayOutcome> trace(const Eigen::Vector3d&, const std::vector<Eigen::Vector3d>& directions) const override {
    std::vector<RayOutcome> out(directions.size());
    for (std::size_t i = 0; i < directions.size(); ++i) {
      if (directions[i].y() > 0.0) {
        out[i].blocked = true;
        out[i].blocking_object = "north wall";
      }
    }
    return out;
  }
  std::vector<PathSet> paths(const Eigen::Vector3d& origin, const std::vector<Eigen::Vector3d>& directions,
                             const PathSearchSettings&) const override {
    const auto outcomes = trace(origin, directions);
    std::vector<PathSet> out(directions.size());
    const Eigen::Vector3d n = Eigen::Vector3d::UnitY();
    for (std::size_t i = 0; i < directions.size(); ++i) {
      const Eigen::Vector3d& s = directions[i];
      out[i].direct = outcomes[i];
      if (!outcomes[i].blocked) {
        SignalPath direct;
        direct.arrival_direction = s;
        out[i].paths.push_back(direct);
        SignalPath secondary;
        secondary.type = PathType::kReflected;
        secondary.reflections = 1;
        secondary.excess_delay_m = kSecondaryDelay_m;
        secondary.rhcp_amplitude = kSecondaryAmplitude;
        secondary.arrival_direction = s;
        out[i].paths.push_back(secondary);
        continue;
      }
      SignalPath wall;
      wall.type = PathType::kReflected;
      wall.reflections = 1;
      wall.excess_delay_m = 2.0 * kWallDistance_m * n.dot(s);
      wall.rhcp_amplitude = kNlosAmplitude;
      wall.arrival_direction = Eigen::Vector3d(s.x(), -s.y(), s.z());
      wall.delay_gradient_origin = 2.0 * n.dot(s) * n;
      wall.delay_gradient_direction = 2.0 * kWallDistance_m * n;
      out[i].paths.push_back(wall);
    }
    return out;
  }
};

std::vector<EpochObservations> run(bool multipath, int epochs) {
  const GnssTime start = GnssTime::parse_iso8601("2020-06-25T00:00:00", TimeScale::kGpst).value();
  static const orbits::BroadcastEphemerides ephemerides(orbits::make_nominal_constellation(start, 600.0).value());
  const Geodetic site{55.49, 8.46, 60.0};
  GeneratorSettings settings;
  settings.signals = {Signal::parse("G1C").value(), Signal::parse("E1C").value()};
  settings.profile = builtin_profile("ideal").value();
  settings.multipath = multipath;
  ObservationGenerator generator(settings, ephemerides, std::make_shared<StaticPosition>(geodetic_to_ecef(site)));
  static const MirrorWorld world;
  if (multipath) generator.set_world(&world, LocalFrame{site, 0.0});
  std::vector<EpochObservations> out;
  for (int k = 0; k < epochs; ++k) out.push_back(generator.observe(start + static_cast<double>(k)).value());
  return out;
}

TEST(GeneratorMultipath, NlosFollowsTheReflectedPath) {
  const auto open = run(false, 2);
  const auto mp = run(true, 2);
  std::map<std::string, double> open_cn0;
  for (const auto& sat : open[0].satellites) {
    for (const auto& m : sat.signals) open_cn0[sat.satellite.to_string() + m.signal.to_string()] = m.cn0_dbhz;
  }
  int nlos = 0, multipath = 0;
  for (std::size_t i = 0; i < mp[0].satellites.size(); ++i) {
    const SatelliteObservation& sat = mp[0].satellites[i];
    if (sat.status != SatelliteStatus::kTracked) continue;
    const double az = sat.direction.azimuth_deg * std::numbers::pi / 180.0;
    const double el = sat.direction.elevation_deg * std::numbers::pi / 180.0;
    for (std::size_t k = 0; k < sat.signals.size(); ++k) {
      const SignalMeasurement& m = sat.signals[k];
      const double wavelength_m = 299792458.0 / m.carrier_hz;
      const double modelled_m = sat.range_m - (m.satellite_clock_m + sat.relativistic_m - m.group_delay_m) +
                                m.ionosphere_code_m + sat.troposphere_m;
      if (sat.path_kind == PathKind::kNlos) {
        ++nlos;
        // 2 d cos(el) cos(az) for a wall south of the antenna and a northern satellite.
        const double excess_m = 2.0 * kWallDistance_m * std::cos(el) * std::cos(az);
        EXPECT_NEAR(m.code_multipath_m, excess_m, 1e-3);
        EXPECT_NEAR(m.pseudorange_m - modelled_m, excess_m, 1e-3);
        EXPECT_NEAR(m.phase_multipath_m, excess_m, 1e-3);  // a real amplitude: no extra phase
        // The same elevation, the same RHCP gain: the power is the path's, -6 dB.
        EXPECT_NEAR(m.cn0_dbhz - open_cn0.at(sat.satellite.to_string() + m.signal.to_string()),
                    20.0 * std::log10(kNlosAmplitude), 0.26);
        // The rate the Doppler carries is how the excess changes from one epoch to the next.
        const SatelliteObservation& later = mp[1].satellites[i];
        ASSERT_EQ(later.path_kind, PathKind::kNlos);
        EXPECT_NEAR(m.range_rate_multipath_mps, later.signals[k].code_multipath_m - m.code_multipath_m, 2e-5);
        EXPECT_NE(m.range_rate_multipath_mps, 0.0);
        EXPECT_NEAR(m.doppler_hz - open[0].satellites[i].signals[k].doppler_hz, -m.range_rate_multipath_mps / wavelength_m,
                    1e-6);
      } else {
        ASSERT_EQ(sat.path_kind, PathKind::kMultipath);
        ++multipath;
        // One in-phase-or-not reflection of amplitude a at 3 m: at most a tau / (1 - a).
        EXPECT_GT(std::abs(m.code_multipath_m), 0.0);
        EXPECT_LE(std::abs(m.code_multipath_m), kSecondaryAmplitude * kSecondaryDelay_m / (1.0 - kSecondaryAmplitude) + 1e-9);
        EXPECT_LE(std::abs(m.phase_multipath_m), std::asin(kSecondaryAmplitude) / (2.0 * std::numbers::pi) * wavelength_m + 1e-9);
      }
    }
  }
  EXPECT_GT(nlos, 4);
  EXPECT_GT(multipath, 4);
}

}  // namespace
}  // namespace skytrace::receiver
