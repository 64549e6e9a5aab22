// With broadcast truth every satellite has one clock, whatever messages the navigation data holds:
// the clock of its reference message's record (Galileo I/NAV, GPS LNAV, BeiDou D1/D2), and each
// signal's code delay relative to it from that record's group delays (Galileo I/NAV carries both
// BGDs), or from the signal's own message where the reference message broadcasts none for it (GPS
// CNAV ISCs, BeiDou CNAV1 TGD_B1Cp), which refer to the same clock reference. The receiver side
// (the records nav.rnx must carry) still follows each signal's message. The nominal constellation is
// given second records of other messages, with other clocks and group delays.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "skytrace/core/constants.hpp"
#include "skytrace/orbits/nominal.hpp"
#include "skytrace/receiver/observation_generator.hpp"

namespace skytrace::receiver {
namespace {

constexpr double kC = constants::kSpeedOfLight_mps;
const SatelliteId kG01{GnssSystem::kGps, 1};

const SignalMeasurement* find(const SatelliteObservation& sat, const char* code) {
  const Signal signal = Signal::parse(code).value();
  for (const auto& m : sat.signals) {
    if (m.signal == signal) return &m;
  }
  return nullptr;
}

class OneClockPerSatellite : public ::testing::Test {
 protected:
  void SetUp() override {
    start_ = GnssTime::parse_iso8601("2020-06-25T00:00:00", TimeScale::kGpst).value();
    orbits::NavigationData data = orbits::make_nominal_constellation(start_, 4 * 3600.0).value();
    // G01: the LNAV record closest to the epoch becomes a CNAV record (clock 5 ns later, T_GD and
    // ISCs of its own), so that a receiver's any-message selection picks CNAV there while the next
    // LNAV record (1 h 50 min away) is still valid.
    auto closest = data.kepler.end();
    for (auto it = data.kepler.begin(); it != data.kepler.end(); ++it) {
      if (it->satellite != kG01 || it->toe < start_ + 3600.0) continue;
      if (closest == data.kepler.end() || it->toe < closest->toe) closest = it;
    }
    ASSERT_NE(closest, data.kepler.end());
    epoch_ = closest->toe + 600.0;
    lnav_toe_ = closest->toe + 7200.0;
    closest->message = orbits::NavMessage::kGpsCnav;
    closest->af0_s += 5e-9;
    closest->group_delays.tgd_s = -4e-9;
    closest->group_delays.isc_l5q5_s = 1.5e-9;
    cnav_ = *closest;
    // Galileo and BeiDou: second records at the same toes. F/NAV's clock 3 ns later and its
    // BGD(E1,E5a) other than I/NAV's; BeiDou CNAV1 records with a clock 4 ns later and TGD_B1Cp.
    std::vector<orbits::KeplerEphemeris> extra;
    for (auto& e : data.kepler) {
      if (e.message == orbits::NavMessage::kGalileoInav) {
        e.group_delays.bgd_e1e5a_s = 2.0e-9;
        e.group_delays.bgd_e1e5b_s = 2.3e-9;
      } else if (e.message == orbits::NavMessage::kGalileoFnav) {
        e.af0_s += 3e-9;
        e.group_delays.bgd_e1e5a_s = 2.6e-9;
      } else if (e.message == orbits::NavMessage::kBeiDouD2) {
        e.group_delays.tgd1_s = 3e-9;  // GEOs: no B1C
      } else if (e.message == orbits::NavMessage::kBeiDouD1) {
        e.group_delays.tgd1_s = 3e-9;
        orbits::KeplerEphemeris cnav1 = e;
        cnav1.message = orbits::NavMessage::kBeiDouCnav1;
        cnav1.af0_s += 4e-9;
        cnav1.group_delays = {};
        cnav1.group_delays.tgd_b1cp_s = 7e-9;
        extra.push_back(cnav1);
      }
    }
    data.kepler.insert(data.kepler.end(), extra.begin(), extra.end());
    ephemerides_ = std::make_unique<orbits::BroadcastEphemerides>(std::move(data));
  }

  EpochObservations observe(ObservationGenerator& generator) { return generator.observe(epoch_).value(); }

  std::unique_ptr<ObservationGenerator> generator() {
    GeneratorSettings settings;
    for (const char* code : {"G1C", "G5Q", "E1C", "E5Q", "E7Q", "C2I", "C1P"}) settings.signals.push_back(Signal::parse(code).value());
    settings.profile = builtin_profile("ideal").value();
    settings.elevation_mask_deg = -90.0;
    settings.troposphere = atmosphere::TroposphereModel::kNone;
    const Geodetic site{48.1, 11.6, 500.0};
    return std::make_unique<ObservationGenerator>(settings, *ephemerides_,
                                                  std::make_shared<StaticPosition>(geodetic_to_ecef(site)));
  }

