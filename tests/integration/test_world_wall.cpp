// The contract scenario wall.yaml: one opaque wall north of the antenna. Every satellite whose
// direction from the antenna crosses the wall must be absent from the observations, every other
// one above the mask present. The expected set comes from the wall's geometry (a slab test here),
// independently of the world loader and the Embree scene.
#include <gtest/gtest.h>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "process.hpp"
#include "skytrace/io/rinex_obs.hpp"
#include "test_support.hpp"
#include "zst_text.hpp"

namespace skytrace {
namespace {

// Does the ray from `origin` along (azimuth, elevation) cross the axis-aligned box [low, high]?
bool ray_hits_box(const Eigen::Vector3d& origin, double azimuth_deg, double elevation_deg, const Eigen::Vector3d& low,
                  const Eigen::Vector3d& high) {
  const double az = azimuth_deg * M_PI / 180.0, el = elevation_deg * M_PI / 180.0;
  const Eigen::Vector3d d(std::cos(el) * std::sin(az), std::cos(el) * std::cos(az), std::sin(el));
  double t_near = 0.0, t_far = 1e12;
  for (int k = 0; k < 3; ++k) {
    if (std::fabs(d[k]) < 1e-15) {
      if (origin[k] < low[k] || origin[k] > high[k]) return false;
      continue;
    }
    double t1 = (low[k] - origin[k]) / d[k], t2 = (high[k] - origin[k]) / d[k];
    if (t1 > t2) std::swap(t1, t2);
    t_near = std::max(t_near, t1);
    t_far = std::min(t_far, t2);
  }
  return t_near <= t_far;
}

struct Box {
  Eigen::Vector3d low, high;
};

// Runs wall.yaml with `sets` and checks every satellite above the mask against `boxes` (the
// world's blocking geometry): absent when its ray crosses one, present otherwise.
void expect_blocking_by(const std::string& name, const std::string& sets, const std::vector<Box>& boxes) {
  const auto scenario = test::shared_data_dir().parent_path() / "contract" / "wall.yaml";
  if (!std::filesystem::exists(scenario)) GTEST_SKIP() << "contract scenario absent: " << scenario;
  const auto out = test::make_temp_dir(name);
  const auto r = test::run_command(test::shell_quote(test::skytrace_executable().string()) + " run " +
                                   test::shell_quote(scenario.string()) + " --out " + test::shell_quote(out.string()) +
                                   " --quiet " + sets);
  ASSERT_EQ(r.exit_code, 0) << r.output;

  const Eigen::Vector3d antenna(0.0, 0.0, 1.5);
  const auto ray_hits = [&](double az, double el) {
    return std::any_of(boxes.begin(), boxes.end(),
                       [&](const Box& b) { return ray_hits_box(antenna, az, el, b.low, b.high); });
  };
  // Directions within this angle of the wall's edges are left out: the satellite's direction in
  // truth.csv is rounded to 1e-4 degrees.
  constexpr double kEdgeMargin_deg = 0.01;
  std::map<std::string, std::set<std::string>> expected_present;  // time -> satellites
  std::map<std::string, std::set<std::string>> either;            // time -> satellites near an edge
  size_t blocked = 0, present = 0, near_edge = 0;
  std::istringstream in(test::read_zst_text(out / "truth.csv.zst"));
  std::string line;
  std::getline(in, line);
  while (std::getline(in, line)) {
    std::vector<std::string> c;
    std::stringstream ss(line);
    for (std::string cell; std::getline(ss, cell, ',');) c.push_back(cell);
    if (c.size() < 7 || c[5].empty()) continue;
    const std::string& status = c[4];
    if (status == "below_mask" || status == "no_ephemeris") continue;
    const double az = std::stod(c[5]), el = std::stod(c[6]);
    const bool hits = ray_hits(az, el);
    bool ambiguous = false;
    for (double daz : {-kEdgeMargin_deg, kEdgeMargin_deg}) {
      for (double del : {-kEdgeMargin_deg, kEdgeMargin_deg}) {
        if (ray_hits(az + daz, el + del) != hits) ambiguous = true;
      }
    }
    if (ambiguous) {
      ++near_edge;
      either[c[0].substr(0, 19)].insert(c[2]);
      continue;
    }
    if (hits) {
      EXPECT_EQ(status, "blocked") << line;
      ++blocked;
    } else {
      EXPECT_EQ(status, "tracked") << line;
      expected_present[c[0].substr(0, 19)].insert(c[2]);
      ++present;
    }
  }
  std::printf("[ figures ] wall.yaml %s: %zu satellite-epochs blocked, %zu in view, %zu within %.2f deg of an edge\n",
              sets.c_str(), blocked, present, near_edge, kEdgeMargin_deg);
  EXPECT_GT(blocked, 100u);
  EXPECT_GT(present, 100u);

  // obs.rnx holds exactly the satellites in view.
  auto obs = io::read_rinex_obs(out / "obs.rnx");
  ASSERT_TRUE(obs.ok()) << obs.error().message;
  for (const auto& epoch : obs->epochs) {
    const std::string time = epoch.time.to_iso8601(TimeScale::kGpst, 0);
    std::set<std::string> recorded;
    for (const auto& sat : epoch.satellites) recorded.insert(sat.satellite.to_string());
    for (const auto& sat : expected_present[time]) EXPECT_TRUE(recorded.count(sat)) << time << " " << sat;
    for (const auto& sat : recorded) {
      // Every recorded satellite is in view (or within the edge margin, counted above).
      if (!expected_present[time].count(sat) && !either[time].count(sat)) ADD_FAILURE() << "recorded but behind the wall or unexpected: " << time << " " << sat;
    }
  }
}

// worlds/wall.sdf: a 40 x 1 x 30 m box centred at (0, 10, 15) on a 400 x 400 m ground plane;
// antenna at (0, 0, 1.5).
const Box kWall{{-20.0, 9.5, 0.0}, {20.0, 10.5, 30.0}};

TEST(WorldWall, SatellitesBehindTheWallAreAbsentAndAllOthersPresent) { expect_blocking_by("world_wall", "", {kWall}); }

// world.surroundings_height_m: the world beyond its extent (here the ground plane's 400 x 400 m)
// blocks what leaves it below 60 m, i.e. up to 11.7-16.3 deg from the antenna, as four walls
// along the extent's edges would (zero-thickness slabs in the check).
TEST(WorldWall, SurroundingsBlockWhatLeavesTheWorldBelowTheirHeight) {
  std::vector<Box> boxes{kWall};
  for (const double edge : {-200.0, 200.0}) {
    boxes.push_back(Box{{edge, -200.0, -1.0}, {edge, 200.0, 60.0}});
    boxes.push_back(Box{{-200.0, edge, -1.0}, {200.0, edge, 60.0}});
  }
  expect_blocking_by("world_surroundings", "--set world.surroundings_height_m=60", boxes);
}

}  // namespace
}  // namespace skytrace
