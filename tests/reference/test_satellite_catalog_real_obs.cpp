// The satellite catalogue against what real receivers recorded and what analysis centres
// published. Each RINEX observation file is scanned with a small parser of its own (independent of
// the library's readers): for every satellite, how many epochs carry a non-blank, non-zero value
// in each pseudorange column. The catalogue must then agree both ways:
//  - forward: every (satellite, code) with data must not be "not transmitted" in the table;
//  - converse: every satellite the table says broadcasts L2C / L5 / L1C (GPS) or B2I / B1C / B2a /
//    B2b (BeiDou), and that has at least kMinEpochs epochs of the L1/B1I reference code, must have
//    data in that column. kMinEpochs keeps out satellites caught for a few epochs near the horizon,
//    when receivers often hold only the strongest signal (e.g. G09 in the KMS3 file: 2 epochs).
// Also every satellite in a precise orbit (SP3) file must be catalogued at that date.
#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "skytrace/core/satellite_catalog.hpp"
#include "test_support.hpp"

namespace skytrace {
namespace {

constexpr int kMinEpochs = 10;

struct ObsScan {
  GnssTime first_epoch;
  std::map<char, std::vector<std::string>> codes;           // system letter -> observation codes
  std::map<std::string, std::map<std::string, int>> epochs;  // "G05" -> {"C2L": 120}
  int epoch_count = 0;

