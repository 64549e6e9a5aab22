// A moving obstacle through `skytrace run`: a wall (20 m wide, 30 m high) drives past the receiver
// along a CSV trajectory (world.moving) and turns on the way. A satellite must be blocked exactly
// while the wall is between it and the antenna: the expected status of every satellite-epoch comes
// from the wall's pose at that epoch (interpolated here from the same CSV) and a ray-box test, not
// from the scene.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <fstream>
#include <map>
#include <numbers>
#include <set>
#include <sstream>

#include "process.hpp"
#include "test_support.hpp"
#include "zst_text.hpp"

namespace skytrace {
namespace {

constexpr double kHeadingDeg = 30.0;
const Eigen::Vector3d kHalfSize(10.0, 0.5, 15.0);  // the wall's box; its centre 15 m above the model frame

std::filesystem::path write_file(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
  return path;
}

// The trajectory: (t, x, y, yaw) in the world frame; linear in between, as documented.
struct Pose {
  double t_s, x_m, y_m, yaw_deg;
};
const Pose kTrajectory[] = {{0, -120, 12, 0}, {300, 0, 12, 0}, {600, 120, 12, 90}};

Eigen::Isometry3d wall_at(double t_s) {
  const Pose* a = &kTrajectory[0];
  const Pose* b = &kTrajectory[1];
  if (t_s > kTrajectory[1].t_s) {
    a = &kTrajectory[1];
    b = &kTrajectory[2];
  }
  const double f = std::clamp((t_s - a->t_s) / (b->t_s - a->t_s), 0.0, 1.0);
  const double yaw = (a->yaw_deg + f * (b->yaw_deg - a->yaw_deg)) * std::numbers::pi / 180.0;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = Eigen::Vector3d(a->x_m + f * (b->x_m - a->x_m), a->y_m + f * (b->y_m - a->y_m), 15.0);
  pose.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return pose;
}

// Does the ray from `origin` (world frame) along azimuth/elevation (ENU) cross the wall?
bool ray_hits_wall(const Eigen::Isometry3d& wall, const Eigen::Vector3d& origin, double azimuth_deg, double elevation_deg) {
  const double az = azimuth_deg * std::numbers::pi / 180.0, el = elevation_deg * std::numbers::pi / 180.0;
  const Eigen::Vector3d enu(std::cos(el) * std::sin(az), std::cos(el) * std::cos(az), std::sin(el));
  // World x axis is kHeadingDeg counter-clockwise from east.
  const Eigen::Vector3d world_dir = Eigen::AngleAxisd(-kHeadingDeg * std::numbers::pi / 180.0, Eigen::Vector3d::UnitZ()) * enu;
  const Eigen::Vector3d o = wall.inverse() * origin;
  const Eigen::Vector3d d = wall.linear().transpose() * world_dir;
  double t_near = 0.0, t_far = 1e12;
  for (int k = 0; k < 3; ++k) {
    if (std::fabs(d[k]) < 1e-15) {
      if (std::fabs(o[k]) > kHalfSize[k]) return false;
      continue;
    }
    double t1 = (-kHalfSize[k] - o[k]) / d[k], t2 = (kHalfSize[k] - o[k]) / d[k];
    if (t1 > t2) std::swap(t1, t2);
    t_near = std::max(t_near, t1);
    t_far = std::min(t_far, t2);
  }
  return t_near <= t_far;
}

double seconds_of_day(const std::string& iso) {
  return 3600.0 * std::stod(iso.substr(11, 2)) + 60.0 * std::stod(iso.substr(14, 2)) + std::stod(iso.substr(17));
}

TEST(WorldMoving, AWallDrivingPastBlocksEachSatelliteOnlyWhileInFront) {
  const auto dir = test::make_temp_dir("world_moving");
  write_file(dir / "street.sdf", R"(<?xml version="1.0"?>
<sdf version="1.9">
  <world name="street">
    <model name="truck">
      <pose>500 500 0 0 0 0</pose>
      <link name="body">
        <collision name="box">
          <pose>0 0 15 0 0 0</pose>
          <geometry><box><size>20 1 30</size></box></geometry>
        </collision>
      </link>
    </model>
  </world>
</sdf>
)");
  std::string csv = "# t_s, x_m, y_m, z_m, yaw_deg\n";
  for (const Pose& p : kTrajectory) {
    csv += std::to_string(p.t_s) + "," + std::to_string(p.x_m) + "," + std::to_string(p.y_m) + ",0," +
           std::to_string(p.yaw_deg) + "\n";
  }
  write_file(dir / "truck.csv", csv);
  write_file(dir / "s.yaml", R"(name: moving
time:
  start: 2020-06-25T06:00:00
  duration_s: 600
  interval_s: 2
receiver:
  position:
    world_enu_m: [0, 0, 1.5]
  elevation_mask_deg: 5
  signals: [G1C, E1C]
ephemeris:
  nominal: true
world:
  sdf: street.sdf
  latitude_deg: 47.0
  longitude_deg: 8.0
  elevation_m: 400
  heading_deg: 30
  moving:
    - model: truck
      trajectory: truck.csv
)");
  const auto out = dir / "out";
  const auto r = test::run_command(test::shell_quote(test::skytrace_executable().string()) + " run " +
                                   test::shell_quote((dir / "s.yaml").string()) + " --out " +
                                   test::shell_quote(out.string()) + " --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.output;

  const Eigen::Vector3d antenna(0, 0, 1.5);
  constexpr double kEdgeMargin_deg = 0.01;  // truth.csv rounds directions to 1e-4 degrees
  std::map<std::string, std::set<std::string>> statuses;  // satellite -> statuses seen
  size_t blocked = 0, tracked = 0, near_edge = 0;
  ASSERT_TRUE(std::filesystem::exists(out / "truth.csv.zst")) << "truth.csv.zst missing";
  std::istringstream in(test::read_zst_text(out / "truth.csv.zst"));
  std::string line;
  std::getline(in, line);
  std::set<std::string> seen;  // satellite-epochs (one row per signal)
  while (std::getline(in, line)) {
    std::vector<std::string> c;
    std::stringstream ss(line);
    for (std::string cell; std::getline(ss, cell, ',');) c.push_back(cell);
    if (c.size() < 7 || c[5].empty()) continue;
    const std::string& status = c[4];
    if (status == "below_mask" || status == "no_ephemeris") continue;
    if (!seen.insert(c[0] + c[2]).second) continue;
    const double t_s = seconds_of_day(c[0]) - 6 * 3600.0;
    const double az = std::stod(c[5]), el = std::stod(c[6]);
    const Eigen::Isometry3d wall = wall_at(t_s);
    const bool hits = ray_hits_wall(wall, antenna, az, el);
    bool ambiguous = false;
    for (double daz : {-kEdgeMargin_deg, kEdgeMargin_deg}) {
      for (double del : {-kEdgeMargin_deg, kEdgeMargin_deg}) {
        // The wall also moves up to 0.4 m per epoch: check the direction against its pose a few
        // milliseconds either side as well.
        for (double dt : {-0.005, 0.005}) {
          if (ray_hits_wall(wall_at(t_s + dt), antenna, az + daz, el + del) != hits) ambiguous = true;
        }
      }
    }
    if (ambiguous) {
      ++near_edge;
      continue;
    }
    if (hits) {
      EXPECT_EQ(status, "blocked") << line;
      if (status == "blocked") {
        EXPECT_NE(line.find("truck/body/box"), std::string::npos) << line;
      }
      ++blocked;
    } else {
      // Tracked, or too weak for the profile at low elevation, but never blocked.
      EXPECT_NE(status, "blocked") << line;
      tracked += status == "tracked" ? 1 : 0;
    }
    statuses[c[2]].insert(status);
  }
  std::printf("[ figures ] moving wall: %zu satellite-epochs blocked, %zu tracked, %zu near an edge\n", blocked, tracked,
              near_edge);
  EXPECT_GT(blocked, 20u);
  EXPECT_GT(tracked, 1000u);
  // Blocked only while the wall is there: the satellites it blocks are tracked at other epochs.
  size_t passed_over = 0;
  for (const auto& [sat, seen_statuses] : statuses) {
    if (seen_statuses.count("blocked") != 0) {
      EXPECT_GE(seen_statuses.size(), 2u) << sat << " is blocked for the whole run";
      ++passed_over;
    }
  }
  EXPECT_GE(passed_over, 2u);
}

}  // namespace
}  // namespace skytrace
