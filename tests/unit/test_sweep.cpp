// Sweep files: axes, grid and zip order, random draws, point ids, records and the manifest.
#include <gtest/gtest.h>

#include <fstream>

#include "skytrace/sim/sweep.hpp"
#include "test_support.hpp"

namespace skytrace::sim {
namespace {

class SweepPlanTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = test::make_temp_dir("sweep_plan");
    std::ofstream(dir_ / "base.yaml") << "name: base\n";
  }
  Result<SweepPlan> parse(const std::string& text) { return parse_sweep("scenario: base.yaml\n" + text, dir_ / "s.yaml"); }
  std::filesystem::path dir_;
};

TEST_F(SweepPlanTest, GridOfListsAndRangesLastAxisFastest) {
  auto plan = parse("axes:\n  seed: {range: [1, 3]}\n  models.multipath: [false, true]\n  x.y: {range: [0, 0.3], step: 0.1}\n");
  ASSERT_TRUE(plan) << plan.error().message;
  EXPECT_EQ(plan->point_count, 3u * 2u * 4u);
  EXPECT_EQ(plan->axes[2].yaml_values, (std::vector<std::string>{"0", "0.1", "0.2", "0.3"}));
  EXPECT_EQ(plan->overrides(0), (std::vector<std::string>{"seed=1", "models.multipath=false", "x.y=0"}));
  EXPECT_EQ(plan->overrides(1), (std::vector<std::string>{"seed=1", "models.multipath=false", "x.y=0.1"}));
  EXPECT_EQ(plan->overrides(4), (std::vector<std::string>{"seed=1", "models.multipath=true", "x.y=0"}));
  EXPECT_EQ(plan->overrides(23), (std::vector<std::string>{"seed=3", "models.multipath=true", "x.y=0.3"}));
  EXPECT_EQ(plan->parameters(23), (nlohmann::json{{"seed", 3}, {"models.multipath", true}, {"x.y", 0.3}}));
  EXPECT_EQ(plan->point_id(7), "p000007");
  EXPECT_EQ(plan->point_index("p000007"), 7u);
  EXPECT_FALSE(plan->point_index("p7"));
  EXPECT_FALSE(plan->point_index("p000024"));
  EXPECT_EQ(plan->scenario, (dir_ / "base.yaml").lexically_normal());
}

TEST_F(SweepPlanTest, ValuesKeepTheirYamlAndJsonForms) {
  auto plan = parse("set:\n  time.duration_s: 60\naxes:\n  a: [[1, 2, 3], \"07\", text, 2.5, {k: v}]\n  b: {range: [10, 4], step: -3}\n");
  ASSERT_TRUE(plan) << plan.error().message;
  EXPECT_EQ(plan->fixed_overrides, (std::vector<std::string>{"time.duration_s=60"}));
  EXPECT_EQ(plan->axes[0].yaml_values, (std::vector<std::string>{"[1, 2, 3]", "\"07\"", "text", "2.5", "{k: v}"}));
  EXPECT_EQ(plan->axes[0].json_values[0], nlohmann::json::array({1, 2, 3}));
  EXPECT_EQ(plan->axes[0].json_values[1], "07");  // quoted: text, not the number 7
  EXPECT_EQ(plan->axes[0].json_values[3], 2.5);
  EXPECT_EQ(plan->axes[1].yaml_values, (std::vector<std::string>{"10", "7", "4"}));
}

TEST_F(SweepPlanTest, RandomDrawsAreReproducibleAndDependOnTheSeedAndKey) {
  const std::string axes = "axes:\n  u: {uniform: [5, 15], count: 1000}\n  n: {normal: [1.5, 0.1], count: 1000}\n"
                           "  i: {integers: [1, 6], count: 1000}\n  c: {choice: [a, b], count: 1000}\n";
  auto plan = parse("combine: zip\nrandom_seed: 1\n" + axes);
  auto again = parse("combine: zip\nrandom_seed: 1\n" + axes);
  auto other = parse("combine: zip\nrandom_seed: 2\n" + axes);
  ASSERT_TRUE(plan && again && other);
  EXPECT_EQ(plan->point_count, 1000u);
  EXPECT_EQ(plan->axes[0].yaml_values, again->axes[0].yaml_values);
  EXPECT_NE(plan->axes[0].yaml_values, other->axes[0].yaml_values);
  double sum_u = 0.0, sum_n = 0.0, sum_n2 = 0.0;
  std::array<int, 7> faces{};
  int a = 0;
  for (size_t k = 0; k < 1000; ++k) {
    const double u = plan->axes[0].json_values[k].get<double>();
    ASSERT_GE(u, 5.0);
    ASSERT_LT(u, 15.0);
    sum_u += u;
    const double n = plan->axes[1].json_values[k].get<double>();
    sum_n += n;
    sum_n2 += n * n;
    const int i = plan->axes[2].json_values[k].get<int>();
    ASSERT_GE(i, 1);
    ASSERT_LE(i, 6);
    ++faces[static_cast<size_t>(i)];
    a += plan->axes[3].json_values[k] == "a" ? 1 : 0;
  }
  EXPECT_NEAR(sum_u / 1000.0, 10.0, 0.3);
  const double mean_n = sum_n / 1000.0;
  EXPECT_NEAR(mean_n, 1.5, 0.01);
  EXPECT_NEAR(std::sqrt(sum_n2 / 1000.0 - mean_n * mean_n), 0.1, 0.01);
  for (int face = 1; face <= 6; ++face) EXPECT_NEAR(faces[static_cast<size_t>(face)], 167, 50) << face;
  EXPECT_NEAR(a, 500, 60);
  // Two axes of one sweep draw differently.
  auto two = parse("combine: zip\naxes:\n  p: {uniform: [0, 1], count: 5}\n  q: {uniform: [0, 1], count: 5}\n");
  ASSERT_TRUE(two);
  EXPECT_NE(two->axes[0].yaml_values, two->axes[1].yaml_values);
}