  [[nodiscard]] bool has_code(char system, const std::string& code) const {
    const auto it = codes.find(system);
    if (it == codes.end()) return false;
    for (const auto& c : it->second) {
      if (c == code) return true;
    }
    return false;
  }
  [[nodiscard]] int count(const std::string& sat, const std::string& code) const {
    const auto it = epochs.find(sat);
    if (it == epochs.end()) return 0;
    const auto jt = it->second.find(code);
    return jt == it->second.end() ? 0 : jt->second;
  }
};

// RINEX 3.0x / 4.00 observation files: "SYS / # / OBS TYPES" header records, epoch records
// starting with '>', one line per satellite with 16-character fields (14 value + LLI + SSI).
ObsScan scan_rinex3_obs(const std::filesystem::path& path) {
  ObsScan scan;
  std::ifstream in(path);
  std::string line;
  char current = ' ';
  while (std::getline(in, line)) {
    if (line.size() < 61) continue;
    const std::string label = line.substr(60);
    if (label.rfind("SYS / # / OBS TYPES", 0) == 0) {
      if (line[0] != ' ') current = line[0];
      for (std::size_t pos = 7; pos + 3 <= 58 && pos + 3 <= line.size(); pos += 4) {
        const std::string code = line.substr(pos, 3);
        if (code != "   ") scan.codes[current].push_back(code);
      }
    }
    if (label.rfind("END OF HEADER", 0) == 0) break;
  }
  int skip_lines = 0;
  while (std::getline(in, line)) {
    if (skip_lines > 0) {
      --skip_lines;
      continue;
    }
    if (line.empty()) continue;
    if (line[0] == '>') {
      const int flag = std::stoi(line.substr(31, 1));
      const int count = std::stoi(line.substr(32, 3));
      if (flag > 1) {  // event records: the following lines are header records
        skip_lines = count;
        continue;
      }
      if (scan.epoch_count == 0) {
        const CalendarTime cal{std::stoi(line.substr(2, 4)), std::stoi(line.substr(7, 2)), std::stoi(line.substr(10, 2)),
                               std::stoi(line.substr(13, 2)), std::stoi(line.substr(16, 2)), std::stod(line.substr(18, 11))};
        scan.first_epoch = GnssTime::from_calendar(cal, TimeScale::kGpst);
      }
      ++scan.epoch_count;
      continue;
    }
    const char system = line[0];
    const auto codes = scan.codes.find(system);
    if (codes == scan.codes.end() || line.size() < 3) continue;
    std::string sat = line.substr(0, 3);
    if (sat[1] == ' ') sat[1] = '0';
    for (std::size_t k = 0; k < codes->second.size(); ++k) {
      const std::string& code = codes->second[k];
      if (code[0] != 'C') continue;
      const std::size_t start = 3 + 16 * k;
      if (start >= line.size()) break;
      const std::string field = line.substr(start, 14);
      if (field.find_first_not_of(' ') == std::string::npos) continue;
      // Some receivers (Trimble) write 0.000 for a missing value.
      if (std::stod(field) == 0.0) continue;
      ++scan.epochs[sat][code];
    }
  }
  return scan;
}

Signal signal_of(char system_letter, const std::string& obs_code) {
  return Signal{system_from_letter(system_letter).value(), obs_code[1], obs_code[2]};
}

// Forward check: nothing recorded may be "not transmitted" in the table, and every G/R/E/C/J
// satellite with data is catalogued at that date.
void check_forward(const ObsScan& scan, const std::string& file) {
  for (const auto& [sat, per_code] : scan.epochs) {
    const SatelliteId id = SatelliteId::parse(sat).value();
    if (id.system != GnssSystem::kSbas && id.system != GnssSystem::kNavic) {
      EXPECT_TRUE(satellite_info(id, scan.first_epoch).has_value()) << file << ": " << sat << " is not catalogued";
    }
    for (const auto& [code, n] : per_code) {
      const Signal signal = signal_of(sat[0], code);
      EXPECT_NE(signal_availability(id, signal, scan.first_epoch), SignalAvailability::kNo)
          << file << ": " << sat << " has " << n << " epochs of " << code << " but the table says "
          << signal.to_string() << " is not transmitted";
    }
  }
}

// Converse check for one signal: satellites of `system` the table says broadcast `target`, and
// with at least kMinEpochs epochs of `reference`, must have data in the `target` column.
// Returns how many satellites were checked so that a test can insist the check was not vacuous.
int check_converse(const ObsScan& scan, const std::string& file, char system, const std::string& reference,
                   const std::string& target) {
  if (!scan.has_code(system, reference) || !scan.has_code(system, target)) return 0;
  int checked = 0;
  for (const auto& [sat, per_code] : scan.epochs) {
    if (sat[0] != system || scan.count(sat, reference) < kMinEpochs) continue;
    const SatelliteId id = SatelliteId::parse(sat).value();
    if (!transmits(id, signal_of(system, target), scan.first_epoch)) continue;
    ++checked;
    EXPECT_GT(scan.count(sat, target), 0)
        << file << ": the table says " << sat << " broadcasts " << target << ", it has "
        << scan.count(sat, reference) << " epochs of " << reference << " but none of " << target;
  }
  return checked;
}

TEST(SatelliteCatalogRealObs, Esbc2020SeptentrioRinex305) {
  const auto path = SKYTRACE_SHARED_FILE("real/esbc_2020177/ESBC00DNK_R_20201770000_01D_30S_MO_first1h.rnx");
  const ObsScan scan = scan_rinex3_obs(path);
  ASSERT_EQ(scan.epoch_count, 120);
  check_forward(scan, "ESBC");
  // GPS: L2C on IIR-M/IIF/III, L5 on IIF/III. On this day 8 satellites have L2C data and 5 have L5.
  EXPECT_EQ(check_converse(scan, "ESBC", 'G', "C1C", "C2L"), 8);
  EXPECT_EQ(check_converse(scan, "ESBC", 'G', "C1C", "C5Q"), 5);
  // BeiDou: B2I only on BDS-2 (C05..C12 seen here); the BDS-3 satellites C19..C37 have no C7I.
  EXPECT_EQ(check_converse(scan, "ESBC", 'C', "C2I", "C7I"), 5);
  for (const char* sat : {"C19", "C20", "C23", "C32", "C34", "C37"}) {
    EXPECT_EQ(scan.count(sat, "C7I"), 0) << sat;
    EXPECT_GT(scan.count(sat, "C2I"), 0) << sat;
  }
  // The IIR-A satellites recorded (G13, G20, G21, G28) have no L2C; the IIR-M ones no L5.
  for (const char* sat : {"G13", "G21", "G28"}) EXPECT_EQ(scan.count(sat, "C2L"), 0) << sat;
  for (const char* sat : {"G05", "G07", "G15"}) EXPECT_EQ(scan.count(sat, "C5Q"), 0) << sat;
}

TEST(SatelliteCatalogRealObs, Nya2024TrimbleRinex305) {
  const auto path = SKYTRACE_SHARED_FILE("real/nya1_2024124/NYA100NOR_S_20241240000_01D_30S_MO_first1h.rnx");
  const ObsScan scan = scan_rinex3_obs(path);
  ASSERT_EQ(scan.epoch_count, 120);
  check_forward(scan, "NYA1");
  // Trimble writes L2C as C2X and L5 as C5X.
  EXPECT_EQ(check_converse(scan, "NYA1", 'G', "C1C", "C2X"), 10);
  EXPECT_EQ(check_converse(scan, "NYA1", 'G', "C1C", "C5X"), 7);
  // BeiDou C7X is B2I (I+Q): BDS-2 C06 and C11 (C16 has 2 epochs only).
  EXPECT_EQ(check_converse(scan, "NYA1", 'C', "C2X", "C7X"), 2);
  for (const char* sat : {"C19", "C21", "C22", "C27", "C28"}) EXPECT_EQ(scan.count(sat, "C7X"), 0) << sat;
}

TEST(SatelliteCatalogRealObs, Kms3SeptentrioRinex400) {
  const auto path = SKYTRACE_SHARED_FILE("real/kms3_rinex4_2022159/KMS300DNK_R_20221591000_01H_30S_MO.rnx");
  const ObsScan scan = scan_rinex3_obs(path);
  ASSERT_EQ(scan.epoch_count, 19);
  check_forward(scan, "KMS3");
  EXPECT_EQ(check_converse(scan, "KMS3", 'G', "C1C", "C2L"), 7);
  EXPECT_EQ(check_converse(scan, "KMS3", 'G', "C1C", "C5Q"), 4);
  EXPECT_EQ(check_converse(scan, "KMS3", 'G', "C1C", "C1L"), 2);  // GPS III: G18, G23
  // BDS-3 MEO/IGSO (11 with enough B1I epochs): B1C pilot, B2a pilot, B2b data; BDS-2: B2I.
  EXPECT_EQ(check_converse(scan, "KMS3", 'C', "C2I", "C1P"), 11);
  EXPECT_EQ(check_converse(scan, "KMS3", 'C', "C2I", "C5P"), 11);
  EXPECT_EQ(check_converse(scan, "KMS3", 'C', "C2I", "C7D"), 12);  // + the BDS-3 GEO C60 (PPP-B2b)
  EXPECT_EQ(check_converse(scan, "KMS3", 'C', "C2I", "C7I"), 3);
  // The BDS-3 GEO C60 has B1I and B2b but neither B1C nor B2a, as the B1C/B2a ICDs state.
  EXPECT_GT(scan.count("C60", "C7D"), 0);
  EXPECT_EQ(scan.count("C60", "C1P"), 0);
  EXPECT_EQ(scan.count("C60", "C5P"), 0);
}

// Satellites listed in a precise orbit file's header ("+" records).
std::set<std::string> sp3_satellites(const std::filesystem::path& path) {
  std::set<std::string> sats;
  std::ifstream in(path);
  std::string line;
  int line_no = 0;
  while (std::getline(in, line) && ++line_no < 40) {
    if (line.rfind("+ ", 0) != 0) continue;
    for (std::size_t pos = 9; pos + 3 <= line.size() && pos < 60; pos += 3) {
      const std::string sat = line.substr(pos, 3);
      if (sat[0] != ' ' && sat[0] != '0') sats.insert(sat);
    }
  }
  return sats;
}

// `gps_complete`: the orbit file has every GPS satellite in service, so the catalogue must list
// no other GPS PRN, except those in `absent_ok` (each with a reason at the call).
void check_sp3(const std::filesystem::path& path, const GnssTime& t, bool gps_complete,
               const std::set<std::string>& absent_ok = {}) {
  const auto sats = sp3_satellites(path);
  ASSERT_FALSE(sats.empty()) << path;
  for (const auto& sat : sats) {
    EXPECT_TRUE(satellite_info(SatelliteId::parse(sat).value(), t).has_value())
        << path.filename() << ": " << sat << " is not catalogued";
  }
  if (gps_complete) {
    for (const auto& info : catalogued_satellites(GnssSystem::kGps, t)) {
      if (absent_ok.count(info.id.to_string()) == 1) continue;
      EXPECT_TRUE(sats.count(info.id.to_string()) == 1)
          << path.filename() << ": catalogued " << info.id.to_string() << " is not in the orbit file";
    }
  }
}

TEST(SatelliteCatalogRealObs, PreciseOrbitSatelliteLists) {
  const auto grg = SKYTRACE_SHARED_FILE("real/esbc_2020177/GRG0MGXFIN_20201770000_01D_15M_ORB.SP3");
  const auto code = SKYTRACE_SHARED_FILE("real/slac_2021118/COD0MGXFIN_20211180000_01D_05M_ORB.SP3");
  const auto gfz = SKYTRACE_SHARED_FILE("real/smartloc_berlin_potsdamer_platz_2016158/gbm19001.sp3");
  const auto noon = [](int y, int m, int d) {
    return GnssTime::from_calendar(CalendarTime{y, m, d, 12, 0, 0.0}, TimeScale::kGpst);
  };
  // GRG 2020-06-25 leaves out the GPS III satellite G04, so only the forward direction there.
  check_sp3(grg, noon(2020, 6, 25), false);
  // CODE 2021-04-28: G11 is absent from both (SVN 46 retired on day 099, SVN 78 set on day 168).
  check_sp3(code, noon(2021, 4, 28), true);
  // GFZ 2016-06-06: G04 was SVN 49, the IIR-M kept as a spare and flown unhealthy; analysis
  // centres leave it out.
  check_sp3(gfz, noon(2016, 6, 6), true, {"G04"});
}

}  // namespace
}  // namespace skytrace
