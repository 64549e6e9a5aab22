// RTCM 3.3 output: CRC-24Q and message 1005 against the example frame of RTCM 10403.x section 4.2,
// bit-level field packing, the DF407 lock-time table, MSM7 messages decoded field by field, and the
// sizes and scaled fields of the ephemeris messages. The check against an independent decoder
// (RTKLIB convbin) is the integration test test_rtcm_rtklib.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <vector>

#include "skytrace/core/constants.hpp"
#include "skytrace/io/rtcm3.hpp"
#include "time_boundaries.hpp"

namespace skytrace::io {
namespace {

const std::vector<std::uint8_t> kExample1005 = {0xD3, 0x00, 0x13, 0x3E, 0xD7, 0xD3, 0x02, 0x02, 0x98,
                                                0x0E, 0xDE, 0xEF, 0x34, 0xB4, 0xBD, 0x62, 0xAC, 0x09,
                                                0x41, 0x98, 0x6F, 0x33, 0x36, 0x0B, 0x98};

TEST(Rtcm3, Crc24qOfThePublishedExampleFrame) {
  const std::span<const std::uint8_t> body(kExample1005.data(), kExample1005.size() - 3);
  EXPECT_EQ(crc24q(body), 0x360B98U);
  EXPECT_EQ(crc24q(kExample1005), 0U);  // a frame with its CRC appended leaves no remainder
}

TEST(Rtcm3, Message1005EqualsThePublishedExample) {
  RtcmStation station;
  station.station_id = 2003;
  station.arp_ecef_m = {1114104.5999, -4850729.7108, 3975521.4643};
  station.gps = true;
  station.glonass = station.galileo = false;
  station.single_receiver_oscillator = false;
  const auto frame = rtcm3_station(station, 1005);
  ASSERT_TRUE(frame.ok()) << frame.error().message;
  EXPECT_EQ(*frame, kExample1005);
  const auto frames = rtcm3_split_frames(*frame);
  ASSERT_EQ(frames.size(), 1U);
  EXPECT_EQ(frames[0].message_number, 1005);
}

TEST(Rtcm3, SplitFramesSkipsGarbageAndBadCrc) {
  std::vector<std::uint8_t> stream = {0x00, 0xD3, 0x12};
  stream.insert(stream.end(), kExample1005.begin(), kExample1005.end());
  auto corrupted = kExample1005;
  corrupted[10] ^= 0x01;
  stream.insert(stream.end(), corrupted.begin(), corrupted.end());
  stream.insert(stream.end(), kExample1005.begin(), kExample1005.end());
  EXPECT_EQ(rtcm3_split_frames(stream).size(), 2U);
}

TEST(Rtcm3, BitFieldsPackMostSignificantBitFirst) {
  BitWriter w;
  w.put_unsigned(0b101, 3);
  w.put_signed(-2, 5);          // 11110
  w.put_sign_magnitude(-5, 6);  // 1 00101
  w.put_unsigned(0x3FF, 10);
  w.put_signed(-(std::int64_t{1} << 37), 38);
  ASSERT_EQ(w.bit_count(), 62U);
  EXPECT_EQ(w.bytes()[0], 0b10111110);
  EXPECT_EQ(w.bytes()[1], 0b10010111);
  BitReader r(w.bytes());
  EXPECT_EQ(r.get_unsigned(3), 5U);
  EXPECT_EQ(r.get_signed(5), -2);
  EXPECT_EQ(r.get_sign_magnitude(6), -5);
  EXPECT_EQ(r.get_unsigned(10), 0x3FFU);
  EXPECT_EQ(r.get_signed(38), -(std::int64_t{1} << 37));
  EXPECT_FALSE(r.overrun());
  (void)r.get_unsigned(8);
  EXPECT_TRUE(r.overrun());
}

TEST(Rtcm3, FrameRefusesOversizedMessages) {
  const std::vector<std::uint8_t> big(1024, 0);
  EXPECT_FALSE(rtcm3_frame(big).ok());
  const std::vector<std::uint8_t> max(1023, 0);
  EXPECT_TRUE(rtcm3_frame(max).ok());
}

TEST(Rtcm3, LockTimeIndicatorTable) {
  // Points of RTCM 10403.3 table 3.5-74 (DF407).
  EXPECT_EQ(msm_lock_time_indicator(0.0), 0);
  EXPECT_EQ(msm_lock_time_indicator(0.063), 63);
  EXPECT_EQ(msm_lock_time_indicator(0.064), 64);
  EXPECT_EQ(msm_lock_time_indicator(0.127), 95);
  EXPECT_EQ(msm_lock_time_indicator(0.128), 96);
  EXPECT_EQ(msm_lock_time_indicator(0.256), 128);
  EXPECT_EQ(msm_lock_time_indicator(33554.432), 672);
  EXPECT_EQ(msm_lock_time_indicator(67108.863), 703);
  EXPECT_EQ(msm_lock_time_indicator(67108.864), 704);
  EXPECT_EQ(msm_lock_time_indicator(1e9), 704);
  EXPECT_DOUBLE_EQ(msm_lock_time_min_s(672), 33554.432);
  // Every indicator's minimum lock time maps back to it, and the table is monotonic.
  for (int i = 0; i < 704; ++i) {
    EXPECT_EQ(msm_lock_time_indicator(msm_lock_time_min_s(i) + 1e-7), i) << i;
    EXPECT_LT(msm_lock_time_min_s(i), msm_lock_time_min_s(i + 1)) << i;
  }
}

TEST(Rtcm3, SignalIdsOfTheMsmTables) {
  const auto id = [](const char* s) { return msm_signal_id(Signal::parse(s).value()); };
  EXPECT_EQ(id("G1C"), 2);
  EXPECT_EQ(id("G2W"), 10);
  EXPECT_EQ(id("G5Q"), 23);
  EXPECT_EQ(id("R1C"), 2);
  EXPECT_EQ(id("R2C"), 8);
  EXPECT_EQ(id("E1C"), 2);
  EXPECT_EQ(id("E5Q"), 23);
  EXPECT_EQ(id("E7Q"), 15);
  EXPECT_EQ(id("C2I"), 2);
  EXPECT_EQ(id("C7I"), 14);
  EXPECT_EQ(id("J1C"), 2);
  EXPECT_EQ(id("R4A"), std::nullopt);  // GLONASS CDMA: no MSM signal ID in RTCM 3.3
  EXPECT_EQ(msm_base(GnssSystem::kNavic), std::nullopt);
}

struct DecodedCell {
  int satellite_id;
  int signal_id;
  double pseudorange_m, phase_m, rate_mps, cn0_dbhz;
  int lock;
  int half;
};

// A plain MSM7 decoder for the test (RTCM 10403.3 3.5.12).
std::vector<DecodedCell> decode_msm7(const std::vector<std::uint8_t>& message, int* number, std::uint32_t* epoch,
                                     int* multiple, std::vector<int>* extended) {
  const double ms = constants::kSpeedOfLight_mps * 1e-3;
  BitReader r(message);
  *number = static_cast<int>(r.get_unsigned(12));
  (void)r.get_unsigned(12);
  *epoch = static_cast<std::uint32_t>(r.get_unsigned(30));
  *multiple = static_cast<int>(r.get_unsigned(1));
  (void)r.get_unsigned(3 + 7 + 2 + 2 + 1 + 3);
  std::vector<int> sats, sigs;
  const std::uint64_t sat_mask = r.get_unsigned(64);
  for (int i = 0; i < 64; ++i) {
    if ((sat_mask >> (63 - i)) & 1U) sats.push_back(i + 1);
  }
  const std::uint64_t sig_mask = r.get_unsigned(32);
  for (int i = 0; i < 32; ++i) {
    if ((sig_mask >> (31 - i)) & 1U) sigs.push_back(i + 1);
  }
  std::vector<std::pair<size_t, int>> cells;
  for (size_t s = 0; s < sats.size(); ++s) {
    for (const int g : sigs) {
      if (r.get_unsigned(1)) cells.emplace_back(s, g);
    }
  }
  std::vector<double> rough_ms(sats.size()), rough_rate(sats.size());
  extended->assign(sats.size(), 0);
  for (size_t s = 0; s < sats.size(); ++s) rough_ms[s] = static_cast<double>(r.get_unsigned(8));
  for (size_t s = 0; s < sats.size(); ++s) (*extended)[s] = static_cast<int>(r.get_unsigned(4));
  for (size_t s = 0; s < sats.size(); ++s) rough_ms[s] += static_cast<double>(r.get_unsigned(10)) / 1024.0;
  for (size_t s = 0; s < sats.size(); ++s) rough_rate[s] = static_cast<double>(r.get_signed(14));
  std::vector<DecodedCell> out(cells.size());
  for (size_t k = 0; k < cells.size(); ++k) {
    out[k].satellite_id = sats[cells[k].first];
    out[k].signal_id = cells[k].second;
    out[k].pseudorange_m = (rough_ms[cells[k].first] + r.get_signed(20) * std::ldexp(1.0, -29)) * ms;
  }
  for (size_t k = 0; k < cells.size(); ++k) {
    out[k].phase_m = (rough_ms[cells[k].first] + r.get_signed(24) * std::ldexp(1.0, -31)) * ms;
  }
  for (auto& c : out) c.lock = static_cast<int>(r.get_unsigned(10));
  for (auto& c : out) c.half = static_cast<int>(r.get_unsigned(1));
  for (auto& c : out) c.cn0_dbhz = static_cast<double>(r.get_unsigned(10)) * 0.0625;
  for (size_t k = 0; k < cells.size(); ++k) {
    out[k].rate_mps = rough_rate[cells[k].first] + r.get_signed(15) * 1e-4;
  }
  EXPECT_FALSE(r.overrun());
  EXPECT_LT(message.size() * 8 - r.position(), 8U);  // only padding left
  return out;
}

RtcmSignalObservation signal_obs(const char* signal, double pr_m, double phase_cycles, double doppler_hz,
                                 double cn0, double lock_s, bool half = false) {
  RtcmSignalObservation o;
  o.signal = Signal::parse(signal).value();
  o.pseudorange_m = pr_m;
  o.phase_cycles = phase_cycles;
  o.doppler_hz = doppler_hz;
  o.cn0_dbhz = cn0;
  o.lock_time_s = lock_s;
  o.half_cycle = half;
  return o;
}

TEST(Rtcm3, Msm7FieldsDecodeToTheInputWithinTheirResolution) {
  const double c = constants::kSpeedOfLight_mps;
  const double lambda_l1 = c / kFrequencyL1_Hz;
  const double lambda_l2 = c / kFrequencyL2_Hz;
  const double lambda_r1 = c / (kFrequencyG1Base_Hz - 2 * kFrequencyG1Step_Hz);
  RtcmEpoch epoch;
  epoch.time = GnssTime::parse_iso8601("2020-06-25T01:02:03", TimeScale::kGpst).value();
  // GPS G05: L1 and L2, a large phase ambiguity the encoder must take off.
  const double pr = 21'234'567.891;
  epoch.satellites.push_back({SatelliteId::parse("G05").value(), 0,
                              {signal_obs("G1C", pr, pr / lambda_l1 + 123456, 1234.567, 45.3, 100.0),
                               signal_obs("G2W", pr + 3.21, (pr - 3.21) / lambda_l2 - 98765, 961.987, 38.1, 100.0, true)}});
  epoch.satellites.push_back({SatelliteId::parse("R07").value(), -2,
                              {signal_obs("R1C", 19'876'543.21, 19'876'543.21 / lambda_r1, -2500.25, 50.0, 0.0)}});
  epoch.satellites.push_back({SatelliteId::parse("I03").value(), 0, {signal_obs("I5A", 3.6e7, 0, 0, 40, 1)}});

  Msm7Encoder encoder(17);
  const auto frames = encoder.encode(epoch);
  ASSERT_TRUE(frames.ok()) << frames.error().message;
  ASSERT_EQ(frames->size(), 2U);  // GPS then GLONASS; NavIC has no MSM in RTCM 3.3
  EXPECT_EQ(encoder.dropped_signals().count(Signal::parse("I5A").value()), 1U);

  const auto gps_frames = rtcm3_split_frames((*frames)[0]);
  ASSERT_EQ(gps_frames.size(), 1U);
  int number = 0, multiple = 0;
  std::uint32_t epoch_field = 0;
  std::vector<int> extended;
  const auto gps = decode_msm7(gps_frames[0].message, &number, &epoch_field, &multiple, &extended);
  EXPECT_EQ(number, 1077);
  EXPECT_EQ(multiple, 1);
  EXPECT_EQ(epoch_field, (4 * 86400 + 3723) * 1000U);  // Thursday 01:02:03 GPST
  ASSERT_EQ(gps.size(), 2U);
  EXPECT_EQ(gps[0].satellite_id, 5);
  EXPECT_EQ(gps[0].signal_id, 2);
  EXPECT_EQ(gps[1].signal_id, 10);
  EXPECT_NEAR(gps[0].pseudorange_m, pr, 0.0003);
  EXPECT_NEAR(gps[1].pseudorange_m, pr + 3.21, 0.0003);
  // Phase: input minus an integer number of cycles.
  const double cycles_l1 = gps[0].phase_m / lambda_l1 - (pr / lambda_l1 + 123456);
  EXPECT_NEAR(cycles_l1, std::round(cycles_l1), 0.001);
  const double cycles_l2 = gps[1].phase_m / lambda_l2 - ((pr - 3.21) / lambda_l2 - 98765);
  EXPECT_NEAR(cycles_l2, std::round(cycles_l2), 0.001);
  EXPECT_NEAR(gps[0].rate_mps, -1234.567 * lambda_l1, 0.0001);
  EXPECT_NEAR(gps[1].rate_mps, -961.987 * lambda_l2, 0.0001);
  EXPECT_NEAR(gps[0].cn0_dbhz, 45.3, 0.0313);
  EXPECT_EQ(gps[0].lock, msm_lock_time_indicator(100.0));
  EXPECT_EQ(gps[0].half, 0);
  EXPECT_EQ(gps[1].half, 1);

  const auto glo_frames = rtcm3_split_frames((*frames)[1]);
  ASSERT_EQ(glo_frames.size(), 1U);
  const auto glo = decode_msm7(glo_frames[0].message, &number, &epoch_field, &multiple, &extended);
  EXPECT_EQ(number, 1087);
  EXPECT_EQ(multiple, 0);
  // GLONASS epoch: day of week and ms of day in Moscow time (UTC + 3 h, GPS - UTC = 18 s).
  EXPECT_EQ(epoch_field >> 27, 4U);
  EXPECT_EQ(epoch_field & ((1U << 27) - 1), (4 * 3600 + 2 * 60 + 3 - 18) * 1000U);
  ASSERT_EQ(extended.size(), 1U);
  EXPECT_EQ(extended[0], 5);  // channel -2 + 7
  ASSERT_EQ(glo.size(), 1U);
  EXPECT_NEAR(glo[0].rate_mps, 2500.25 * lambda_r1, 0.0001);
  EXPECT_EQ(glo[0].lock, 0);
}

TEST(Rtcm3, Msm7KeepsThePhaseOffsetWithinAnArcAndSplitsLargeEpochs) {
  const double lambda = constants::kSpeedOfLight_mps / kFrequencyL1_Hz;
  Msm7Encoder encoder(0);
  std::vector<double> decoded_minus_input;
  for (int k = 0; k < 3; ++k) {
    RtcmEpoch epoch;
    epoch.time = GnssTime::from_gpst_seconds(1'277'000'000 + 30 * k);
    // Code and carrier drift apart by 0.5 m per epoch (ionosphere), the ambiguity stays.
    const double pr = 2.2e7 + 100.0 * k;
    epoch.satellites.push_back({SatelliteId{GnssSystem::kGps, 9}, 0,
                                {signal_obs("G1C", pr, (pr - 0.5 * k) / lambda + 777777, 0.0, 40.0, 30.0 * k)}});
    const auto frames = encoder.encode(epoch);
    ASSERT_TRUE(frames.ok());
    int number = 0, multiple = 0;
    std::uint32_t t = 0;
    std::vector<int> extended;
    const auto cells = decode_msm7(rtcm3_split_frames(frames->at(0)).at(0).message, &number, &t, &multiple, &extended);
    decoded_minus_input.push_back(cells.at(0).phase_m / lambda - ((pr - 0.5 * k) / lambda + 777777));
  }
  EXPECT_NEAR(decoded_minus_input[1], decoded_minus_input[0], 0.001);
  EXPECT_NEAR(decoded_minus_input[2], decoded_minus_input[0], 0.001);

  // 40 GPS satellites with 3 signals: 120 cells need two messages (at most 64 cells each).
  RtcmEpoch big;
  big.time = GnssTime::from_gpst_seconds(1'277'000'000);
  for (int prn = 1; prn <= 32; ++prn) {
    big.satellites.push_back({SatelliteId{GnssSystem::kGps, static_cast<std::uint8_t>(prn)}, 0,
                              {signal_obs("G1C", 2e7, 1e8, 10, 40, 1), signal_obs("G2W", 2e7, 1e8, 10, 40, 1),
                               signal_obs("G5Q", 2e7, 1e8, 10, 40, 1)}});
  }
  const auto frames = encoder.encode(big);
  ASSERT_TRUE(frames.ok());
  ASSERT_EQ(frames->size(), 2U);
  int number = 0, multiple = 0;
  std::uint32_t t = 0;
  std::vector<int> extended;
  const auto first = decode_msm7(rtcm3_split_frames(frames->at(0)).at(0).message, &number, &t, &multiple, &extended);
  EXPECT_EQ(multiple, 1);
  EXPECT_LE(first.size(), 64U);
  const auto second = decode_msm7(rtcm3_split_frames(frames->at(1)).at(0).message, &number, &t, &multiple, &extended);
  EXPECT_EQ(multiple, 0);
  EXPECT_EQ(first.size() + second.size(), 96U);
}

orbits::KeplerEphemeris gps_record() {
  orbits::KeplerEphemeris e;
  e.satellite = SatelliteId{GnssSystem::kGps, 5};
  e.message = orbits::NavMessage::kGpsLnav;
  e.toe = e.toc = GnssTime::from_week_tow(TimeScale::kGpst, 2111, 352800.0);
  e.week = 2111;
  e.toe_sow = 352800.0;
  e.af0_s = -1.2345678e-4;
  e.af1_s_per_s = -3.4106e-12;
  e.sqrt_a_sqrtm = 5153.6543;
  e.eccentricity = 0.0123456;
  e.i0_rad = 0.9712345;
  e.omega0_rad = -2.1234567;
  e.omega_rad = 1.2345678;
  e.m0_rad = -0.5432198;
  e.delta_n_rad_per_s = 4.5e-9;
  e.idot_rad_per_s = -3.2e-10;
  e.omega_dot_rad_per_s = -8.1e-9;
  e.crs_m = -12.34;
  e.crc_m = 234.5;
  e.cuc_rad = -6.2e-7;
  e.cus_rad = 8.1e-6;
  e.cic_rad = 1.1e-7;
  e.cis_rad = -2.2e-8;
  e.group_delays.tgd_s = -1.1e-8;
  e.iode = e.iodc = 77;
  e.accuracy_m = 2.0;
  e.fit_interval_h = 4.0;
  return e;
}

TEST(Rtcm3, Message1019FieldsAreScaledPerTheTable) {
  const auto e = gps_record();
  const auto frame = rtcm3_ephemeris(e);
  ASSERT_TRUE(frame.ok()) << frame.error().message;
  const auto frames = rtcm3_split_frames(*frame);
  ASSERT_EQ(frames.size(), 1U);
  EXPECT_EQ(frames[0].message.size(), 61U);  // 488 bits
  BitReader r(frames[0].message);
  EXPECT_EQ(r.get_unsigned(12), 1019U);
  EXPECT_EQ(r.get_unsigned(6), 5U);
  EXPECT_EQ(r.get_unsigned(10), 2111U % 1024U);
  EXPECT_EQ(r.get_unsigned(4), 0U);  // URA index of 2.0 m
  (void)r.get_unsigned(2);
  EXPECT_NEAR(r.get_signed(14) * std::ldexp(1.0, -43) * constants::kPi, e.idot_rad_per_s, std::ldexp(1.0, -44) * 3.15);
  EXPECT_EQ(r.get_unsigned(8), 77U);
  EXPECT_EQ(r.get_unsigned(16), 352800U / 16U);
  (void)r.get_signed(8);
  (void)r.get_signed(16);
  EXPECT_NEAR(r.get_signed(22) * std::ldexp(1.0, -31), e.af0_s, std::ldexp(1.0, -32));
  EXPECT_EQ(r.get_unsigned(10), 77U);
  EXPECT_NEAR(r.get_signed(16) * std::ldexp(1.0, -5), e.crs_m, std::ldexp(1.0, -6));
  (void)r.get_signed(16);
  // M0 in semicircles.
  EXPECT_NEAR(r.get_signed(32) * std::ldexp(1.0, -31) * constants::kPi, e.m0_rad, 2e-9);
  (void)r.get_signed(16);
  EXPECT_NEAR(static_cast<double>(r.get_unsigned(32)) * std::ldexp(1.0, -33), e.eccentricity, std::ldexp(1.0, -34));
  (void)r.get_signed(16);
  EXPECT_NEAR(static_cast<double>(r.get_unsigned(32)) * std::ldexp(1.0, -19), e.sqrt_a_sqrtm, std::ldexp(1.0, -20));
}

TEST(Rtcm3, EphemerisMessageSizes) {
  auto e = gps_record();
  const auto size_of = [](const auto& record) { return rtcm3_split_frames(rtcm3_ephemeris(record).value()).at(0).message.size(); };
  EXPECT_EQ(size_of(e), 61U);  // 1019: 488 bits
  e.satellite = SatelliteId{GnssSystem::kQzss, 1};
  e.message = orbits::NavMessage::kQzssLnav;
  EXPECT_EQ(size_of(e), 61U);  // 1044: 485 bits
  e.satellite = SatelliteId{GnssSystem::kBeiDou, 11};
  e.message = orbits::NavMessage::kBeiDouD1;
  e.iode = e.iodc = 1;
  e.toe = e.toc = GnssTime::from_week_tow(TimeScale::kBdt, 755, 352800.0);
  EXPECT_EQ(size_of(e), 64U);  // 1042: 511 bits
  e.satellite = SatelliteId{GnssSystem::kGalileo, 11};
  e.message = orbits::NavMessage::kGalileoFnav;
  e.toe = e.toc = GnssTime::from_week_tow(TimeScale::kGst, 1087, 352800.0);
  e.af0_s = 1e-4;
  e.af1_s_per_s = 1e-12;
  EXPECT_EQ(size_of(e), 62U);  // 1045: 496 bits
  e.message = orbits::NavMessage::kGalileoInav;
  EXPECT_EQ(size_of(e), 63U);  // 1046: 504 bits
  e.message = orbits::NavMessage::kGpsCnav;
  EXPECT_FALSE(rtcm3_ephemeris(e).ok());

  orbits::GlonassEphemeris g;
  g.satellite = SatelliteId{GnssSystem::kGlonass, 7};
  g.toe = GnssTime::parse_iso8601("2020-06-25T00:15:00", TimeScale::kUtc).value();
  g.message_frame_time_s = 600.0;
  g.position_m = {1.2e7, -1.5e7, 1.8e7};
  g.velocity_mps = {1234.5, -2345.6, 345.6};
  g.acceleration_mps2 = {1e-6, -2e-6, 0.0};
  g.frequency_channel = 5;
  g.minus_tau_n_s = 1.5e-5;
  g.gamma_n = 9.1e-13;
  const auto glo = rtcm3_split_frames(rtcm3_ephemeris(g).value()).at(0).message;
  EXPECT_EQ(glo.size(), 45U);  // 1020: 360 bits
  BitReader r(glo);
  EXPECT_EQ(r.get_unsigned(12), 1020U);
  EXPECT_EQ(r.get_unsigned(6), 7U);
  EXPECT_EQ(r.get_unsigned(5), 12U);
  (void)r.get_unsigned(4);
  EXPECT_EQ(r.get_unsigned(5), 3U);   // tk: 00:10 UTC = 03:10 Moscow
  EXPECT_EQ(r.get_unsigned(6), 10U);
  EXPECT_EQ(r.get_unsigned(1), 0U);
  (void)r.get_unsigned(2);
  EXPECT_EQ(r.get_unsigned(7), (3 * 3600 + 15 * 60) / 900U);  // tb
  EXPECT_NEAR(r.get_sign_magnitude(24) * std::ldexp(1.0, -20) * 1e3, 1234.5, std::ldexp(1.0, -21) * 1e3);
  EXPECT_NEAR(r.get_sign_magnitude(27) * std::ldexp(1.0, -11) * 1e3, 1.2e7, std::ldexp(1.0, -12) * 1e3);
}

// MSM7 epoch time fields (message number -> DF004 / DF427 / DF416+DF034) of one epoch at t.
std::map<int, std::uint32_t> msm_epoch_fields(const GnssTime& t) {
  RtcmEpoch epoch;
  epoch.time = t;
  epoch.satellites.push_back({SatelliteId::parse("G05").value(), 0, {signal_obs("G1C", 2.1e7, 1.1e8, 100.0, 45.0, 100.0)}});
  epoch.satellites.push_back({SatelliteId::parse("R07").value(), -2, {signal_obs("R1C", 2.0e7, 1.0e8, 100.0, 45.0, 100.0)}});
  epoch.satellites.push_back({SatelliteId::parse("C11").value(), 0, {signal_obs("C2I", 2.2e7, 1.1e8, 100.0, 45.0, 100.0)}});
  Msm7Encoder encoder(17);
  const auto frames = encoder.encode(epoch);
  std::map<int, std::uint32_t> out;
  if (!frames.ok()) {
    ADD_FAILURE() << frames.error().message;
    return out;
  }
  for (const auto& bytes : *frames) {
    for (const auto& frame : rtcm3_split_frames(bytes)) {
      int number = 0, multiple = 0;
      std::uint32_t field = 0;
      std::vector<int> extended;
      decode_msm7(frame.message, &number, &field, &multiple, &extended);
      out[number] = field;
    }
  }
  return out;
}

// The expected epoch fields of a whole-second instant: GPS and BeiDou milliseconds of their week,
// GLONASS day of week << 27 | milliseconds of the Moscow day.
std::map<int, std::uint32_t> expected_epoch_fields(const GnssTime& whole_second) {
  const WeekTow gps = whole_second.to_week_tow(TimeScale::kGpst);
  const WeekTow bdt = whole_second.to_week_tow(TimeScale::kBdt);
  const WeekTow glo = whole_second.to_week_tow(TimeScale::kGlonasst);
  const auto glo_s = static_cast<std::uint32_t>(glo.tow_s);
  return {{1077, static_cast<std::uint32_t>(gps.tow_s) * 1000U},
          {1087, ((glo_s / 86400U) << 27) | ((glo_s % 86400U) * 1000U)},
          {1127, static_cast<std::uint32_t>(bdt.tow_s) * 1000U}};
}

TEST(Rtcm3, MsmEpochTimeRoundedToMillisecondsCarriesIntoTheNextWeekAndDay) {
  for (const auto& b : test::time_boundaries()) {
    const GnssTime next = GnssTime::parse_iso8601(b.next, TimeScale::kGpst).value();
    for (const double fraction : test::fractions_rounding_up(3)) {
      EXPECT_EQ(msm_epoch_fields(test::boundary_time(b, TimeScale::kGpst, fraction)), expected_epoch_fields(next))
          << b.name << ", fraction 1 - " << 1.0 - fraction;
    }
  }
  // GPS week end: millisecond 0 of the next week; BeiDou's week ends 14 s later; the Moscow day
  // (UTC + 3 h) ends at 21:00 UTC.
  const GnssTime gps_week_end = GnssTime::from_week_tow(TimeScale::kGpst, 2312, 604799.9996);
  EXPECT_EQ(msm_epoch_fields(gps_week_end).at(1077), 0U);
  EXPECT_EQ(msm_epoch_fields(GnssTime::from_week_tow(TimeScale::kBdt, 956, 604799.9996)).at(1127), 0U);
  const GnssTime moscow_midnight = GnssTime::parse_iso8601("2024-05-02T20:59:59.9996", TimeScale::kUtc).value();
  EXPECT_EQ(msm_epoch_fields(moscow_midnight).at(1087), 5U << 27);  // Friday 00:00:00.000 Moscow time
}

TEST(Rtcm3, GlonassEpochRoundedAcrossTheEndOfALeapSecond) {
  // 2016-12-31T23:59:60.9996 UTC rounds to 2017-01-01T00:00:00.000 UTC (GPS - UTC now 18 s), which
  // is Sunday 03:00:00.000 Moscow time. The offset must be taken at the rounded instant.
  const GnssTime leap = GnssTime::parse_iso8601("2016-12-31T23:59:60", TimeScale::kUtc).value();
  for (const double fraction : test::fractions_rounding_up(3)) {
    EXPECT_EQ(msm_epoch_fields(leap + fraction).at(1087), 10'800'000U) << "fraction 1 - " << 1.0 - fraction;
  }
}

}  // namespace
}  // namespace skytrace::io
