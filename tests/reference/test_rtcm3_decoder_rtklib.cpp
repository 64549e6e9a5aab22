// Rtcm3Decoder on a real reference-station stream (GMSD, Trimble NetR9, 2012-10-14: MSM7 of GPS,
// GLONASS, QZSS and BeiDou, no 1005/1006) against RTKLIB's convbin, an independent decoder, run on
// the same file: every BeiDou code, phase and C/N0 convbin writes (Debian's RTKLIB 2.4.3 converts
// only the BeiDou MSMs of this early-MSM stream) equals skytrace's to the millimetre; skytrace also
// reads the GPS, GLONASS and QZSS MSMs, and reports that the stream carries no station position.
#include <gtest/gtest.h>

#include <fstream>
#include <iterator>

#include "process.hpp"
#include "skytrace/io/rinex_obs.hpp"
#include "skytrace/io/rtcm3.hpp"
#include "test_support.hpp"

namespace skytrace {
namespace {

TEST(Rtcm3DecoderRtklib, RealMsm7StreamDecodesAsConvbinDecodesIt) {
  const auto stream = SKYTRACE_SHARED_FILE("real/gsi_0759_3040_2005092/GMSD7_20121014.rtcm3");
  if (test::run_command("command -v convbin >/dev/null").exit_code != 0) GTEST_SKIP() << "RTKLIB's convbin not installed";
  const auto dir = test::make_temp_dir("rtcm3_decoder_rtklib");
  const auto rinex = dir / "gmsd.obs";
  const auto converted = test::run_command("convbin -r rtcm3 -tr 2012/10/14 00:00:00 -v 3.04 -o " +
                                           test::shell_quote(rinex.string()) + " " + test::shell_quote(stream.string()) +
                                           " >/dev/null 2>&1");
  ASSERT_EQ(converted.exit_code, 0);
  auto reference = io::read_rinex_obs(rinex);
  ASSERT_TRUE(reference.ok()) << reference.error().message;

  std::ifstream in(stream, std::ios::binary);
  const std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  io::Rtcm3Decoder decoder(GnssTime::parse_iso8601("2012-10-14T00:00:00", TimeScale::kGpst).value());
  decoder.feed(bytes);
  decoder.finish();
  const auto epochs = decoder.take_epochs();
  EXPECT_FALSE(decoder.station().has_value());  // no 1005/1006 in this stream
  EXPECT_EQ(decoder.counts().msm_messages, 4u * 257u);
  EXPECT_EQ(decoder.counts().malformed_messages, 0u);
  // QZSS signal ID 6 of this early stream is not in RTCM 3.3's table: those cells are counted, the
  // message's other cells read.
  EXPECT_EQ(decoder.counts().unknown_signal_cells, 257u);
  std::set<GnssSystem> systems;
  for (const auto& e : epochs) {
    for (const auto& s : e.satellites) systems.insert(s.satellite.system);
  }
  EXPECT_EQ(systems, (std::set<GnssSystem>{GnssSystem::kGps, GnssSystem::kGlonass, GnssSystem::kQzss, GnssSystem::kBeiDou}));

  size_t compared = 0;
  for (const auto& ref : reference->epochs) {
    const auto mine = std::find_if(epochs.begin(), epochs.end(), [&](const io::RtcmEpoch& e) { return std::abs(e.time - ref.time) < 1e-3; });
    ASSERT_NE(mine, epochs.end()) << ref.time.to_iso8601(TimeScale::kGpst);
    for (const auto& sat : ref.satellites) {
      const auto& types = reference->header.observation_types.at(sat.satellite.system);
      const auto s = std::find_if(mine->satellites.begin(), mine->satellites.end(),
                                  [&](const io::RtcmSatelliteObservation& o) { return o.satellite == sat.satellite; });
      ASSERT_NE(s, mine->satellites.end()) << sat.satellite.to_string();
      for (size_t t = 0; t < types.size() && t < sat.values.size(); ++t) {
        if (!sat.values[t].value) continue;
        const std::string& code = types[t].code;
        const auto signal = std::find_if(s->signals.begin(), s->signals.end(),
                                         [&](const io::RtcmSignalObservation& o) { return o.signal.code() == code.substr(1); });
        ASSERT_NE(signal, s->signals.end()) << sat.satellite.to_string() << " " << code;
        const double value = *sat.values[t].value;
        if (code[0] == 'C') {
          EXPECT_NEAR(*signal->pseudorange_m, value, 1e-3) << sat.satellite.to_string() << code;
        } else if (code[0] == 'L') {
          EXPECT_NEAR(*signal->phase_cycles, value, 1e-3) << sat.satellite.to_string() << code;
        } else if (code[0] == 'S') {
          EXPECT_NEAR(signal->cn0_dbhz, value, 1e-3) << sat.satellite.to_string() << code;
        }
        ++compared;
      }
    }
  }
  EXPECT_GT(compared, 5000u);
}

}  // namespace
}  // namespace skytrace
