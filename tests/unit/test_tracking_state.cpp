// Tracking state of the observation generator: acquisition time and thresholds with hysteresis,
// loss of lock and new ambiguities, half-cycle flags, lock time, channel limits, cycle slips at
// low C/N0, reproducible streams, and the link-budget C/N0.
#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "skytrace/orbits/nominal.hpp"
#include "skytrace/receiver/link_budget.hpp"
#include "skytrace/receiver/observation_generator.hpp"
#include "test_support.hpp"

namespace skytrace::receiver {
namespace {

// Open sky, everything blocked, or everything behind a given vegetation loss.
class SwitchWorld final : public PathQuery {
 public:
  bool blocked = false;
  double attenuation_db = 0.0;
  std::vector<RayOutcome> trace(const Eigen::Vector3d&, const std::vector<Eigen::Vector3d>& directions) const override {
    std::vector<RayOutcome> out(directions.size());
    for (auto& o : out) {
      o.blocked = blocked;
      if (blocked) o.blocking_object = "box";
      o.vegetation_attenuation_db = attenuation_db;
      o.vegetation_path_m = attenuation_db > 0.0 ? 5.0 : 0.0;
    }
    return out;
  }
};


ReceiverProfile profile_with_channels(int channels) {
  return parse_profile(skytrace::test::test_profile_yaml(channels), "test.yaml").value();
}

const GnssTime kStart = GnssTime::parse_iso8601("2020-06-25T00:00:00", TimeScale::kGpst).value();
const Geodetic kSite{55.49, 8.46, 60.0};

const orbits::BroadcastEphemerides& ephemerides() {
  static const orbits::BroadcastEphemerides e(orbits::make_nominal_constellation(kStart, 3600.0).value());
  return e;
}

ObservationGenerator make_generator(const ReceiverProfile& profile, bool noise, std::vector<Signal> signals = {}) {
  GeneratorSettings settings;
  settings.signals = signals.empty() ? std::vector<Signal>{Signal::parse("G1C").value(), Signal::parse("E1C").value()} : signals;
  settings.elevation_mask_deg = 0.0;  // the profile's 10 degrees apply
  settings.profile = profile;
  settings.noise = noise;
  settings.seed = 42;
  return ObservationGenerator(settings, ephemerides(), std::make_shared<StaticPosition>(geodetic_to_ecef(kSite)));
}

const SignalMeasurement* find(const EpochObservations& e, const std::string& sat, const char* signal) {
  for (const auto& s : e.satellites) {
    if (s.satellite.to_string() != sat) continue;
    for (const auto& m : s.signals) {
      if (m.signal == Signal::parse(signal).value()) return &m;
    }
  }
  return nullptr;
}

// The highest GPS satellite at the start.
std::string highest_gps(const EpochObservations& e) {
  std::string best;
  double best_el = -90.0;
  for (const auto& s : e.satellites) {
    if (s.satellite.system == GnssSystem::kGps && s.status == SatelliteStatus::kTracked &&
        s.direction.elevation_deg > best_el) {
      best_el = s.direction.elevation_deg;
      best = s.satellite.to_string();
    }
  }
  return best;
}

TEST(TrackingState, AcquisitionLockTimeHalfCyclesAndLossOfLock) {
  auto generator = make_generator(profile_with_channels(0), false);
  SwitchWorld world;
  generator.set_world(&world, LocalFrame{kSite, 0.0});
  std::vector<EpochObservations> epochs;
  for (int i = 0; i < 20; ++i) {
    world.blocked = i == 10;
    epochs.push_back(generator.observe(kStart + static_cast<double>(i)).value());
  }
  const std::string sat = highest_gps(epochs[0]);
  ASSERT_FALSE(sat.empty());
  std::string galileo;
  for (const auto& s : epochs[0].satellites) {
    if (s.satellite.system == GnssSystem::kGalileo && s.status == SatelliteStatus::kTracked) galileo = s.satellite.to_string();
  }
  ASSERT_FALSE(galileo.empty());
  // Tracked from the first epoch (the receiver ran before the scenario): a new arc.
  const SignalMeasurement* first = find(epochs[0], sat, "G1C");
  ASSERT_NE(first, nullptr);
  EXPECT_TRUE(first->loss_of_lock);
  for (int i = 1; i < 10; ++i) {
    const SignalMeasurement* m = find(epochs[i], sat, "G1C");
    ASSERT_NE(m, nullptr) << i;
    EXPECT_FALSE(m->loss_of_lock) << i;
    EXPECT_DOUBLE_EQ(m->lock_time_s, i);
    EXPECT_EQ(m->ambiguity_cycles, first->ambiguity_cycles);
    // C/A carries data: its half cycle is resolved 6 s after acquisition. E1C is a pilot.
    EXPECT_EQ(m->half_cycle_unresolved, i < 6) << i;
    EXPECT_FALSE(find(epochs[i], galileo, "E1C")->half_cycle_unresolved);
  }
  // Blocked at 10; seen again from 11 on, it rose halfway (10.5 s): acquired 3 s later, at 14.
  EXPECT_EQ(find(epochs[10], sat, "G1C"), nullptr);
  for (int i = 11; i < 14; ++i) {
    EXPECT_EQ(find(epochs[i], sat, "G1C"), nullptr) << i;
    for (const auto& s : epochs[i].satellites) {
      if (s.satellite.to_string() == sat) {
        EXPECT_EQ(s.detail, "acquiring");
      }
    }
  }
  const SignalMeasurement* again = find(epochs[14], sat, "G1C");
  ASSERT_NE(again, nullptr);
  EXPECT_TRUE(again->loss_of_lock);
  EXPECT_TRUE(again->half_cycle_unresolved);
  EXPECT_DOUBLE_EQ(again->lock_time_s, 0.0);
  EXPECT_NE(again->ambiguity_cycles, first->ambiguity_cycles);
  EXPECT_DOUBLE_EQ(find(epochs[19], sat, "G1C")->lock_time_s, 5.0);
}

TEST(TrackingState, TracksDownToTheTrackingThresholdButAcquiresOnlyAboveTheAcquisitionThreshold) {
  auto generator = make_generator(profile_with_channels(0), false);
  SwitchWorld world;
  generator.set_world(&world, LocalFrame{kSite, 0.0});
  const auto open = generator.observe(kStart).value();
  const std::string sat = highest_gps(open);
  // 12 dB of foliage: every signal between the thresholds (20 and 40 dB-Hz).
  world.attenuation_db = 12.0;
  const auto shaded = generator.observe(kStart + 1.0).value();
  const SignalMeasurement* m = find(shaded, sat, "G1C");
  ASSERT_NE(m, nullptr) << "a tracked signal keeps tracking below the acquisition threshold";
  EXPECT_NEAR(m->cn0_dbhz, find(open, sat, "G1C")->cn0_dbhz - 12.0, 0.26);
  EXPECT_LT(m->cn0_dbhz, 40.0);
  EXPECT_GT(m->cn0_dbhz, 20.0);
  // Lost once: not acquired again while it stays between the thresholds.
  world.blocked = true;
  (void)generator.observe(kStart + 2.0).value();
  world.blocked = false;
  for (int i = 3; i < 10; ++i) {
    const auto e = generator.observe(kStart + static_cast<double>(i)).value();
    EXPECT_EQ(find(e, sat, "G1C"), nullptr) << i;
    for (const auto& s : e.satellites) {
      if (s.satellite.to_string() == sat) {
        EXPECT_EQ(s.status, SatelliteStatus::kAttenuated);
        EXPECT_EQ(s.detail, "below the acquisition threshold after vegetation");
      }
    }
  }
  // Foliage gone at 10 (taken as 9.5, halfway from the last epoch): acquired 3 s later, at 13.
  world.attenuation_db = 0.0;
  EXPECT_EQ(find(generator.observe(kStart + 10.0).value(), sat, "G1C"), nullptr);
  EXPECT_EQ(find(generator.observe(kStart + 12.0).value(), sat, "G1C"), nullptr);
  EXPECT_NE(find(generator.observe(kStart + 13.0).value(), sat, "G1C"), nullptr);
}

// A semi-codeless channel with its own threshold follows the satellite's L1 C/A channel: under
// foliage that takes L2W below the tracking threshold but leaves L1 C/A tracked, L2W is kept and
// even acquired; with L1 C/A not simulated (nothing to follow) the usual thresholds apply.
TEST(TrackingState, AidedSemicodelessChannelsHoldWhileTheirCaChannelDoes) {
  std::string yaml = skytrace::test::test_profile_yaml(0);
  yaml.replace(yaml.find("signals: [G1C, E1C]"), 19, "signals: [G1C, G2W, E1C]");
  ReceiverProfile profile = parse_profile(yaml, "test.yaml").value();
  profile.semicodeless_threshold_dbhz = 5.0;
  const Signal g1c = Signal::parse("G1C").value(), g2w = Signal::parse("G2W").value();
  SwitchWorld world;
  auto generator = make_generator(profile, false, {g1c, g2w});
  generator.set_world(&world, LocalFrame{kSite, 0.0});
  const std::string sat = highest_gps(generator.observe(kStart).value());
  ASSERT_FALSE(sat.empty());
  // 10 dB of foliage: L1 C/A stays above the 20 dB-Hz tracking threshold, L2W (its squaring loss
  // grows as the signal weakens) falls below it and is kept.
  world.attenuation_db = 10.0;
  const auto shaded = generator.observe(kStart + 1.0).value();
  ASSERT_NE(find(shaded, sat, "G1C"), nullptr);
  const SignalMeasurement* l2w = find(shaded, sat, "G2W");
  ASSERT_NE(l2w, nullptr) << "kept below the tracking threshold while L1 C/A is locked";
  EXPECT_LT(l2w->cn0_dbhz, 20.0);
  EXPECT_GE(l2w->cn0_dbhz, 5.0);
  // Blocked once: L1 C/A is lost and, under the foliage, below its acquisition threshold; L2W
  // has nothing to follow and is not tracked either, until the sky opens and both reacquire.
  world.blocked = true;
  EXPECT_EQ(find(generator.observe(kStart + 2.0).value(), sat, "G2W"), nullptr);
  world.blocked = false;
  for (int i = 3; i < 8; ++i) {
    const auto e = generator.observe(kStart + static_cast<double>(i)).value();
    EXPECT_EQ(find(e, sat, "G1C"), nullptr) << i;
    EXPECT_EQ(find(e, sat, "G2W"), nullptr) << i;
  }
  world.attenuation_db = 0.0;
  const auto reopened = generator.observe(kStart + 13.0).value();
  EXPECT_NE(find(reopened, sat, "G1C"), nullptr);
  EXPECT_NE(find(reopened, sat, "G2W"), nullptr);

  // With no L1 C/A simulated, L2W has nothing to follow: the usual thresholds.
  SwitchWorld shade;
  auto alone = make_generator(profile, false, {g2w});
  alone.set_world(&shade, LocalFrame{kSite, 0.0});
  int reported = 0;
  for (int i = 0; i < 5; ++i) {
    shade.attenuation_db = i == 0 ? 0.0 : 10.0;
    const auto epoch = alone.observe(kStart + static_cast<double>(i)).value();
    for (const auto& s : epoch.satellites) {
      for (const auto& m : s.signals) {
        EXPECT_GE(m.cn0_dbhz, i == 0 ? 40.0 : 20.0) << s.satellite.to_string() << " at " << i;
        ++reported;
      }
    }
  }
  EXPECT_GT(reported, 0);
}

TEST(TrackingState, ChannelsGoToTheHighestSatellites) {
  auto generator = make_generator(profile_with_channels(3), false);
  const auto e = generator.observe(kStart).value();
  int signals = 0;
  double lowest_tracked_deg = 90.0, highest_untracked_deg = -90.0;
  for (const auto& s : e.satellites) {
    signals += static_cast<int>(s.signals.size());
    if (s.status == SatelliteStatus::kTracked) lowest_tracked_deg = std::min(lowest_tracked_deg, s.direction.elevation_deg);
    if (s.status == SatelliteStatus::kNoSignal && s.detail == "no free channel") {
      highest_untracked_deg = std::max(highest_untracked_deg, s.direction.elevation_deg);
    }
  }
  EXPECT_EQ(signals, 3);
  EXPECT_GT(highest_untracked_deg, 10.0);  // satellites above the mask went without a channel
  EXPECT_GT(lowest_tracked_deg, highest_untracked_deg);
}

TEST(TrackingState, CycleSlipsAtLowCn0OnlyAndReproducible) {
  const ReceiverProfile profile = profile_with_channels(0);
  auto count_slips = [&](double attenuation_db, std::vector<std::int64_t>* jumps) {
    auto generator = make_generator(profile, true);
    SwitchWorld world;
    world.attenuation_db = 0.0;
    generator.set_world(&world, LocalFrame{kSite, 0.0});
    std::map<std::string, std::int64_t> last_ambiguity;
    int slips = 0;
    for (int i = 0; i < 300; ++i) {
      world.attenuation_db = i == 0 ? 0.0 : attenuation_db;  // acquired in the open, then shaded
      const auto e = generator.observe(kStart + static_cast<double>(i)).value();
      for (const auto& s : e.satellites) {
        for (const auto& m : s.signals) {
          const std::string key = s.satellite.to_string() + m.signal.to_string();
          const auto previous = last_ambiguity.find(key);
          if (i > 0 && m.loss_of_lock && previous != last_ambiguity.end() && m.ambiguity_cycles != previous->second) {
            ++slips;
            if (jumps != nullptr) jumps->push_back(m.ambiguity_cycles - previous->second);
          }
          last_ambiguity[key] = m.ambiguity_cycles;
        }
      }
    }
    return slips;
  };
  EXPECT_EQ(count_slips(0.0, nullptr), 0);  // about 45 dB-Hz: mean time to slip is astronomical
  std::vector<std::int64_t> jumps, again;
  const int slips = count_slips(23.0, &jumps);  // about 23-26 dB-Hz
  EXPECT_GT(slips, 5);
  for (std::int64_t jump : jumps) {
    EXPECT_GE(std::llabs(jump), 1);
    EXPECT_LE(std::llabs(jump), 5);
  }
  EXPECT_EQ(count_slips(23.0, &again), slips);
  EXPECT_EQ(again, jumps);
}

// Semi-codeless L2W aided by the L1 C/A loop: the L2W phase error follows the C/A loop's (the
// same metres), so the geometry-free combination keeps only the narrow aided loop's noise; the
// C/A signal's own noise is unchanged, and the order the signals are listed in does not matter.
TEST(TrackingState, AidedSemicodelessPhaseFollowsTheCaLoop) {
  auto profile_yaml = [](double aiding_hz) {
    std::string yaml = skytrace::test::test_profile_yaml(0);
    yaml.replace(yaml.find("signals: [G1C, E1C]"), 19, "signals: [G1C, G2W, E1C]");
    if (aiding_hz > 0.0) {
      const std::string pll = "  pll_bandwidth_hz: 15\n";
      yaml.insert(yaml.find(pll) + pll.size(), "  semicodeless_aiding_bandwidth_hz: " + std::to_string(aiding_hz) + "\n");
    }
    return parse_profile(yaml, "test.yaml").value();
  };
  struct Series {
    std::vector<double> l1_m, l2_m;
  };
  auto run = [&](const ReceiverProfile& profile, std::vector<Signal> signals) {
    auto generator = make_generator(profile, true, signals);
    const std::string sat = highest_gps(generator.observe(kStart).value());
    Series out;
    for (int i = 1; i <= 600; ++i) {
      const auto e = generator.observe(kStart + static_cast<double>(i)).value();
      const SignalMeasurement* l1 = find(e, sat, "G1C");
      const SignalMeasurement* l2 = find(e, sat, "G2W");
      if (l1 == nullptr || l2 == nullptr) continue;
      out.l1_m.push_back(l1->phase_noise_m);
      out.l2_m.push_back(l2->phase_noise_m);
    }
    return out;
  };
  auto rms = [](const std::vector<double>& a, const std::vector<double>& b, double b_sign) {
    double sum = 0.0;
    for (std::size_t i = 0; i < a.size(); ++i) sum += std::pow(a[i] + b_sign * b[i], 2);
    return std::sqrt(sum / static_cast<double>(a.size()));
  };
  const std::vector<Signal> ca_first{Signal::parse("G1C").value(), Signal::parse("G2W").value()};
  const std::vector<Signal> w_first{Signal::parse("G2W").value(), Signal::parse("G1C").value()};
  const Series unaided = run(profile_yaml(0.0), ca_first);
  const Series aided = run(profile_yaml(1.0), ca_first);
  ASSERT_GT(unaided.l1_m.size(), 500u);
  ASSERT_EQ(aided.l1_m.size(), unaided.l1_m.size());
  EXPECT_EQ(aided.l1_m, unaided.l1_m);  // the C/A loop is not touched
  const std::vector<double> zero(aided.l1_m.size(), 0.0);
  const double gf_unaided_m = rms(unaided.l1_m, unaided.l2_m, -1.0);
  const double gf_aided_m = rms(aided.l1_m, aided.l2_m, -1.0);
  // Aided, L2W - L1C is the narrow loop's error alone: the unaided L2W loop's at the same C/N0
  // scaled by sqrt(1 Hz / 15 Hz) (at 1 s both loops' errors are white).
  EXPECT_NEAR(gf_aided_m, rms(unaided.l2_m, zero, 1.0) * std::sqrt(1.0 / 15.0), 0.1 * gf_aided_m);
  EXPECT_LT(gf_aided_m, 0.4 * gf_unaided_m) << gf_aided_m << " m against " << gf_unaided_m << " m";
  // And the L2W error carries the C/A error: correlated when aided, not otherwise.
  auto correlation = [&](const Series& x) {
    double xy = 0.0;
    for (std::size_t i = 0; i < x.l1_m.size(); ++i) xy += x.l1_m[i] * x.l2_m[i];
    return xy / static_cast<double>(x.l1_m.size()) / (rms(x.l1_m, zero, 1.0) * rms(x.l2_m, zero, 1.0));
  };
  // (0.26 for this satellite: its block's weaker L2 P(Y) makes the narrow loop's own error 3-4
  // times the C/A loop's.)
  EXPECT_GT(correlation(aided), 0.2);
  EXPECT_LT(std::abs(correlation(unaided)), 0.15);
  // Listed W first, the C/A loop still aids it: the same measurements.
  const Series reordered = run(profile_yaml(1.0), w_first);
  EXPECT_EQ(reordered.l1_m, aided.l1_m);
  EXPECT_EQ(reordered.l2_m, aided.l2_m);
}

TEST(TrackingState, SignalsTheProfileCannotTrackAreLeftOut) {
  auto generator = make_generator(profile_with_channels(0), false,
                                  {Signal::parse("G1C").value(), Signal::parse("G2W").value(), Signal::parse("E1C").value()});
  ASSERT_EQ(generator.untrackable_signals().size(), 1u);
  EXPECT_EQ(generator.untrackable_signals()[0].to_string(), "G2W");
  const auto e = generator.observe(kStart).value();
  for (const auto& s : e.satellites) {
    for (const auto& m : s.signals) EXPECT_NE(m.signal.to_string(), "G2W");
  }
}

TEST(TrackingState, Cn0IsTheLinkBudget) {
  const ReceiverProfile profile = profile_with_channels(0);
  auto generator = make_generator(profile, false);
  const auto e = generator.observe(kStart).value();
  const Eigen::Vector3d receiver_m = geodetic_to_ecef(kSite);
  int checked = 0;
  for (const auto& s : e.satellites) {
    for (const auto& m : s.signals) {
      const double expected = link_budget(profile, *profile.tracked(m.signal), s.satellite_position_m, receiver_m,
                                          s.direction.elevation_deg, s.direction.azimuth_deg, 0.0)
                                  .cn0_dbhz();
      EXPECT_NEAR(m.cn0_dbhz, expected, 0.125 + 1e-9);
      EXPECT_DOUBLE_EQ(m.cn0_dbhz / 0.25, std::round(m.cn0_dbhz / 0.25));
      // With a flat 0 dBic antenna the budget barely depends on elevation: ICD minimum + 3 dB +
      // 203.98 - 1.5 within the 2 dB of the satellite beam and range.
      const double minimum = signal_power_spec(m.signal)->minimum_dbw;
      EXPECT_NEAR(m.cn0_dbhz, minimum + 3.0 + 203.975 - 1.5, 2.5);
      ++checked;
    }
  }
  EXPECT_GT(checked, 10);
}

}  // namespace
}  // namespace skytrace::receiver
