// ObservationGenerator::observe_batch: the satellites' stage 1 split among threads gives the very
// observations of observe() epoch by epoch, and errors arrive as observe() would meet them.
#include <gtest/gtest.h>

#include <cstring>
#include <functional>
#include <thread>
#include <vector>

#include "skytrace/orbits/nominal.hpp"
#include "skytrace/receiver/observation_generator.hpp"

namespace skytrace::receiver {
namespace {

const GnssTime& start() {
  static const GnssTime t = GnssTime::parse_iso8601("2020-06-25T00:00:00", TimeScale::kGpst).value();
  return t;
}

const orbits::BroadcastEphemerides& ephemerides() {
  static const orbits::BroadcastEphemerides e(orbits::make_nominal_constellation(start(), 3600.0).value());
  return e;
}

// Every constellation with a nominal one, noise and a wandering clock: GLONASS records go through
// the integration cache, every satellite keeps a flight-time guess from epoch to epoch.
std::unique_ptr<ObservationGenerator> make_generator() {
  GeneratorSettings settings;
  for (const char* code : {"G1C", "G2W", "R1C", "E1C", "E5Q", "C2I", "J1C"}) settings.signals.push_back(Signal::parse(code).value());
  settings.profile = builtin_profile("septentrio-polarx5").value();
  settings.noise = true;
  settings.ideal_clock = false;
  settings.seed = 11;
  settings.elevation_mask_deg = 0.0;
  return std::make_unique<ObservationGenerator>(settings, ephemerides(),
                                                std::make_shared<StaticPosition>(geodetic_to_ecef(Geodetic{55.49, 8.46, 60.0})));
}

// Runs each share on a thread of its own.
void run_on_threads(const std::function<void(size_t)>& work, size_t shares) {
  std::vector<std::thread> threads;
  for (size_t s = 1; s < shares; ++s) threads.emplace_back([&work, s] { work(s); });
  work(0);
  for (auto& t : threads) t.join();
}

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

void expect_same(const EpochObservations& a, const EpochObservations& b, const std::string& where) {
  ASSERT_EQ(a.satellites.size(), b.satellites.size()) << where;
  EXPECT_TRUE(same_bits(a.true_time - b.true_time, 0.0)) << where;
  for (size_t i = 0; i < a.satellites.size(); ++i) {
    const SatelliteObservation& x = a.satellites[i];
    const SatelliteObservation& y = b.satellites[i];
    const std::string here = where + " " + x.satellite.to_string();
    ASSERT_EQ(x.satellite, y.satellite) << here;
    EXPECT_EQ(x.status, y.status) << here;
    EXPECT_EQ(x.detail, y.detail) << here;
    EXPECT_TRUE(same_bits(x.range_m, y.range_m)) << here;
    EXPECT_TRUE(same_bits(x.direction.elevation_deg, y.direction.elevation_deg)) << here;
    EXPECT_TRUE(same_bits(x.ionosphere_l1_m, y.ionosphere_l1_m)) << here;
    EXPECT_TRUE(same_bits(x.satellite_clock_m, y.satellite_clock_m)) << here;
    ASSERT_EQ(x.signals.size(), y.signals.size()) << here;
    for (size_t k = 0; k < x.signals.size(); ++k) {
      EXPECT_TRUE(same_bits(x.signals[k].pseudorange_m, y.signals[k].pseudorange_m)) << here;
      EXPECT_TRUE(same_bits(x.signals[k].carrier_phase_cycles, y.signals[k].carrier_phase_cycles)) << here;
      EXPECT_TRUE(same_bits(x.signals[k].doppler_hz, y.signals[k].doppler_hz)) << here;
      EXPECT_TRUE(same_bits(x.signals[k].cn0_dbhz, y.signals[k].cn0_dbhz)) << here;
      EXPECT_EQ(x.signals[k].loss_of_lock, y.signals[k].loss_of_lock) << here;
    }
  }
}

TEST(GeneratorBatch, SatellitesSplitAmongThreadsGiveTheObservationsOfOneEpochAtATime) {
  constexpr int kEpochs = 40;
  std::vector<GnssTime> tags;
  for (int k = 0; k < kEpochs; ++k) tags.push_back(start() + 30.0 * k);
  auto serial = make_generator();
  std::vector<EpochObservations> expected(kEpochs);
  for (int k = 0; k < kEpochs; ++k) ASSERT_TRUE(serial->observe(tags[k], expected[k]).ok());
  size_t tracked = 0;
  for (const auto& e : expected) {
    for (const auto& s : e.satellites) tracked += s.status == SatelliteStatus::kTracked ? 1 : 0;
  }
  ASSERT_GT(tracked, 20U * kEpochs);

  for (const size_t shares : {1U, 2U, 3U, 7U}) {
    auto batched = make_generator();
    batched->set_geometry_shares(shares);
    std::vector<EpochObservations> got(kEpochs);
    // Batches of uneven sizes; the storage of the first batch reused by a later one.
    for (size_t first = 0, size = 1; first < kEpochs; first += size, size = size % 9 + 2) {
      const size_t count = std::min<size_t>(size, kEpochs - first);
      std::vector<GnssTime> batch_tags(tags.begin() + first, tags.begin() + first + count);
      std::vector<EpochObservations*> epochs;
      for (size_t j = 0; j < count; ++j) epochs.push_back(&got[first + j]);
      const Status st =
          batched->observe_batch(batch_tags, epochs, [shares](const std::function<void(size_t)>& work) { run_on_threads(work, shares); });
      ASSERT_TRUE(st.ok()) << st.error().message;
    }
    for (int k = 0; k < kEpochs; ++k) expect_same(expected[k], got[k], std::to_string(shares) + " shares, epoch " + std::to_string(k));
  }
}

TEST(GeneratorBatch, AnEpochOutOfOrderEndsTheBatchThereAfterTheEpochsBeforeIt) {
  auto serial = make_generator();
  std::vector<EpochObservations> expected(2);
  ASSERT_TRUE(serial->observe(start(), expected[0]).ok());
  ASSERT_TRUE(serial->observe(start() + 1.0, expected[1]).ok());
  const auto serial_error = serial->observe(start() + 1.0, expected[1]);

  auto batched = make_generator();
  batched->set_geometry_shares(3);
  std::vector<EpochObservations> got(3);
  const Status st = batched->observe_batch({start(), start() + 1.0, start() + 1.0}, {&got[0], &got[1], &got[2]},
                                           [](const std::function<void(size_t)>& work) { run_on_threads(work, 3); });
  ASSERT_FALSE(st.ok());
  ASSERT_FALSE(serial_error.ok());
  EXPECT_EQ(st.error().message, serial_error.error().message);
  expect_same(expected[0], got[0], "epoch 0");
  expect_same(expected[1], got[1], "epoch 1");
}

}  // namespace
}  // namespace skytrace::receiver
