// Scenario files: the contract scenarios parse unchanged; bad input names key path and line.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cstdlib>
#include <optional>

#include "skytrace/sim/scenario.hpp"
#include "skytrace/sim/setup.hpp"
#include "test_support.hpp"
#include "time_boundaries.hpp"

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

TEST(Scenario, OverridesReachIntoListsByIndex) {
  const Scenario s = parse_scenario(kMinimal, "s.yaml", "/tmp", {"receiver.signals.1=E5Q"}).value();
  EXPECT_EQ(s.receivers[0].signals[1].to_string(), "E5Q");
  auto r = parse_scenario(kMinimal, "s.yaml", "/tmp", {"receiver.signals.2=E5Q"});
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("'receiver.signals' is a list of 2: '2' is not an index from 0 to 1"),
            std::string::npos)
      << r.error().message;
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

// A value given on the command line is not on any line of the file: the message names the option.
TEST(Scenario, ABadOverriddenValueNamesTheOptionNotALineOfTheFile) {
  auto r = parse_scenario(kMinimal, "s.yaml", "/tmp", {"time.interval_s=0"});
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("s.yaml (--set time.interval_s=0): time.interval_s: value 0 out of range"), std::string::npos)
      << r.error().message;
  // Below an overridden value, and in a list reached by index (the parser's path in brackets).
  r = parse_scenario(kMinimal, "s.yaml", "/tmp", {"receiver.signals=[G1C, Q]"});
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("s.yaml (--set receiver.signals=[G1C, Q]): receiver.signals[1]: invalid signal 'Q'"),
            std::string::npos)
      << r.error().message;
  r = parse_scenario(kMinimal, "s.yaml", "/tmp", {"receiver.signals.1=Q"});
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("s.yaml (--set receiver.signals.1=Q): receiver.signals[1]:"), std::string::npos)
      << r.error().message;
  // The file's own values keep their lines, also beside an overridden key that their key begins with.
  r = parse_scenario(replace(kMinimal, "ephemeris:", "models:\n  multipath_order: 7\nephemeris:"), "s.yaml", "/tmp",
                     {"models.multipath=true", "receiver.signals.1=E5Q"});
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("s.yaml:12: models.multipath_order: value 7"), std::string::npos) << r.error().message;
  EXPECT_EQ(r.error().message.find("(--set"), std::string::npos) << r.error().message;
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

// summary.json's configuration.time.start (scenario_to_json): the start in the scenario's own
// scale with 3 decimals, rounded on the timeline first.
TEST(Scenario, JsonStartTimeRoundedToMillisecondsCarriesIntoMinuteHourDayMonthAndYear) {
  Scenario s = parse(kMinimal).value();
  for (const TimeScale scale : {TimeScale::kGpst, TimeScale::kUtc}) {
    s.time.scale = scale;
    for (const auto& b : test::time_boundaries()) {
      for (const double fraction : test::fractions_rounding_up(3)) {
        s.time.start = test::boundary_time(b, scale, fraction);
        const auto j = nlohmann::json::parse(scenario_to_json(s));
        EXPECT_EQ(j["time"]["start"].get<std::string>(), test::with_zero_decimals(b.next, 3))
            << b.name << ", " << to_string(scale) << ", fraction 1 - " << 1.0 - fraction;
      }
    }
  }
  // Inside the leap second of 2016 the UTC start keeps second 60.
  s.time.scale = TimeScale::kUtc;
  s.time.start = GnssTime::parse_iso8601("2016-12-31T23:59:59.9996", TimeScale::kUtc).value();
  EXPECT_EQ(nlohmann::json::parse(scenario_to_json(s))["time"]["start"].get<std::string>(), "2016-12-31T23:59:60.000");
}

// The RINEX "PGM / RUN BY / DATE" date of a run (obs.rnx, nav.rnx) without SOURCE_DATE_EPOCH: the
// scenario start in UTC, to the second below (it is a date stamp, not a rounded epoch).
TEST(Scenario, RinexCreationDateNeverShowsSecond60) {
  std::optional<std::string> saved;
  if (const char* v = std::getenv("SOURCE_DATE_EPOCH")) saved = v;
  unsetenv("SOURCE_DATE_EPOCH");
  Scenario s = parse(kMinimal).value();
  for (const auto& b : test::time_boundaries()) {
    const std::string last(b.last_second);
    const std::string expected = last.substr(0, 4) + last.substr(5, 2) + last.substr(8, 2) + " " + last.substr(11, 2) +
                                 last.substr(14, 2) + last.substr(17, 2) + " UTC";
    for (const double fraction : {0.5, 1.0 - 1e-10, std::nextafter(1.0, 0.0)}) {
      s.time.start = test::boundary_time(b, TimeScale::kUtc, fraction);
      EXPECT_EQ(rinex_creation_date(s), expected) << b.name << ", fraction 1 - " << 1.0 - fraction;
    }
  }
  s.time.start = GnssTime::parse_iso8601("2016-12-31T23:59:60.5", TimeScale::kUtc).value();
  EXPECT_EQ(rinex_creation_date(s), "20161231 235960 UTC");
  if (saved) setenv("SOURCE_DATE_EPOCH", saved->c_str(), 1);
}

}  // namespace
}  // namespace skytrace::sim
