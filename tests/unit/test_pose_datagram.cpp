// Antenna pose datagrams of `skytrace serve --pose-udp` (sim::parse_pose_datagram).
#include <gtest/gtest.h>

#include "skytrace/core/frames.hpp"
#include "skytrace/sim/live.hpp"

namespace skytrace::sim {
namespace {

TEST(PoseDatagram, ParsesEcefWorldAndLlh) {
  const auto ecef = parse_pose_datagram("ecef 3582105.291 532589.731 5232754.805 0.5 -0.25 0\r\n");
  ASSERT_TRUE(ecef.ok()) << ecef.error().message;
  EXPECT_EQ(ecef->frame, PoseDatagram::Frame::kEcef);
  EXPECT_DOUBLE_EQ(ecef->position.x(), 3582105.291);
  ASSERT_TRUE(ecef->velocity.has_value());
  EXPECT_DOUBLE_EQ(ecef->velocity->y(), -0.25);

  const auto world = parse_pose_datagram("world 5 -3 1.5");
  ASSERT_TRUE(world.ok());
  EXPECT_EQ(world->frame, PoseDatagram::Frame::kWorld);
  EXPECT_FALSE(world->velocity.has_value());

  const auto llh = parse_pose_datagram("llh 48.1507 11.5690 560.0\n");
  ASSERT_TRUE(llh.ok());
  EXPECT_NEAR((llh->position - geodetic_to_ecef(Geodetic{48.1507, 11.5690, 560.0})).norm(), 0.0, 1e-6);
}

TEST(PoseDatagram, RefusesWhatIsNotAPose) {
  for (const char* text : {"", "ecef 1 2", "ecef 1 2 3 4", "llh 1 2 3 4 5 6", "ecef 1 2 x", "ecef 1e999 2 3",
                           "pose 1 2 3", "ecef 1 2 3 0x"}) {
    const auto pose = parse_pose_datagram(text);
    ASSERT_FALSE(pose.ok()) << text;
    EXPECT_EQ(pose.error().code, ErrorCode::kParse) << text;
  }
}

}  // namespace
}  // namespace skytrace::sim
