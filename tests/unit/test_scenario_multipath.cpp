// Scenario keys of the multipath model: defaults, values, bad values named.
#include <gtest/gtest.h>

#include "skytrace/sim/scenario.hpp"

namespace skytrace::sim {
namespace {

std::string scenario_with(const std::string& models) {
  return R"(name: mp
time:
  start: 2020-06-25T00:00:00
  scale: GPST
  duration_s: 60
  interval_s: 30
receiver:
  position:
    ecef_m: [3582105.2910, 532589.7313, 5232754.8054]
  signals: [G1C]
ephemeris:
  nominal: true
models:
)" + models;
}

TEST(ScenarioMultipath, DefaultsAndValues) {
  const Scenario d = parse_scenario(scenario_with("  multipath: true\n"), "s.yaml", "/tmp").value();
  EXPECT_TRUE(d.models.multipath);
  EXPECT_EQ(d.models.multipath_radius_m, 150.0);
  EXPECT_EQ(d.models.multipath_order, 1);
  EXPECT_TRUE(d.models.diffraction);
  const Scenario s = parse_scenario(scenario_with("  multipath: true\n  multipath_radius_m: 80\n  multipath_order: 2\n"
                                                  "  diffraction: false\n"),
                                    "s.yaml", "/tmp")
                         .value();
  EXPECT_EQ(s.models.multipath_radius_m, 80.0);
  EXPECT_EQ(s.models.multipath_order, 2);
  EXPECT_FALSE(s.models.diffraction);
}

TEST(ScenarioMultipath, BadValuesAreNamed) {
  auto r = parse_scenario(scenario_with("  multipath_order: 3\n"), "s.yaml", "/tmp");
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("multipath_order"), std::string::npos) << r.error().message;
  r = parse_scenario(scenario_with("  multipath_order: 1.5\n"), "s.yaml", "/tmp");
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("0, 1 or 2"), std::string::npos) << r.error().message;
  r = parse_scenario(scenario_with("  multipath_radius_m: -5\n"), "s.yaml", "/tmp");
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("multipath_radius_m"), std::string::npos) << r.error().message;
}

}  // namespace
}  // namespace skytrace::sim
