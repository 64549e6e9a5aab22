// The RINEX observation reader on real recordings (2.11, 3.03, 3.05, 4.00), and the writer
// reproducing them. Expected numbers were taken from the files with grep/awk, not with this reader.
#include "skytrace/io/rinex_obs.hpp"
#include "test_support.hpp"

namespace skytrace::io {
namespace {

size_t total_records(const ObservationFile& file) {
  size_t n = 0;
  for (const auto& e : file.epochs) n += e.satellites.size();
  return n;
}

// Value k (0-based, in the system's type order) of a satellite in epoch `epoch` (0-based).
const ObservationValue& value_of(const ObservationFile& file, size_t epoch, const char* satellite, size_t k) {
  const auto id = SatelliteId::parse(satellite);
  EXPECT_TRUE(id.ok()) << satellite;
  const auto* record = file.epochs.at(epoch).find(*id);
  if (record == nullptr) throw std::runtime_error(std::string("no ") + satellite + " in epoch " + std::to_string(epoch));
  return record->values.at(k);
}

GnssTime gpst(int y, int mo, int d, int h, int mi, double s) {
  return GnssTime::from_calendar(CalendarTime{y, mo, d, h, mi, s}, TimeScale::kGpst);
}

void expect_value(const ObservationValue& v, double expected, std::uint8_t lli, std::uint8_t ssi) {
  ASSERT_TRUE(v.value.has_value());
  EXPECT_NEAR(*v.value, expected, 1e-6);  // the files hold 3 decimals: parsing must be exact to rounding
  EXPECT_EQ(v.lli, lli);
  EXPECT_EQ(v.ssi, ssi);
}

// Writing what was read, then reading it again, must give every value back to 1e-3 and every flag.
void expect_rewrite_identical(const ObservationFile& original, double version, const std::string& name) {
  const auto dir = test::make_temp_dir("rinex_obs_rewrite_" + name);
  ObservationHeader header = original.header;
  header.version = version;
  header.phase_shifts.clear();  // rewritten as zero shifts
  header.glonass_code_phase_biases.clear();
  const auto path = dir / "rewrite.rnx";
  const Status written = write_rinex_obs(path, header, original.epochs);
  ASSERT_TRUE(written.ok()) << written.error().message;
  auto again = read_rinex_obs(path);
  ASSERT_TRUE(again.ok()) << again.error().message;
  // Codes only: a rewritten RINEX 2 file no longer carries the 2-letter originals.
  ASSERT_EQ(again->header.observation_types.size(), original.header.observation_types.size());
  for (const auto& [system, types] : original.header.observation_types) {
    const auto& other = again->header.observation_types.at(system);
    ASSERT_EQ(other.size(), types.size());
    for (size_t k = 0; k < types.size(); ++k) EXPECT_EQ(other[k].code, types[k].code);
  }
  EXPECT_EQ(again->header.glonass_slots, original.header.glonass_slots);
  EXPECT_EQ(again->header.marker_name, original.header.marker_name);
  ASSERT_EQ(again->epochs.size(), original.epochs.size());
  size_t compared = 0;
  for (size_t e = 0; e < original.epochs.size(); ++e) {
    const auto& a = original.epochs[e];
    const auto& b = again->epochs[e];
    ASSERT_NEAR(b.time - a.time, 0.0, 1e-9);
    ASSERT_EQ(b.satellites.size(), a.satellites.size());
    for (const auto& sat : a.satellites) {
      const auto* other = b.find(sat.satellite);
      ASSERT_NE(other, nullptr);
      ASSERT_EQ(other->values.size(), sat.values.size());
      for (size_t k = 0; k < sat.values.size(); ++k) {
        ASSERT_EQ(other->values[k].value.has_value(), sat.values[k].value.has_value());
        if (sat.values[k].value) {
          ASSERT_NEAR(*other->values[k].value, *sat.values[k].value, 1e-6);
        }
        ASSERT_EQ(other->values[k].lli, sat.values[k].lli);
        ASSERT_EQ(other->values[k].ssi, sat.values[k].ssi);
        ++compared;
      }
    }
  }
  EXPECT_GT(compared, 1000u);
}

TEST(RinexObsRealFiles, Esbc305SixSystems) {
  const auto path = SKYTRACE_SHARED_FILE("real/esbc_2020177/ESBC00DNK_R_20201770000_01D_30S_MO_first1h.rnx");
  auto file = read_rinex_obs(path);
  ASSERT_TRUE(file.ok()) << file.error().message;
  const auto& h = file->header;
  EXPECT_NEAR(h.version, 3.05, 1e-9);
  EXPECT_EQ(h.marker_name, "ESBC00DNK");
  EXPECT_EQ(h.receiver_type, "SEPT POLARX5");
  EXPECT_EQ(h.antenna_type, "ASH701945E_M    SCIS");
  ASSERT_TRUE(h.approx_position_ecef_m.has_value());
  EXPECT_NEAR((*h.approx_position_ecef_m)[0], 3582105.2910, 1e-4);
  EXPECT_NEAR(h.antenna_delta_hen_m[0], 0.2160, 1e-4);
  EXPECT_EQ(h.observation_types.size(), 6u);  // C E G J R S
  EXPECT_EQ(h.observation_types.at(GnssSystem::kGps).size(), 18u);
  EXPECT_EQ(h.observation_types.at(GnssSystem::kGlonass).size(), 20u);
  EXPECT_EQ(h.observation_types.at(GnssSystem::kGalileo).size(), 20u);
  EXPECT_EQ(h.observation_types.at(GnssSystem::kBeiDou).size(), 12u);
  EXPECT_EQ(h.observation_types.at(GnssSystem::kGalileo)[13].code, "L7Q");  // first continuation code
  EXPECT_EQ(h.glonass_slots.size(), 23u);
  EXPECT_EQ(h.glonass_slots[1], (GlonassSlotFrequency{2, -4}));
  EXPECT_EQ(h.glonass_slots.back(), (GlonassSlotFrequency{24, 2}));
  EXPECT_EQ(h.phase_shifts.size(), 22u);
  EXPECT_EQ(h.signal_strength_unit, "DBHZ");
  EXPECT_EQ(h.interval_s, 30.0);
  EXPECT_EQ(h.time_system, TimeScale::kGpst);
  EXPECT_EQ(*h.time_of_first_obs, gpst(2020, 6, 25, 0, 0, 0.0));
  EXPECT_EQ(*h.time_of_last_obs, gpst(2020, 6, 25, 0, 59, 30.0));

  // grep -c '^>' -> 120; sum of the epoch counts (columns 33-35) -> 5278; first epoch 43, last 46.
  ASSERT_EQ(file->epochs.size(), 120u);
  EXPECT_EQ(total_records(*file), 5278u);
  EXPECT_EQ(file->epochs.front().satellites.size(), 43u);
  EXPECT_EQ(file->epochs.back().satellites.size(), 46u);
  EXPECT_EQ(file->epochs.back().time, gpst(2020, 6, 25, 0, 59, 30.0));
  // Values as printed in the file (awk substr of the 16-column fields).
  expect_value(value_of(*file, 0, "G05", 0), 20947300.931, 0, 8);
  expect_value(value_of(*file, 0, "G05", 5), -1037.205, 0, 8);
  EXPECT_FALSE(value_of(*file, 0, "G05", 4).value.has_value());
  expect_value(value_of(*file, 0, "C05", 0), 40715949.461, 0, 5);
  expect_value(value_of(*file, 0, "C05", 6), 212018673.071, 0, 5);
  expect_value(value_of(*file, 0, "S36", 0), 39057532.413, 0, 6);
  expect_value(value_of(*file, 0, "S36", 2), -0.920, 0, 6);  // written "-.920"
  expect_value(value_of(*file, 15, "R12", 14), 93573939.580, 1, 5);
  expect_value(value_of(*file, 119, "R01", 10), 109389997.848, 0, 7);
  expect_value(value_of(*file, 119, "R01", 15), 45.750, 0, 0);

  expect_rewrite_identical(*file, 3.04, "esbc_304");
  expect_rewrite_identical(*file, 4.00, "esbc_400");
}

TEST(RinexObsRealFiles, Nya305TrimbleLayout) {
  const auto path = SKYTRACE_SHARED_FILE("real/nya1_2024124/NYA100NOR_S_20241240000_01D_30S_MO_first1h.rnx");
  auto file = read_rinex_obs(path);
  ASSERT_TRUE(file.ok()) << file.error().message;
  EXPECT_EQ(file->header.marker_name, "NYA1");
  EXPECT_EQ(file->header.receiver_clock_offset_applied, 0);
  EXPECT_EQ(file->header.glonass_slots.size(), 24u);
  EXPECT_TRUE(file->header.glonass_code_phase_biases.empty());  // blank record
  ASSERT_EQ(file->epochs.size(), 120u);
  EXPECT_EQ(total_records(*file), 4034u);
  EXPECT_EQ(file->epochs.front().satellites.size(), 36u);
  EXPECT_EQ(file->epochs.back().satellites.size(), 33u);
  // "> 2024  5  3  0  0  0.0000000  0 36        .000000000000": unpadded date, clock ".000000000000".
  EXPECT_EQ(file->epochs.front().time, gpst(2024, 5, 3, 0, 0, 0.0));
  ASSERT_TRUE(file->epochs.front().receiver_clock_offset_s.has_value());
  EXPECT_EQ(*file->epochs.front().receiver_clock_offset_s, 0.0);
  expect_value(value_of(*file, 0, "G27", 0), 22265735.555, 0, 0);
  expect_value(value_of(*file, 0, "G27", 1), 117007388.310, 1, 8);
  expect_value(value_of(*file, 0, "G20", 14), 0.0, 0, 0);  // written ".000"
  expect_rewrite_identical(*file, 3.04, "nya");
}

TEST(RinexObsRealFiles, Slac211ThreeSystems) {
  const auto path = SKYTRACE_SHARED_FILE("real/slac_2021118/slac1180.21o");
  auto file = read_rinex_obs(path);
  ASSERT_TRUE(file.ok()) << file.error().message;
  const auto& h = file->header;
  EXPECT_NEAR(h.version, 2.11, 1e-9);
  EXPECT_EQ(h.marker_name, "SLAC");
  EXPECT_EQ(h.leap_seconds, 18);
  EXPECT_NEAR((*h.approx_position_ecef_m)[2], 3854247.9550, 1e-4);
  // 20 types on 3 header lines; G, R and E appear in the body.
  ASSERT_EQ(h.observation_types.size(), 3u);
  const auto& g = h.observation_types.at(GnssSystem::kGps);
  ASSERT_EQ(g.size(), 20u);
  EXPECT_EQ(g[3], (ObservationType{"C2W", "P2"}));
  EXPECT_EQ(g[19], (ObservationType{"", "S8"}));
  EXPECT_EQ(h.observation_types.at(GnssSystem::kGalileo)[9], (ObservationType{"C5X", "C5"}));
  // Independent RINEX 2 walk with awk: 241 epochs, 5127 satellite records, 25 in the first epoch.
  ASSERT_EQ(file->epochs.size(), 241u);
  EXPECT_EQ(total_records(*file), 5127u);
  EXPECT_EQ(file->epochs.front().satellites.size(), 25u);
  EXPECT_EQ(file->epochs.back().satellites.size(), 18u);
  EXPECT_EQ(file->epochs.front().time, gpst(2021, 4, 28, 19, 0, 0.0));
  EXPECT_EQ(file->epochs.back().time, gpst(2021, 4, 28, 21, 0, 0.0));
  expect_value(value_of(*file, 0, "G15", 0), 122610995.213, 0, 7);
  expect_value(value_of(*file, 0, "G15", 3), 23332083.105, 0, 0);
  EXPECT_FALSE(value_of(*file, 0, "G01", 4).value.has_value());
  expect_value(value_of(*file, 0, "G19", 1), 82256563.654, 4, 7);
  expect_value(value_of(*file, 0, "R15", 1), 98464487.559, 0, 4);
  expect_value(value_of(*file, 0, "E15", 9), 23962516.750, 0, 0);
  expect_value(value_of(*file, 99, "G13", 0), 127937458.024, 0, 6);
  // No rewrite: several RINEX 2 codes (GPS L6, Galileo P2 ...) have no RINEX 3 equivalent.
}

TEST(RinexObsRealFiles, Kms3Rinex400) {
  const auto path = SKYTRACE_SHARED_FILE("real/kms3_rinex4_2022159/KMS300DNK_R_20221591000_01H_30S_MO.rnx");
  auto file = read_rinex_obs(path);
  ASSERT_TRUE(file.ok()) << file.error().message;
  const auto& h = file->header;
  EXPECT_NEAR(h.version, 4.00, 1e-9);
  EXPECT_EQ(h.marker_name, "KMS3");
  EXPECT_EQ(h.program, "sbf2rin-15.4.0");
  EXPECT_EQ(h.observation_types.size(), 6u);
  EXPECT_EQ(h.glonass_slots.size(), 10u);
  EXPECT_EQ(h.leap_seconds, 18);
  ASSERT_EQ(file->epochs.size(), 19u);
  EXPECT_EQ(total_records(*file), 919u);
  EXPECT_EQ(file->epochs.front().satellites.size(), 49u);
  EXPECT_EQ(file->epochs.back().satellites.size(), 48u);
  EXPECT_EQ(file->epochs.back().time, gpst(2022, 6, 8, 10, 9, 0.0));
  expect_value(value_of(*file, 18, "J04", 4), 233423279.604, 0, 5);
  expect_value(value_of(*file, 18, "J04", 7), 174309599.299, 0, 4);
  expect_value(value_of(*file, 18, "J04", 0), 44418974.505, 0, 5);
  expect_rewrite_identical(*file, 4.00, "kms3");
}

TEST(RinexObsRealFiles, HatanakaCompressedFileIsRefusedClearly) {
  const auto path = SKYTRACE_SHARED_FILE("real/kms3_rinex4_2022159/KMS300DNK_R_20221591000_01H_30S_MO.crx");
  auto file = read_rinex_obs(path);
  ASSERT_FALSE(file.ok());
  EXPECT_EQ(file.error().code, ErrorCode::kUnsupported);
  EXPECT_NE(file.error().message.find("MO.crx:1:"), std::string::npos) << file.error().message;
  EXPECT_NE(file.error().message.find("crx2rnx"), std::string::npos) << file.error().message;
}

TEST(RinexObsRealFiles, SmartLocBerlin211FiveHertz) {
  const auto path = SKYTRACE_SHARED_FILE("real/smartloc_berlin_potsdamer_platz_2016158/Berlin_Potsdamer_Platz.obs");
  auto file = read_rinex_obs(path);
  ASSERT_TRUE(file.ok()) << file.error().message;
  const auto& h = file->header;
  EXPECT_NEAR(h.version, 2.11, 1e-9);
  EXPECT_EQ(h.program, "smartLoc");
  EXPECT_TRUE(h.marker_name.empty());
  // Types C1 L1 S1 D1; the body has G, R and S (SBAS PRN 120 written S20).
  ASSERT_EQ(h.observation_types.size(), 3u);
  EXPECT_EQ(h.observation_types.at(GnssSystem::kSbas)[3], (ObservationType{"D1C", "D1"}));
  ASSERT_EQ(file->epochs.size(), 1375u);
  EXPECT_EQ(total_records(*file), 21270u);
  EXPECT_EQ(file->epochs.front().satellites.size(), 19u);
  EXPECT_EQ(file->epochs.back().satellites.size(), 16u);
  // 11:10:41.7 GPST = GPS week 1900 TOW 126641.7 s (the data set's t = 0).
  EXPECT_NEAR(file->epochs.front().time - GnssTime::from_week_tow(TimeScale::kGpst, 1900, 126641.7), 0.0, 1e-9);
  EXPECT_NEAR(file->epochs.back().time - gpst(2016, 6, 6, 11, 15, 25.0), 0.099, 1e-9);
  expect_value(value_of(*file, 0, "G12", 0), 19834589.652, 0, 8);
  expect_value(value_of(*file, 0, "R20", 1), 105797330.978, 0, 6);
  expect_value(value_of(*file, 0, "S20", 3), 297.699, 0, 6);
  expect_value(value_of(*file, 1374, "G02", 3), 2754.212, 0, 5);
  expect_rewrite_identical(*file, 3.04, "smartloc");
}

TEST(RinexObsRealFiles, HongKongUblox303) {
  const auto path = SKYTRACE_SHARED_FILE("real/hk_tst_ublox_m8t_2019118/COM3_190428_124409.obs");
  auto file = read_rinex_obs(path);
  ASSERT_TRUE(file.ok()) << file.error().message;
  const auto& h = file->header;
  EXPECT_NEAR(h.version, 3.03, 1e-9);
  EXPECT_EQ(h.program, "RTKCONV 2.4.3 b30");
  EXPECT_EQ(h.observation_types.size(), 5u);
  EXPECT_EQ(h.observation_types.at(GnssSystem::kBeiDou)[1].code, "L2I");
  EXPECT_EQ(h.glonass_code_phase_biases.size(), 4u);
  ASSERT_EQ(file->epochs.size(), 1760u);
  EXPECT_EQ(total_records(*file), 26146u);
  EXPECT_EQ(file->epochs.front().satellites.size(), 8u);
  EXPECT_EQ(file->epochs.back().satellites.size(), 12u);
  EXPECT_NEAR(file->epochs.front().time - gpst(2019, 4, 28, 12, 44, 33.0), 0.997, 1e-9);
  EXPECT_NEAR(file->epochs.back().time - gpst(2019, 4, 28, 13, 13, 53.0), 0.001, 1e-9);
  // "G 2  21600712.022   113512506.8763": blank-padded PRN, LLI 3 and no SSI.
  expect_value(value_of(*file, 0, "G02", 1), 113512506.876, 3, 0);
  const auto& blank_with_lli = value_of(*file, 0, "G19", 1);
  EXPECT_FALSE(blank_with_lli.value.has_value());
  EXPECT_EQ(blank_with_lli.lli, 3);
  expect_value(value_of(*file, 0, "C28", 2), 1714.910, 0, 0);
  expect_value(value_of(*file, 1759, "C04", 1), 201761745.113, 2, 0);
  expect_value(value_of(*file, 1759, "C11", 3), 31.0, 0, 0);
  expect_rewrite_identical(*file, 3.04, "hk");
}

}  // namespace
}  // namespace skytrace::io
