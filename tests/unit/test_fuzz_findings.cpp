// Regressions of inputs found by fuzzing (fuzz/, docs/reliability.md): each test holds the
// essence of one finding, reduced by hand, and what the code must do instead.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "skytrace/core/time.hpp"
#include "skytrace/io/rinex_obs.hpp"
#include "skytrace/io/rtcm3.hpp"
#include "skytrace/orbits/fetch.hpp"
#include "skytrace/orbits/rinex_nav.hpp"
#include "skytrace/world/loaders.hpp"
#include "skytrace/sim/scenario.hpp"
#include "test_support.hpp"

#include <fstream>

namespace skytrace {
namespace {

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

// UBSan: float-cast-overflow of the version in both RINEX readers (a version of 2E11 has no int).
TEST(FuzzFindings, RinexVersionFarOutOfRangeIsRefusedWithFileLineAndRange) {
  const auto obs = io::parse_rinex_obs(
      "v.obs", "     2E11           OBSERVATION DATA    M                   RINEX VERSION / TYPE\n");
  ASSERT_FALSE(obs.ok());
  EXPECT_EQ(obs.error().code, ErrorCode::kUnsupported);
  EXPECT_TRUE(contains(obs.error().message, "v.obs:1:")) << obs.error().message;
  EXPECT_TRUE(contains(obs.error().message, "2E11")) << obs.error().message;
  EXPECT_TRUE(contains(obs.error().message, "2.x, 3.x and 4.x")) << obs.error().message;

  for (const char* version : {"     2E11", "    -1E30"}) {
    const auto nav = orbits::parse_rinex_nav(
        "v.nav", std::string(version) + "           N: GNSS NAV DATA    G: GPS              RINEX VERSION / TYPE\n");
    ASSERT_FALSE(nav.ok()) << version;
    EXPECT_EQ(nav.error().code, ErrorCode::kUnsupported) << version;
    EXPECT_TRUE(contains(nav.error().message, "v.nav:1:")) << nav.error().message;
    EXPECT_TRUE(contains(nav.error().message, "2.x, 3.x and 4.x")) << nav.error().message;
  }
  // NaN and inf are no numbers at all: malformed, like any numeric field holding them.
  for (const char* version : {"      nan", "      inf"}) {
    const auto nav = orbits::parse_rinex_nav(
        "v.nav", std::string(version) + "           N: GNSS NAV DATA    G: GPS              RINEX VERSION / TYPE\n");
    ASSERT_FALSE(nav.ok()) << version;
    EXPECT_EQ(nav.error().code, ErrorCode::kParse) << version;
    EXPECT_TRUE(contains(nav.error().message, "v.nav:1: field 'format version': not a number")) << nav.error().message;
  }
}

// UBSan: a Toe of 1e40 s reached the int64 conversion of GnssTime::from_week_tow.
TEST(FuzzFindings, RinexNavToeFarOutsideTheWeekIsAnErrorNamingTheField) {
  const std::string text =
      "     3.04           N: GNSS NAV DATA    G: GPS              RINEX VERSION / TYPE\n"
      "                                                            END OF HEADER\n"
      "G05 2020 06 25 04 00 00 1.604342833161E-05 7.048583938740E-12 0.000000000000E+00\n"
      "     5.800000000000E+01-3.968750000000E+01 4.304822170265E-09 6.342094507864E-01\n"
      "    -2.177432179451E-06 1.000394229777E-02 1.937150955200E-06 5.153707128525E+03\n"
      "     1.000000000000E+40-1.508742570877E-07 2.572838528869E+00 1.359730958939E-07\n"
      "     9.806518601091E-01 3.539687500000E+02 7.941703015008E-01-8.384634967987E-09\n"
      "    -5.714523747137E-11 1.000000000000E+00 2.111000000000E+03 0.000000000000E+00\n"
      "     2.000000000000E+00 0.000000000000E+00 5.122274160385E-09 5.800000000000E+01\n"
      "     3.561060000000E+05 4.000000000000E+00\n";
  const auto nav = orbits::parse_rinex_nav("t.rnx", text);
  ASSERT_FALSE(nav.ok());
  EXPECT_TRUE(contains(nav.error().message, "t.rnx:6: field 'Toe': out of range")) << nav.error().message;
}

// The time conversions themselves never convert an out-of-range double: the plain ones clamp to
// +-kMaxTimeOffset_s, the checked ones refuse.
TEST(FuzzFindings, TimeConversionsOfAbsurdDoublesAreDefined) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  for (const double bad_s : {1e40, -1e40, inf, -inf, nan}) {
    EXPECT_FALSE(time_offset_in_range(bad_s)) << bad_s;
    const GnssTime t = GnssTime::from_week_tow(TimeScale::kGpst, 2111, bad_s);
    EXPECT_LE(std::abs(static_cast<double>(t.whole_seconds())), kMaxTimeOffset_s + 2111 * 604800.0) << bad_s;
    EXPECT_FALSE(GnssTime::checked_week_tow(TimeScale::kGpst, 2111, bad_s).ok()) << bad_s;
    EXPECT_FALSE(GnssTime::checked_calendar(CalendarTime{2020, 1, 1, 0, 0, bad_s}, TimeScale::kUtc).ok()) << bad_s;
    (void)GnssTime::from_calendar(CalendarTime{2020, 1, 1, 0, 0, bad_s}, TimeScale::kUtc);
    (void)GnssTime::from_gpst_seconds(0, bad_s);
    (void)(GnssTime{} + bad_s);
  }
  EXPECT_EQ(GnssTime::from_gpst_seconds(0, 1e40).whole_seconds(), static_cast<std::int64_t>(kMaxTimeOffset_s));
  EXPECT_EQ(GnssTime::from_gpst_seconds(0, -1e40).whole_seconds(), -static_cast<std::int64_t>(kMaxTimeOffset_s));
  const auto bad_tow = GnssTime::checked_week_tow(TimeScale::kGpst, 2111, 1e40);
  ASSERT_FALSE(bad_tow.ok());
  EXPECT_EQ(bad_tow.error().code, ErrorCode::kInvalidArgument);
  EXPECT_FALSE(GnssTime::checked_calendar(CalendarTime{2020, 13, 1, 0, 0, 0.0}, TimeScale::kUtc).ok());
  EXPECT_FALSE(GnssTime::checked_calendar(CalendarTime{2020, 1, 0, 0, 0, 0.0}, TimeScale::kUtc).ok());
  // In range the checked forms are the plain ones.
  EXPECT_EQ(*GnssTime::checked_week_tow(TimeScale::kBdt, 800, 3600.5), GnssTime::from_week_tow(TimeScale::kBdt, 800, 3600.5));
  const CalendarTime c{2016, 12, 31, 23, 59, 60.25};
  EXPECT_EQ(*GnssTime::checked_calendar(c, TimeScale::kUtc), GnssTime::from_calendar(c, TimeScale::kUtc));
}

// Codes packed least-significant bit first, as in Unix compress data.
class LzwPacker {
 public:
  void put(std::uint32_t code, int width) {
    for (int b = 0; b < width; ++b, ++position_bits_) {
      if (position_bits_ / 8 >= bytes_.size()) bytes_.push_back('\0');
      if ((code >> b) & 1U) bytes_[position_bits_ / 8] = static_cast<char>(bytes_[position_bits_ / 8] | (1 << (position_bits_ % 8)));
    }
  }
  // Zero bits up to the next multiple of `bits`.
  void pad_to(std::size_t bits) {
    while (position_bits_ % bits != 0) put(0, 1);
  }
  [[nodiscard]] const std::string& bytes() const { return bytes_; }

