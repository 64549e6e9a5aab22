// Scenario files: the contract scenarios parse unchanged; bad input names key path and line.
#include <gtest/gtest.h>

#include "skytrace/sim/scenario.hpp"
#include "test_support.hpp"

namespace skytrace::sim {
namespace {

const char* kMinimal = R"(name: t
time:
  start: 2020-06-25T00:00:00
  scale: GPST
  duration_s: 600
  interval_s: 30
receiver:
  position:
    ecef_m: [3582105.2910, 532589.7313, 5232754.8054]
  signals: [G1C, E1C]
ephemeris:
  nominal: true
)";

Result<Scenario> parse(const std::string& text) { return parse_scenario(text, "s.yaml", "/tmp"); }

std::string replace(std::string text, const std::string& from, const std::string& to) {
  const auto pos = text.find(from);
  EXPECT_NE(pos, std::string::npos) << from;
  return text.replace(pos, from.size(), to);
}

TEST(Scenario, MinimalWithDefaults) {
  const Scenario s = parse(kMinimal).value();
  EXPECT_EQ(s.name, "t");
  EXPECT_EQ(s.time.start.to_iso8601(TimeScale::kGpst, 0), "2020-06-25T00:00:00");
  EXPECT_DOUBLE_EQ(s.time.duration_s, 600.0);
  ASSERT_EQ(s.receivers.size(), 1u);
  EXPECT_EQ(s.receivers[0].signals.size(), 2u);
  EXPECT_EQ(s.receivers[0].profile, "ideal");
  EXPECT_EQ(s.models.ionosphere, "klobuchar");
  EXPECT_TRUE(s.ephemeris.nominal);
  EXPECT_NE(scenario_to_json(s).find("\"signals\""), std::string::npos);
}

TEST(Scenario, OverridesReplaceAndAddKeys) {
  const Scenario s =
      parse_scenario(kMinimal, "s.yaml", "/tmp",
                     {"models.ionosphere=none", "time.interval_s=10", "receiver.signals=[G1C]", "seed=9"})
          .value();
  EXPECT_EQ(s.models.ionosphere, "none");  // a mapping the file did not have
  EXPECT_DOUBLE_EQ(s.time.interval_s, 10.0);
  EXPECT_EQ(s.receivers[0].signals.size(), 1u);
  EXPECT_EQ(s.seed, 9u);
}

TEST(Scenario, BadOverridesAreNamed) {
  auto r = parse_scenario(kMinimal, "s.yaml", "/tmp", {"models.ionosphere"});
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("expected KEY.PATH=VALUE"), std::string::npos) << r.error().message;
  r = parse_scenario(kMinimal, "s.yaml", "/tmp", {"name.first=x"});
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("'name' is not a mapping"), std::string::npos) << r.error().message;
  r = parse_scenario(kMinimal, "s.yaml", "/tmp", {"models.ionospher=none"});
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("models.ionospher: unknown key"), std::string::npos) << r.error().message;
  r = parse_scenario(kMinimal, "s.yaml", "/tmp", {"time..x=1"});
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("empty key"), std::string::npos) << r.error().message;
}

TEST(Scenario, TimeScaleApplies) {
  const Scenario s = parse(replace(kMinimal, "scale: GPST", "scale: UTC")).value();
  EXPECT_EQ(s.time.start.to_iso8601(TimeScale::kGpst, 0), "2020-06-25T00:00:18");
}

TEST(Scenario, UnknownKeyNamesPathAndLine) {
  const auto r = parse(replace(kMinimal, "  signals:", "  signalz: [G1C]\n  signals:"));
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("s.yaml:10: receiver.signalz: unknown key"), std::string::npos) << r.error().message;
}

TEST(Scenario, BadValuesNamePathAndLine) {
  auto r = parse(replace(kMinimal, "[G1C, E1C]", "[G1C, E2C]"));
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("receiver.signals[1]"), std::string::npos) << r.error().message;
  EXPECT_NE(r.error().message.find("does not exist for Galileo"), std::string::npos) << r.error().message;

  r = parse(replace(kMinimal, "interval_s: 30", "interval_s: fast"));
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("s.yaml:6: time.interval_s: expected a number"), std::string::npos) << r.error().message;

  r = parse(replace(kMinimal, "[3582105.2910, 532589.7313, 5232754.8054]", "[1000, 0, 0]"));
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("below the Earth's surface"), std::string::npos) << r.error().message;

  r = parse(replace(kMinimal, "  nominal: true", "  navigation: [missing.rnx]"));
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("file not found: /tmp/missing.rnx"), std::string::npos) << r.error().message;

  r = parse(replace(kMinimal, "start: 2020-06-25T00:00:00", "start: 2020-06-31T00:00:00"));
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("time.start"), std::string::npos) << r.error().message;

  r = parse(std::string(kMinimal) + "models:\n  ionosphere: ionex\n");
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("models.ionex_file"), std::string::npos) << r.error().message;

  r = parse("time: [unclosed");
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("YAML syntax error"), std::string::npos) << r.error().message;
}

TEST(Scenario, ContractScenariosParseUnchanged) {
  const auto contract = test::shared_data_dir().parent_path() / "contract";
  if (!std::filesystem::exists(contract)) GTEST_SKIP() << "no contract folder at " << contract;
  int parsed = 0;
  for (const auto& entry : std::filesystem::directory_iterator(contract)) {
    if (entry.path().extension() != ".yaml") continue;
    const auto s = load_scenario(entry.path());
    ASSERT_TRUE(s.ok()) << s.error().message;
    EXPECT_FALSE(s->receivers.empty());
    ++parsed;
  }
  EXPECT_GE(parsed, 6);
}

}  // namespace
}  // namespace skytrace::sim
