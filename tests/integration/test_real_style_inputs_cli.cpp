// Real users' files through the command line (issue #13): an observation file with the channel
// numbers (X1) and ionosphere pseudo-observables (I1) that RINEX 3.02+ defines, QZSS LNAV records
// with SV health 1 (the L1C/B bit of IS-QZSS-PNT: L1 C/A, L2C, L5 usable), a QZSS signal whose
// health bit marks it unusable, and a system without any ephemeris. The files are derived at test
// time from the real ESBC data (never copied into the repository).
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <vector>

#include "process.hpp"
#include "skytrace/io/rinex_obs.hpp"
#include "test_support.hpp"
#include "zst_text.hpp"

namespace skytrace {
namespace {

std::filesystem::path esbc_dir() { return test::shared_data_dir() / "real/esbc_2020177"; }
std::filesystem::path esbc_obs() { return esbc_dir() / "ESBC00DNK_R_20201770000_01D_30S_MO_first1h.rnx"; }
std::filesystem::path esbc_nav() { return esbc_dir() / "ESBC00DNK_R_20201770000_01D_MN.rnx"; }
std::string skytrace_cmd() { return test::shell_quote(test::skytrace_executable().string()); }
std::string q(const std::filesystem::path& p) { return test::shell_quote(p.string()); }

std::vector<std::string> read_lines(const std::filesystem::path& path) {
  std::ifstream file(path);
  std::istringstream unpacked(path.extension() == ".zst" ? test::read_zst_text(path) : std::string());
  std::istream& in = path.extension() == ".zst" ? static_cast<std::istream&>(unpacked) : file;
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

void write_lines(const std::filesystem::path& path, const std::vector<std::string>& lines) {
  std::ofstream out(path);
  for (const auto& line : lines) out << line << "\n";
}

std::string pad(std::string text, size_t width) {
  if (text.size() < width) text.resize(width, ' ');
  return text;
}

// The first `epochs` epochs of the ESBC hour as a RINEX 3.04 file, as sbf2rin writes them: every
// system lists the channel number X1 last (GPS also I1), and every satellite line carries a value.
std::filesystem::path write_observations_with_channel_numbers(const std::filesystem::path& dir, int epochs) {
  const auto lines = read_lines(esbc_obs());
  std::vector<std::string> out;
  std::map<char, size_t> type_count;
  size_t i = 0;
  for (; i < lines.size(); ++i) {
    std::string line = lines[i];
    const std::string label = line.size() > 60 ? line.substr(60) : "";
    if (label.starts_with("RINEX VERSION / TYPE")) line.replace(0, 9, "     3.04");
    if (label.starts_with("SYS / # / OBS TYPES") && line[0] != ' ') {
      const char system = line[0];
      std::vector<std::string> codes;
      for (size_t j = i;; ++j) {
        for (size_t k = 0; k < 13; ++k) {
          std::string code = lines[j].substr(7 + 4 * k, 3);
          while (!code.empty() && code.back() == ' ') code.pop_back();
          if (!code.empty()) codes.push_back(code);
        }
        if (j + 1 >= lines.size() || !lines[j + 1].starts_with("      ") ||
            lines[j + 1].find("SYS / # / OBS TYPES") == std::string::npos) {
          i = j;
          break;
        }
      }
      codes.push_back("X1");
      if (system == 'G') codes.push_back("I1");
      type_count[system] = codes.size();
      for (size_t k = 0; k < codes.size(); k += 13) {
        char head[8];
        std::snprintf(head, sizeof head, "%c  %3zu", system, codes.size());
        std::string text = k == 0 ? head : "      ";
        for (size_t c = k; c < std::min(codes.size(), k + 13); ++c) text += " " + pad(codes[c], 3);
        out.push_back(pad(text, 60) + "SYS / # / OBS TYPES");
      }
      continue;
    }
    out.push_back(line);
    if (label.starts_with("END OF HEADER")) break;
  }
  int epoch_count = 0;
  for (++i; i < lines.size(); ++i) {
    const std::string& line = lines[i];
    if (line.starts_with(">")) {
      if (++epoch_count > epochs) break;
      out.push_back(line);
      continue;
    }
    if (line.empty()) continue;
    const size_t types = type_count.at(line[0]);
    const size_t extra = line[0] == 'G' ? 2 : 1;
    std::string record = line;
    record.resize(3 + 16 * (types - extra), ' ');  // the original values (trailing blanks cut or added)
    record += "         7.000  ";  // channel 7 (F14.3, LLI, SSI)
    if (line[0] == 'G') record += "         1.250  ";
    while (!record.empty() && record.back() == ' ') record.pop_back();
    out.push_back(record);
  }
  const auto path = dir / "ESBC_sbf2rin_style.rnx";
  write_lines(path, out);
  return path;
}

// The ESBC navigation file with every record of `system` passed through `edit` (its lines, the
// epoch line first); an edit leaving no line drops the record.
std::filesystem::path write_navigation(const std::filesystem::path& dir, const std::string& name, char system,
                                       const std::function<void(std::vector<std::string>&)>& edit) {
  const auto lines = read_lines(esbc_nav());
  std::vector<std::string> out;
  size_t i = 0;
  for (; i < lines.size(); ++i) {
    out.push_back(lines[i]);
    if (lines[i].find("END OF HEADER") != std::string::npos) break;
  }
  for (++i; i < lines.size();) {
    std::vector<std::string> record{lines[i++]};
    while (i < lines.size() && lines[i].starts_with("    ")) record.push_back(lines[i++]);
    if (record.front()[0] == system) edit(record);
    out.insert(out.end(), record.begin(), record.end());
  }
  const auto path = dir / name;
  write_lines(path, out);
  return path;
}

// QZSS LNAV: the SV health field (broadcast orbit 6, second value) set to `health`.
std::function<void(std::vector<std::string>&)> set_health(int health) {
  return [health](std::vector<std::string>& record) {
    char value[32];
    std::snprintf(value, sizeof value, "%19.12E", static_cast<double>(health));
    record.at(6).replace(4 + 19, 19, value);
  };
}

std::filesystem::path write_scenario(const std::filesystem::path& dir, const std::string& position,
                                     const std::string& start, const std::string& signals,
                                     const std::filesystem::path& nav) {
  const std::string text = "name: issue13\ntime:\n  start: " + start +
                           "\n  scale: GPST\n  duration_s: 300\n  interval_s: 30\nreceiver:\n  position:\n    " +
                           position + "\n  signals: " + signals + "\nephemeris:\n  navigation:\n    - " + nav.string() +
                           "\n";
  const auto path = dir / "scenario.yaml";
  std::ofstream(path) << text;
  return path;
}

constexpr const char* kTokyo = "lla_deg_m: [35.68, 139.77, 40]";
constexpr const char* kEsbjerg = "ecef_m: [3582105.2910, 532589.7313, 5232754.8054]";
constexpr const char* kQzssHour = "2020-06-25T12:00:00";  // J01 records 11:00 to 14:00 in the ESBC file

nlohmann::json read_json(const std::filesystem::path& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

class RealStyleInputs : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!std::filesystem::exists(esbc_obs()) || !std::filesystem::exists(esbc_nav())) {
      GTEST_SKIP() << "ESBC data absent (set SKYTRACE_SHARED_DATA): " << esbc_dir();
    }
    dir_ = test::make_temp_dir(std::string("real_style_") +
                               ::testing::UnitTest::GetInstance()->current_test_info()->name());
  }
  test::ProcessResult run(const std::filesystem::path& scenario, const std::string& out = "out") {
    return test::run_command(skytrace_cmd() + " run " + q(scenario) + " --out " + q(dir_ / out) + " --quiet");
  }
  std::filesystem::path dir_;
};

TEST_F(RealStyleInputs, ChannelNumbersAreReadAndIgnoredByCompareAndPosition) {
  const auto real = write_observations_with_channel_numbers(dir_, 20);
  auto file = io::read_rinex_obs(real);
  ASSERT_TRUE(file.ok()) << file.error().message;
  ASSERT_EQ(file->warnings.size(), 1u);  // one note for the file, not one per line
  EXPECT_NE(file->warnings[0].find("X1"), std::string::npos) << file->warnings[0];
  EXPECT_NE(file->warnings[0].find("I1"), std::string::npos) << file->warnings[0];
  const auto x1 = file->header.type_index(GnssSystem::kGps, "X1");
  ASSERT_TRUE(x1.has_value());
  ASSERT_FALSE(file->epochs.empty());
  const io::SatelliteObservations* gps = nullptr;
  for (const auto& sat : file->epochs[0].satellites) {
    if (gps == nullptr && sat.satellite.system == GnssSystem::kGps) gps = &sat;
  }
  ASSERT_NE(gps, nullptr);
  ASSERT_GT(gps->values.size(), *x1);
  EXPECT_EQ(gps->values[*x1].value, 7.0);

  // Against the original hour, and against a simulation of the same span.
  auto r = test::run_command(skytrace_cmd() + " compare " + q(real) + " " + q(esbc_obs()) + " --json " +
                             q(dir_ / "self.json"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("warning"), std::string::npos) << r.output;
  EXPECT_EQ(read_json(dir_ / "self.json")["common_epochs"], 20);
  const auto scenario = write_scenario(dir_, kEsbjerg, "2020-06-25T00:00:00", "[G1C, E1C]", esbc_nav());
  r = run(scenario);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = test::run_command(skytrace_cmd() + " compare " + q(real) + " " + q(dir_ / "out" / "obs.rnx") + " --nav " +
                        q(esbc_nav()));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("G1C"), std::string::npos) << r.output;

  r = test::run_command(skytrace_cmd() + " position " + q(real) + " --nav " + q(esbc_nav()) + " --out " +
                        q(dir_ / "fix.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(read_lines(dir_ / "fix.csv").size(), 21u);  // header and 20 epochs
}

TEST_F(RealStyleInputs, MalformedObservationCodeNamesFileAndLine) {
  auto lines = read_lines(esbc_obs());
  size_t at = 0;
  for (; at < lines.size(); ++at) {
    if (lines[at].find("SYS / # / OBS TYPES") != std::string::npos && lines[at][0] == 'G') break;
  }
  ASSERT_LT(at, lines.size());
  lines[at].replace(7, 3, "C1 ");  // a code without its attribute
  lines.resize(at + 40);
  write_lines(dir_ / "bad.rnx", lines);
  const auto r = test::run_command(skytrace_cmd() + " compare " + q(dir_ / "bad.rnx") + " " + q(esbc_obs()));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("bad.rnx:" + std::to_string(at + 1)), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("'C1'"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("expected"), std::string::npos) << r.output;
}

TEST_F(RealStyleInputs, QzssHealthOneIsUsedForRunPositionAndCompare) {
  const auto nav = write_navigation(dir_, "qzss_health1.rnx", 'J', set_health(1));
  const auto scenario = write_scenario(dir_, kTokyo, kQzssHour, "[G1C, J1C, J2L, J5Q]", nav);
  auto r = run(scenario);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  auto obs = io::read_rinex_obs(dir_ / "out" / "obs.rnx");
  ASSERT_TRUE(obs.ok()) << obs.error().message;
  size_t qzss = 0;
  for (const auto& epoch : obs->epochs) {
    for (const auto& sat : epoch.satellites) qzss += sat.satellite.system == GnssSystem::kQzss ? 1 : 0;
  }
  EXPECT_GT(qzss, 0u) << "no QZSS observation";

  r = test::run_command(skytrace_cmd() + " position " + q(dir_ / "out" / "obs.rnx") + " --nav " + q(nav) +
                        " --out " + q(dir_ / "fix.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = test::run_command(skytrace_cmd() + " compare " + q(dir_ / "out" / "obs.rnx") + " " +
                        q(dir_ / "out" / "obs.rnx") + " --nav " + q(nav));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("J1C"), std::string::npos) << r.output;
}

TEST_F(RealStyleInputs, UnhealthyQzssSignalIsLeftOutAndTheOthersKept) {
  // IS-QZSS-PNT bits 5 (L1) and 4 (L1 C/A) set, L1C/B not transmitted: L1 C/A unusable, L2C and L5 fine.
  const auto nav = write_navigation(dir_, "qzss_l1ca_bad.rnx", 'J', set_health(0x31));
  const auto scenario = write_scenario(dir_, kTokyo, kQzssHour, "[G1C, J1C, J5Q]", nav);
  const auto r = run(scenario);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  auto obs = io::read_rinex_obs(dir_ / "out" / "obs.rnx");
  ASSERT_TRUE(obs.ok()) << obs.error().message;
  const auto j1c = obs->header.type_index(GnssSystem::kQzss, "C1C");
  const auto j5q = obs->header.type_index(GnssSystem::kQzss, "C5Q");
  ASSERT_TRUE(j1c && j5q);
  size_t with_l5 = 0, with_l1 = 0;
  for (const auto& epoch : obs->epochs) {
    for (const auto& sat : epoch.satellites) {
      if (sat.satellite.system != GnssSystem::kQzss) continue;
      with_l5 += sat.values.size() > *j5q && sat.values[*j5q].value ? 1 : 0;
      with_l1 += sat.values.size() > *j1c && sat.values[*j1c].value ? 1 : 0;
    }
  }
  EXPECT_GT(with_l5, 0u);
  EXPECT_EQ(with_l1, 0u);
  const auto truth = read_lines(dir_ / "out" / "truth.csv.zst");
  size_t unhealthy_rows = 0;
  for (const auto& line : truth) {
    if (line.find(",J1C,unhealthy,") != std::string::npos) {
      ++unhealthy_rows;
      EXPECT_NE(line.find("QZSS LNAV health 49"), std::string::npos) << line;
    }
    EXPECT_EQ(line.find(",J5Q,unhealthy,"), std::string::npos) << line;
  }
  EXPECT_GT(unhealthy_rows, 0u);
}

TEST_F(RealStyleInputs, SystemWithoutEphemerisIsLeftOutWithAWarning) {
  const auto nav = write_navigation(dir_, "no_glonass.rnx", 'R', [](std::vector<std::string>& r) { r.clear(); });
  const auto scenario = write_scenario(dir_, kEsbjerg, "2020-06-25T00:00:00", "[G1C, R1C]", nav);
  const auto r = run(scenario);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("GLONASS"), std::string::npos) << r.output;  // the console warning
  const auto summary = read_json(dir_ / "out" / "summary.json");
  bool warned = false;
  for (const auto& warning : summary["warnings"]) {
    const std::string text = warning;
    warned = warned || (text.find("no valid GLONASS ephemeris") != std::string::npos &&
                        text.find("left out") != std::string::npos);
  }
  EXPECT_TRUE(warned) << summary["warnings"].dump();
  auto obs = io::read_rinex_obs(dir_ / "out" / "obs.rnx");
  ASSERT_TRUE(obs.ok()) << obs.error().message;
  EXPECT_EQ(obs->header.observation_types.count(GnssSystem::kGlonass), 0u);
  EXPECT_EQ(obs->header.observation_types.count(GnssSystem::kGps), 1u);
}

TEST_F(RealStyleInputs, NoSystemServedStopsWithExitCode4) {
  const auto nav = write_navigation(dir_, "no_glonass.rnx", 'R', [](std::vector<std::string>& r) { r.clear(); });
  // GLONASS absent altogether; GPS outside the file's day.
  const auto scenario = write_scenario(dir_, kEsbjerg, "2020-07-25T00:00:00", "[G1C, R1C]", nav);
  const auto r = run(scenario);
  EXPECT_EQ(r.exit_code, 4) << r.output;
  EXPECT_NE(r.output.find("no valid GPS ephemeris"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("no valid GLONASS ephemeris"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir_ / "out" / "obs.rnx"));
}

}  // namespace
}  // namespace skytrace