 private:
  std::string bytes_;
  std::size_t position_bits_ = 0;
};

// ASan: with a 9-bit maximum the table is full at 512 entries while the width still grows to 10
// bits (as compress writes it); a code 512 then became the previous code and the next one read
// one entry past the 512-entry tables.
TEST(FuzzFindings, LzwCodeEqualToTheFullTableSizeIsCorruptData) {
  LzwPacker codes;
  for (std::uint32_t k = 0; k < 257; ++k) codes.put('a' + k % 26, 9);  // 256 new entries: 256..511
  codes.pad_to(9 * 8);  // the group of eight 9-bit codes ends before the width grows
  codes.put(512, 10);
  codes.put(512, 10);
  const std::string data = std::string{'\x1f', '\x9d', '\x09'} + codes.bytes();
  const auto text = orbits::uncompress_lzw(data);
  ASSERT_FALSE(text.ok());
  EXPECT_EQ(text.error().code, ErrorCode::kParse);
  EXPECT_TRUE(contains(text.error().message, "code 512 is beyond the table")) << text.error().message;

  // The same table, full, followed by codes it holds decodes (the 9-bit files compress writes).
  LzwPacker valid;
  for (std::uint32_t k = 0; k < 257; ++k) valid.put('a' + k % 26, 9);
  valid.pad_to(9 * 8);
  valid.put(300, 10);
  const auto decoded = orbits::uncompress_lzw(std::string{'\x1f', '\x9d', '\x09'} + valid.bytes());
  ASSERT_TRUE(decoded.ok()) << decoded.error().message;
  // Entry 300 was made from the literals 44 and 45 ('s', 't').
  EXPECT_EQ(decoded->size(), 257u + 2u);
  EXPECT_EQ(decoded->substr(257), "st");
}

// UBSan: BitReader::get_signed shifted by -1 for a 0-bit field and overflowed computing the value
// of a negative 63-bit field.
TEST(FuzzFindings, RtcmBitReaderFieldsOfAnyWidthAreDefined) {
  const std::vector<std::uint8_t> ones(16, 0xFF);
  io::BitReader reader(ones);
  EXPECT_EQ(reader.get_signed(0), 0);
  EXPECT_EQ(reader.get_sign_magnitude(0), 0);
  EXPECT_EQ(reader.position(), 0u);
  EXPECT_EQ(reader.get_signed(63), -1);
  EXPECT_EQ(reader.get_signed(64), -1);
  EXPECT_FALSE(reader.overrun());
  const std::vector<std::uint8_t> sign_only{0x80, 0, 0, 0, 0, 0, 0, 0};
  io::BitReader high(sign_only);
  EXPECT_EQ(high.get_signed(63), -(std::int64_t{1} << 62));
  io::BitReader magnitude(ones);
  EXPECT_EQ(magnitude.get_sign_magnitude(64), -std::numeric_limits<std::int64_t>::max());
}

// The cityjson fuzz target's smoke run in CI (2026-11-27): a member of another JSON type than the
// loader reads ("type": 9999999999) made nlohmann's value() throw out of the loader (terminate).
TEST(FuzzFindings, CityJsonMemberOfAnotherTypeIsAParseErrorNamingTheFile) {
  const auto dir = test::make_temp_dir("fuzz_cityjson");
  const auto path = dir / "typed.json";
  std::ofstream(path) << R"({"type":9999999999,"version":"2.0","transform":{"scale":[0.001,0.001,0.001],"translate":[13.3723,52.5086,0]},
"metadata":{"referenceSystem":"https://www.opengis.net/def/crs/EPSG/0/4326"},
"CityObjects":{"house":{"type":"Building","geometry":[{"type":"Solid","lod":"2.2","blod":1,"boundaries":[[[[[0,1,2]]]]]}]}},
"vertices":[[390000.0,5800000.0,30.0],[390010.0,58000000]]})";
  auto world = world::load_cityjson_world(path, {});
  ASSERT_FALSE(world);
  EXPECT_EQ(world.error().code, ErrorCode::kParse);
  EXPECT_NE(world.error().message.find("typed.json: malformed CityJSON"), std::string::npos) << world.error().message;
  // The same with a geometry type of another JSON type, deeper in the file.
  std::ofstream(path) << R"({"type":"CityJSON","version":"2.0","CityObjects":{"house":{"type":"Building","geometry":[{"type":7,"lod":"2"}]}},"vertices":[[0,0,0]]})";
  auto deeper = world::load_cityjson_world(path, {});
  ASSERT_FALSE(deeper);
  EXPECT_EQ(deeper.error().code, ErrorCode::kParse);
}

