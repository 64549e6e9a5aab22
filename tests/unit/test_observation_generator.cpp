// The observation engine with a stub world: blocked satellites are absent, vegetation lowers C/N0
// and can drop signals, everything else is untouched.
#include <gtest/gtest.h>

#include <cmath>

#include "skytrace/orbits/nominal.hpp"
#include "skytrace/receiver/observation_generator.hpp"

namespace skytrace::receiver {
namespace {

// Blocks everything towards the north-east quadrant below 60 degrees; vegetation of a given
// attenuation to the south-west quadrant.
class QuadrantWorld final : public PathQuery {
 public:
  explicit QuadrantWorld(double attenuation_db) : attenuation_db_(attenuation_db) {}
  std::vector<RayOutcome> trace(const Eigen::Vector3d&, const std::vector<Eigen::Vector3d>& directions) const override {
    std::vector<RayOutcome> out(directions.size());
    for (size_t i = 0; i < directions.size(); ++i) {
      const Eigen::Vector3d& d = directions[i];
      const double elevation_deg = std::asin(d.z()) * 180.0 / M_PI;
      if (d.x() > 0 && d.y() > 0 && elevation_deg < 60.0) {
        out[i].blocked = true;
        out[i].blocking_object = "wall";
      } else if (d.x() < 0 && d.y() < 0) {
        out[i].vegetation_path_m = 10.0;
        out[i].vegetation_attenuation_db = attenuation_db_;
      }
    }
    return out;
  }

 private:
  double attenuation_db_;
};

struct Counts {
  int tracked = 0, blocked = 0, attenuated = 0;
};

Counts run_epoch(const PathQuery* world, std::vector<SatelliteObservation>* out = nullptr) {
  const GnssTime start = GnssTime::parse_iso8601("2020-06-25T00:00:00", TimeScale::kGpst).value();
  static const orbits::BroadcastEphemerides ephemerides(orbits::make_nominal_constellation(start, 600.0).value());
  const Geodetic site{55.49, 8.46, 60.0};
  GeneratorSettings settings;
  settings.signals = {Signal::parse("G1C").value(), Signal::parse("E1C").value()};
  settings.profile = builtin_profile("ideal").value();
  ObservationGenerator generator(settings, ephemerides, std::make_shared<StaticPosition>(geodetic_to_ecef(site)));
  if (world != nullptr) generator.set_world(world, LocalFrame{site, 0.0});
  const auto epoch = generator.observe(start).value();
  Counts c;
  for (const auto& sat : epoch.satellites) {
    if (sat.status == SatelliteStatus::kTracked) ++c.tracked;
    if (sat.status == SatelliteStatus::kBlocked) ++c.blocked;
    if (sat.status == SatelliteStatus::kAttenuated) ++c.attenuated;
  }
  if (out != nullptr) *out = epoch.satellites;
  return c;
}

TEST(ObservationGeneratorWorld, BlockedSatellitesAreAbsentAndVegetationLowersCn0) {
  std::vector<SatelliteObservation> open_sky, in_world;
  const Counts open = run_epoch(nullptr, &open_sky);
  const QuadrantWorld light_trees(6.0);
  const Counts with_world = run_epoch(&light_trees, &in_world);
  EXPECT_EQ(open.blocked, 0);
  EXPECT_GT(with_world.blocked, 0);
  EXPECT_EQ(with_world.tracked + with_world.blocked, open.tracked);
  ASSERT_EQ(open_sky.size(), in_world.size());
  int attenuated_seen = 0;
  for (size_t i = 0; i < open_sky.size(); ++i) {
    const auto& a = open_sky[i];
    const auto& b = in_world[i];
    if (a.status != SatelliteStatus::kTracked) continue;
    const double east = std::sin(a.direction.azimuth_deg * M_PI / 180.0);
    const double north = std::cos(a.direction.azimuth_deg * M_PI / 180.0);
    if (east > 0 && north > 0 && a.direction.elevation_deg < 60.0) {
      EXPECT_EQ(b.status, SatelliteStatus::kBlocked) << a.satellite.to_string();
      EXPECT_EQ(b.detail, "wall");
      EXPECT_TRUE(b.signals.empty());
    } else if (east < 0 && north < 0) {
      ASSERT_EQ(b.status, SatelliteStatus::kTracked);
      EXPECT_NEAR(b.signals[0].cn0_dbhz, a.signals[0].cn0_dbhz - 6.0, 0.26);  // C/N0 resolution 0.25
      EXPECT_DOUBLE_EQ(b.signals[0].pseudorange_m, a.signals[0].pseudorange_m);
      ++attenuated_seen;
    } else {
      EXPECT_EQ(b.status, SatelliteStatus::kTracked);
      EXPECT_DOUBLE_EQ(b.signals[0].cn0_dbhz, a.signals[0].cn0_dbhz);
    }
  }
  EXPECT_GT(attenuated_seen, 0);
  // Dense vegetation drops the signals below the tracking threshold.
  const QuadrantWorld forest(40.0);
  const Counts dense = run_epoch(&forest);
  EXPECT_GT(dense.attenuated, 0);
  EXPECT_EQ(dense.tracked + dense.blocked + dense.attenuated, open.tracked);
}

}  // namespace
}  // namespace skytrace::receiver