  GnssTime start_, epoch_, lnav_toe_;
  orbits::KeplerEphemeris cnav_;
  std::unique_ptr<orbits::BroadcastEphemerides> ephemerides_;
};

TEST_F(OneClockPerSatellite, EverySignalOfASatelliteGetsTheReferenceRecordsClock) {
  auto gen = generator();
  const EpochObservations epoch = observe(*gen);
  const double gamma15 = std::pow(kFrequencyL1_Hz / kFrequencyL5_Hz, 2);
  int galileo = 0, beidou = 0;
  bool gps = false;
  for (const auto& sat : epoch.satellites) {
    if (sat.status != SatelliteStatus::kTracked) continue;
    SCOPED_TRACE(sat.satellite.to_string());
    for (const auto& m : sat.signals) EXPECT_EQ(m.satellite_clock_m, sat.satellite_clock_m) << m.signal.to_string();
    if (sat.satellite == kG01) {
      // The truth is LNAV's (the record of toe + 2 h), not the nearer CNAV record's 5 ns later clock.
      const auto* l1 = find(sat, "G1C");
      const auto* l5 = find(sat, "G5Q");
      ASSERT_NE(l1, nullptr);
      ASSERT_NE(l5, nullptr);
      const orbits::KeplerEphemeris* lnav =
          ephemerides_->find_kepler(kG01, epoch_, orbits::NavMessage::kGpsLnav);
      ASSERT_NE(lnav, nullptr);
      EXPECT_EQ(lnav->toe, lnav_toe_);
      const double transmit_clock_m =
          kC * orbits::evaluate_kepler(*lnav, epoch_ - sat.range_m / kC).clock_bias_s;
      EXPECT_NEAR(sat.satellite_clock_m, transmit_clock_m, 1e-6);
      // L1 C/A from LNAV's T_GD; L5 from CNAV's T_GD - ISC_L5Q5 (LNAV broadcasts no ISC).
      EXPECT_NEAR(l1->group_delay_m, kC * lnav->group_delays.tgd_s, 1e-9);
      EXPECT_NEAR(l5->group_delay_m, kC * (-4e-9 - 1.5e-9), 1e-9);
      gps = true;
    }
    if (sat.satellite.system == GnssSystem::kGalileo) {
      const auto* e1 = find(sat, "E1C");
      const auto* e5a = find(sat, "E5Q");
      const auto* e5b = find(sat, "E7Q");
      ASSERT_TRUE(e1 != nullptr && e5a != nullptr && e5b != nullptr);
      // All three from the I/NAV record: E1 BGD(E1,E5b); E5a - E1 = (gamma15 - 1) BGD(E1,E5a) of
      // I/NAV, not F/NAV's 2.6 ns; E5b gamma17 BGD(E1,E5b).
      EXPECT_NEAR(e1->group_delay_m, kC * 2.3e-9, 1e-9);
      EXPECT_NEAR(e5a->group_delay_m - e1->group_delay_m, kC * (gamma15 - 1.0) * 2.0e-9, 1e-9);
      EXPECT_NEAR(e5b->group_delay_m, kC * std::pow(kFrequencyL1_Hz / kFrequencyE5b_Hz, 2) * 2.3e-9, 1e-9);
      ++galileo;
    }
    if (sat.satellite.system == GnssSystem::kBeiDou) {
      const auto* b1i = find(sat, "C2I");
      const auto* b1c = find(sat, "C1P");
      ASSERT_NE(b1i, nullptr);
      EXPECT_NEAR(b1i->group_delay_m, kC * 3e-9, 1e-9);  // D1's TGD1
      if (b1c != nullptr) {
        EXPECT_NEAR(b1c->group_delay_m, kC * 7e-9, 1e-9);  // CNAV1's TGD_B1Cp, both relative to B3I
        ++beidou;
      }
    }
  }
  EXPECT_TRUE(gps);
  EXPECT_GT(galileo, 3);
  EXPECT_GT(beidou, 2);

  // The receiver side is unchanged: nav.rnx gets the record each signal's message needs (G01 L1
  // C/A: the nearest record of any message, CNAV; L5: CNAV; Galileo E5a: F/NAV).
  const auto& used = gen->used_kepler();
  EXPECT_TRUE(std::any_of(used.begin(), used.end(), [&](const orbits::KeplerEphemeris* e) {
    return e->satellite == kG01 && e->message == orbits::NavMessage::kGpsCnav && e->toe == cnav_.toe;
  }));
  EXPECT_TRUE(std::any_of(used.begin(), used.end(), [](const orbits::KeplerEphemeris* e) {
    return e->message == orbits::NavMessage::kGalileoFnav;
  }));
  EXPECT_TRUE(std::any_of(used.begin(), used.end(), [](const orbits::KeplerEphemeris* e) {
    return e->message == orbits::NavMessage::kBeiDouCnav1;
  }));
}

}  // namespace
}  // namespace skytrace::receiver