// The sdf fuzz target (session 20, in CI's 16 s smoke run, once loads had become 40 times
// faster): a version attribute that is no number (`<sdf version="\xe0.4">`) made sdformat call
// std::stoi unchecked, and its exception ended the program. Now an error naming the file, in the
// world file and in a model file it includes.
TEST(FuzzFindings, SdfVersionThatIsNoNumberIsAParseErrorNamingTheFile) {
  const auto dir = test::make_temp_dir("fuzz_sdf_version");
  const auto path = dir / "w.sdf";
  std::ofstream(path) << "<?xml version=\"1.0\"?>\n<sdf version=\"\xe0.4\">\n<model name=\"m\"><static>true</static>"
                         "<link name=\"l\"><collision name=\"c\"><geometry><box><size>1 1 1</size></box></geometry>"
                         "</collision></link></model>\n</sdf>\n";
  world::SdfLoadOptions isolated;
  isolated.use_environment_paths = false;
  auto world = world::load_sdf_world(path, isolated);
  ASSERT_FALSE(world);
  EXPECT_EQ(world.error().code, ErrorCode::kParse);
  EXPECT_TRUE(contains(world.error().message, "w.sdf: malformed SDF")) << world.error().message;
  EXPECT_TRUE(contains(world.error().message, "version")) << world.error().message;

  const auto models = dir / "models";
  std::filesystem::create_directories(models / "bad");
  std::ofstream(models / "bad" / "model.config")
      << "<?xml version=\"1.0\"?><model><name>bad</name><sdf version=\"1.6\">model.sdf</sdf></model>";
  std::ofstream(models / "bad" / "model.sdf")
      << "<?xml version=\"1.0\"?><sdf version=\"x.y\"><model name=\"bad\"><link name=\"l\"/></model></sdf>";
  const auto including = dir / "including.sdf";
  std::ofstream(including) << "<?xml version=\"1.0\"?><sdf version=\"1.9\"><world name=\"w\"><include><uri>model://bad</uri>"
                              "</include></world></sdf>";
  world::SdfLoadOptions options;
  options.use_environment_paths = false;
  options.model_paths = {models};
  auto included = world::load_sdf_world(including, options);
  ASSERT_FALSE(included);
  EXPECT_EQ(included.error().code, ErrorCode::kParse) << included.error().message;
}

// The scenario fuzz target (session 13, after 5 minutes of two processes): a file with both
// `receiver` and `receivers`, one of them an rtk rover, read past the end of the `receivers` list
// when the rover's base was checked (the receivers' places in the file and in the list differed).
// One of the two keys is what docs/scenario.md allows: both are now an error naming them.
TEST(FuzzFindings, ScenarioWithBothReceiverAndReceiversIsAnError) {
  const std::string text = R"(name: both
time: {start: 2026-03-01T12:00:00, scale: GPST, duration_s: 60, interval_s: 1}
receiver:
  name: ROVR
  position: {ecef_m: [3582105.29, 532589.73, 5232754.81]}
  signals: [G1C]
  rtk: {base: BASE}
receivers:
  - name: BASE
    position: {ecef_m: [3582105.29, 532589.73, 5232754.81]}
    signals: [G1C]
ephemeris: {nominal: true}
)";
  auto scenario = sim::parse_scenario(text, "both.yaml", std::filesystem::current_path());
  ASSERT_FALSE(scenario);
  EXPECT_NE(scenario.error().message.find("give 'receiver' (one receiver) or 'receivers' (a list), not both"),
            std::string::npos)
      << scenario.error().message;
}

}  // namespace
}  // namespace skytrace
