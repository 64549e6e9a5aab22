// Rtcm3Decoder: what the project's own RTCM 3 stream (1006, MSM7, ephemerides) carries comes back
// from bytes cut at arbitrary places, with garbage and a corrupted frame in between, within the
// fields' resolutions; epochs are gathered by instant and by the multiple-message bit. The check
// against an independent decoder (RTKLIB's convbin) on a real stream is in
// tests/reference/test_rtcm3_decoder_rtklib.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "skytrace/core/constants.hpp"
#include "skytrace/io/rtcm3.hpp"

namespace skytrace::io {
namespace {

RtcmSignalObservation observation(const char* signal, double pseudorange_m, double phase_cycles, double doppler_hz,
                                  double cn0_dbhz, double lock_time_s) {
  RtcmSignalObservation o;
  o.signal = Signal::parse(signal).value();
  o.pseudorange_m = pseudorange_m;
  o.phase_cycles = phase_cycles;
  o.doppler_hz = doppler_hz;
  o.cn0_dbhz = cn0_dbhz;
  o.lock_time_s = lock_time_s;
  return o;
}

double wavelength_m(const char* signal, int glonass_channel = 0) {
  return constants::kSpeedOfLight_mps / find_signal_info(Signal::parse(signal).value())->carrier_frequency_hz(glonass_channel);
}

RtcmEpoch make_epoch(const GnssTime& t, double drift_m) {
  RtcmEpoch e;
  e.time = t;
  const double pr_g = 21'234'567.891 + drift_m, pr_r = 19'876'543.21 + drift_m, pr_e = 24'000'123.456 + drift_m;
  const double pr_c = 37'550'171.141 + drift_m;
  e.satellites.push_back({SatelliteId::parse("G05").value(), 0,
                          {observation("G1C", pr_g, pr_g / wavelength_m("G1C") + 123456, 1234.567, 45.25, 100.0),
                           observation("G2W", pr_g + 3.21, (pr_g - 3.21) / wavelength_m("G2W"), 961.987, 38.0, 100.0)}});
  e.satellites.push_back({SatelliteId::parse("R07").value(), -2,
                          {observation("R1C", pr_r, pr_r / wavelength_m("R1C", -2) - 5000, -2500.25, 50.0, 30.0)}});
  e.satellites.push_back({SatelliteId::parse("E11").value(), 0,
                          {observation("E1C", pr_e, pr_e / wavelength_m("E1C"), 100.5, 47.5, 60.0),
                           observation("E5Q", pr_e + 1.5, (pr_e - 1.5) / wavelength_m("E5Q"), 75.1, 49.0, 60.0)}});
  e.satellites.push_back({SatelliteId::parse("C08").value(), 0,
                          {observation("C2I", pr_c, pr_c / wavelength_m("C2I"), -210.434, 44.625, 300.0)}});
  return e;
}

TEST(Rtcm3Decoder, OwnStreamComesBackFromBytesCutAnywhereWithGarbageBetween) {
  RtcmStation station;
  station.station_id = 611;
  station.arp_ecef_m = Eigen::Vector3d(-3978242.4348, 3382841.1715, 3649902.7667);
  station.antenna_height_m = 1.234;
  Rtcm3Stream stream(Rtcm3StreamSettings{611, 10.0, 60.0}, station);
  const GnssTime t0 = GnssTime::parse_iso8601("2020-06-25T23:59:50", TimeScale::kGpst).value();
  std::vector<std::uint8_t> bytes = {0x00, 0xD3, 0x00, 0x13, 0x44};  // garbage and a false preamble
  std::vector<RtcmEpoch> sent;
  for (int k = 0; k < 20; ++k) {  // across midnight: the GLONASS day and BeiDou's 14 s
    sent.push_back(make_epoch(t0 + k, 700.0 * k));
    auto epoch_bytes = stream.epoch(sent.back(), {}, {});
    ASSERT_TRUE(epoch_bytes.ok()) << epoch_bytes.error().message;
    if (k == 7) {
      auto corrupted = *epoch_bytes;
      corrupted[corrupted.size() / 2] ^= 0x40;  // a frame with a bad CRC: skipped
      bytes.insert(bytes.end(), corrupted.begin(), corrupted.end());
      sent.pop_back();
      continue;
    }
    bytes.insert(bytes.end(), epoch_bytes->begin(), epoch_bytes->end());
    bytes.push_back(0x5A);
  }
  Rtcm3Decoder decoder(t0 + 3600.0 * 24);  // a reference a day later still places the week
  std::mt19937 random(7);
  size_t at = 0;
  while (at < bytes.size()) {
    const size_t n = std::min<size_t>(bytes.size() - at, 1 + random() % 97);
    decoder.feed(std::span<const std::uint8_t>(bytes.data() + at, n));
    at += n;
  }
  decoder.finish();
  const auto epochs = decoder.take_epochs();
  ASSERT_TRUE(decoder.station().has_value());
  EXPECT_EQ(decoder.station()->station_id, 611);
  EXPECT_NEAR((decoder.station()->arp_ecef_m - station.arp_ecef_m).norm(), 0.0, 1e-4);
  EXPECT_NEAR(decoder.station()->antenna_height_m, 1.234, 1e-4);
  EXPECT_GT(decoder.counts().skipped_bytes, 20u);

  // The corrupted epoch lost its damaged frame only: its other systems still form an epoch.
  size_t matched = 0;
  for (const auto& expected : sent) {
    const auto found = std::find_if(epochs.begin(), epochs.end(), [&](const RtcmEpoch& e) { return std::abs(e.time - expected.time) < 1e-6; });
    ASSERT_NE(found, epochs.end()) << expected.time.to_iso8601(TimeScale::kGpst);
    ASSERT_EQ(found->satellites.size(), expected.satellites.size()) << expected.time.to_iso8601(TimeScale::kGpst);
    for (const auto& sat : expected.satellites) {
      const auto got = std::find_if(found->satellites.begin(), found->satellites.end(),
                                    [&](const RtcmSatelliteObservation& s) { return s.satellite == sat.satellite; });
      ASSERT_NE(got, found->satellites.end()) << sat.satellite.to_string();
      EXPECT_EQ(got->glonass_channel, sat.glonass_channel);
      ASSERT_EQ(got->signals.size(), sat.signals.size());
      for (size_t i = 0; i < sat.signals.size(); ++i) {
        const auto& want = sat.signals[i];
        const auto& have = got->signals[i];
        EXPECT_EQ(have.signal, want.signal);
        EXPECT_NEAR(*have.pseudorange_m, *want.pseudorange_m, 6e-4) << want.signal.to_string();
        // Phase: the same up to the whole cycles the encoder takes off per arc.
        const double cycles = *have.phase_cycles - *want.phase_cycles;
        EXPECT_NEAR(cycles, std::round(cycles), 2e-3) << want.signal.to_string();
        EXPECT_NEAR(*have.doppler_hz, *want.doppler_hz, 1e-3 / 0.19) << want.signal.to_string();
        EXPECT_NEAR(have.cn0_dbhz, want.cn0_dbhz, 0.0625);
        EXPECT_LE(have.lock_time_s, want.lock_time_s + 1e-9);
      }
    }
    ++matched;
  }
  EXPECT_EQ(matched, 19u);
}

TEST(Rtcm3Decoder, MessagesItDoesNotReadAreCountedAndMalformedOnesRefused) {
  Rtcm3Decoder decoder(GnssTime::parse_iso8601("2020-06-25T00:00:00", TimeScale::kGpst).value());
  // 1019 with a short body, and an MSM7 header claiming more satellites than it carries.
  const std::vector<std::uint8_t> ephemeris = {0x3F, 0xB0, 0x00};
  const std::vector<std::uint8_t> msm = {0x43, 0x50, 0x00, 0x00, 0x00, 0x00, 0x00, 0xFF, 0xFF};
  for (const auto* message : {&ephemeris, &msm}) {
    auto frame = rtcm3_frame(*message);
    ASSERT_TRUE(frame.ok());
    decoder.feed(*frame);
  }
  decoder.finish();
  EXPECT_EQ(decoder.counts().frames, 2u);
  EXPECT_EQ(decoder.counts().other_messages, 1u);
  EXPECT_EQ(decoder.counts().malformed_messages, 1u);
  EXPECT_TRUE(decoder.take_epochs().empty());
}

}  // namespace
}  // namespace skytrace::io