TEST_F(SweepPlanTest, BadFilesNameLineAndKey) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"axes:\n  seed: {range: [3, 1]}\n", "s.yaml:3: axes.seed.range: an empty range"},
      {"axes:\n  seed: {range: [1, 3], step: 0}\n", "axes.seed.step: a step of 0"},
      {"axes:\n  seed: {uniform: [3, 1], count: 2}\n", "axes.seed.uniform: expected [LOW, HIGH] with LOW < HIGH"},
      {"axes:\n  seed: {uniform: [1, 3]}\n", "needs count"},
      {"axes:\n  seed: {range: [1, 3], uniform: [1, 2]}\n", "exactly one of"},
      {"axes:\n  seed: {steps: 3}\n", "steps: unknown key"},
      {"combine: zip\naxes:\n  a: [1, 2]\n  b: [1, 2, 3]\n", "s.yaml:5: axes.b: 3 values, but the axes before it have 2"},
      {"combine: star\n", "combine"},
      {"axes: [seed]\n", "axes: expected a mapping"},
      {"axes:\n  seed: [1]\n  seed: [2]\n", "axes.seed: duplicate key"},
  };
  for (const auto& [text, message] : cases) {
    auto plan = parse(text);
    ASSERT_FALSE(plan) << text;
    EXPECT_NE(plan.error().message.find(message), std::string::npos) << "expected '" << message << "' in " << plan.error().message;
  }
  auto no_scenario = parse_sweep("scenario: nowhere.yaml\n", dir_ / "s.yaml");
  ASSERT_FALSE(no_scenario);
  EXPECT_NE(no_scenario.error().message.find("no scenario file"), std::string::npos);
}

TEST_F(SweepPlanTest, ManifestCountsRecordsOfThisSweepOnly) {
  auto plan = parse("axes:\n  seed: [1, 2, 3]\n");
  ASSERT_TRUE(plan);
  const SweepLayout layout{dir_ / "out"};
  PointRecord done{"p000000", "done", 0, "", 1.5, "h", plan->overrides(0), plan->scenario.string()};
  PointRecord failed{"p000001", "failed", 3, "bad world", 0.1, "h", plan->overrides(1), plan->scenario.string()};
  PointRecord other_sweep{"p000002", "done", 0, "", 1.0, "h", {"seed=99"}, plan->scenario.string()};
  for (const auto& r : {done, failed, other_sweep}) ASSERT_TRUE(write_point_record(layout, r));
  EXPECT_TRUE(point_done(*plan, read_point_record(layout, "p000000"), 0));
  EXPECT_FALSE(point_done(*plan, read_point_record(layout, "p000002"), 2));
  auto counts = write_sweep_manifest(*plan, layout);
  ASSERT_TRUE(counts) << counts.error().message;
  EXPECT_EQ(counts->done, 1u);
  EXPECT_EQ(counts->failed, 1u);
  EXPECT_EQ(counts->pending, 1u);
  std::ifstream in(layout.out / "manifest.json");
  const auto manifest = nlohmann::json::parse(in);
  EXPECT_EQ(manifest.at("points").size(), 3u);
  EXPECT_EQ(manifest.at("points")[1].at("error"), "bad world");
  EXPECT_EQ(manifest.at("points")[2].at("status"), "pending");
  // A reason from the scheduler for a point without a record.
  std::filesystem::remove_all(layout.point_dir("p000002"));
  counts = write_sweep_manifest(*plan, layout, {{2, "killed by Slurm at its time limit"}});
  ASSERT_TRUE(counts);
  EXPECT_EQ(counts->failed, 2u);
  EXPECT_EQ(counts->failed_ids, (std::vector<std::string>{"p000001", "p000002"}));
}

}  // namespace
}  // namespace skytrace::sim
