// Interpolated trajectories (sim/trajectory): the ends, where a receiver clock offset puts the true
// instant of the first or last epoch a little outside a trajectory that spans the run exactly.
#include <gtest/gtest.h>

#include "skytrace/sim/trajectory.hpp"

namespace skytrace::sim {
namespace {

TEST(Trajectory, EndsCarryOnForTenMillisecondsThenSayWhichTimeIsOutside) {
  const GnssTime t0 = GnssTime::from_calendar({2020, 6, 25, 10, 0, 0.0}, TimeScale::kGpst);
  std::vector<TrajectorySample> samples;
  for (int k = 0; k <= 10; ++k) {
    samples.push_back(TrajectorySample{t0 + static_cast<double>(k), Eigen::Vector3d(5.0 * k, 0.0, 0.0)});
  }
  const auto trajectory = InterpolatedTrajectory::create(samples, "drive.csv").value();
  // 5 m/s east: 5 ms past the end is 2.5 cm further.
  const auto after = trajectory->at(t0 + 10.005);
  ASSERT_TRUE(after) << after.error().message;
  EXPECT_NEAR(after.value().position_m.x(), 50.025, 1e-9);
  EXPECT_NEAR(after.value().velocity_mps.x(), 5.0, 1e-9);
  const auto before = trajectory->at(t0 - 0.005);
  ASSERT_TRUE(before);
  EXPECT_NEAR(before.value().position_m.x(), -0.025, 1e-9);
  const auto beyond = trajectory->at(t0 + 10.02);
  ASSERT_FALSE(beyond);
  EXPECT_EQ(beyond.error().code, ErrorCode::kOutOfRange);
  EXPECT_NE(beyond.error().message.find("drive.csv: time 2020-06-25T10:00:10.020 GPST is outside the trajectory "
                                        "(2020-06-25T10:00:00.000 to 2020-06-25T10:00:10.000)"),
            std::string::npos)
      << beyond.error().message;
}

}  // namespace
}  // namespace skytrace::sim
