// A receiver that outputs a satellite only once it holds a broadcast ephemeris for it (profile key
// tracking.output_requires_ephemeris): decode times, transmission times on the timeline (GLONASS in
// UTC, BeiDou in BDT, unknown values), the rule of receiver/ephemeris_decoding.hpp, and the
// generator: warm start, a rising satellite tracked but not output until then, re-acquisition.
#include <gtest/gtest.h>

#include <map>
#include <set>

#include "skytrace/orbits/nominal.hpp"
#include "skytrace/receiver/ephemeris_decoding.hpp"
#include "skytrace/receiver/observation_generator.hpp"
#include "test_support.hpp"

namespace skytrace::receiver {
namespace {

using orbits::NavMessage;

GnssTime gpst(const char* iso) { return GnssTime::parse_iso8601(iso, TimeScale::kGpst).value(); }
GnssTime utc(const char* iso) { return GnssTime::parse_iso8601(iso, TimeScale::kUtc).value(); }
Signal sig(const char* code) { return Signal::parse(code).value(); }

// A healthy record with toe at `toe` (GPST) transmitted at `transmitted_sow` of toe's week.
orbits::KeplerEphemeris kepler(const char* sat, NavMessage message, const GnssTime& toe, double transmitted_sow) {
  orbits::KeplerEphemeris e;
  e.satellite = SatelliteId::parse(sat).value();
  e.message = message;
  const TimeScale scale = e.satellite.system == GnssSystem::kBeiDou ? TimeScale::kBdt : TimeScale::kGpst;
  const WeekTow wt = toe.to_week_tow(scale);
  e.toe = e.toc = toe;
  e.week = wt.week;
  e.toe_sow = wt.tow_s;
  e.fit_interval_h = 4.0;
  e.data_source = message == NavMessage::kGalileoFnav ? 258 : 513;
  e.transmission_time_sow = transmitted_sow;
  return e;
}

double sow(const GnssTime& t) { return t.to_week_tow(TimeScale::kGpst).tow_s; }

TEST(EphemerisDecoding, DecodeTimesFollowTheMessageStructure) {
  EXPECT_EQ(orbits::ephemeris_decode_time_s(NavMessage::kGpsLnav), 30.0);
  EXPECT_EQ(orbits::ephemeris_decode_time_s(NavMessage::kQzssLnav), 30.0);
  EXPECT_EQ(orbits::ephemeris_decode_time_s(NavMessage::kGalileoInav), 30.0);
  EXPECT_EQ(orbits::ephemeris_decode_time_s(NavMessage::kGalileoFnav), 50.0);
  EXPECT_EQ(orbits::ephemeris_decode_time_s(NavMessage::kBeiDouD1), 30.0);
  EXPECT_EQ(orbits::ephemeris_decode_time_s(NavMessage::kBeiDouD2), 30.0);  // 10 pages, one per 3-s frame
  EXPECT_EQ(orbits::ephemeris_decode_time_s(NavMessage::kGlonassFdma), 30.0);
  EXPECT_EQ(orbits::ephemeris_decode_time_s(NavMessage::kNavicLnav), 48.0);
  EXPECT_EQ(orbits::ephemeris_decode_time_s(NavMessage::kSbas), 12.0);
  EXPECT_EQ(orbits::ephemeris_decode_time_s(NavMessage::kGpsCnav), 48.0);
}

TEST(EphemerisDecoding, SignalsCarryTheirMessages) {
  EXPECT_TRUE(orbits::signal_carries(sig("G1C"), NavMessage::kGpsLnav));
  EXPECT_FALSE(orbits::signal_carries(sig("G2W"), NavMessage::kGpsLnav));  // P(Y) is encrypted
  EXPECT_TRUE(orbits::signal_carries(sig("G5Q"), NavMessage::kGpsCnav));
  EXPECT_FALSE(orbits::signal_carries(sig("J1C"), NavMessage::kGpsLnav));  // QZSS has its own
  EXPECT_TRUE(orbits::signal_carries(sig("E1C"), NavMessage::kGalileoInav));
  EXPECT_FALSE(orbits::signal_carries(sig("E1C"), NavMessage::kGalileoFnav));
  EXPECT_TRUE(orbits::signal_carries(sig("E5Q"), NavMessage::kGalileoFnav));
  EXPECT_TRUE(orbits::signal_carries(sig("E8X"), NavMessage::kGalileoFnav));
  EXPECT_TRUE(orbits::signal_carries(sig("C2I"), NavMessage::kBeiDouD2));
  EXPECT_FALSE(orbits::signal_carries(sig("C1P"), NavMessage::kBeiDouD1));
  EXPECT_TRUE(orbits::signal_carries(sig("R2C"), NavMessage::kGlonassFdma));
}

TEST(EphemerisDecoding, KeplerTransmissionTimesOnTheTimeline) {
  const GnssTime toe = gpst("2024-05-03T02:00:00");
  // NYA1's G10: toe 02:00, transmitted 434736 s of the week = 00:45:36.
  auto e = kepler("G10", NavMessage::kGpsLnav, toe, 434736.0);
  EXPECT_EQ(orbits::transmission_time(e).value(), gpst("2024-05-03T00:45:36"));
  // Adjusted to the record's week by -604800 (RINEX), or left unadjusted: the same instant.
  auto sunday = kepler("G10", NavMessage::kGpsLnav, gpst("2024-05-05T01:00:00"), -3600.0);
  EXPECT_EQ(orbits::transmission_time(sunday).value(), gpst("2024-05-04T23:00:00"));
  sunday.transmission_time_sow = 604800.0 - 3600.0;
  EXPECT_EQ(orbits::transmission_time(sunday).value(), gpst("2024-05-04T23:00:00"));
  // BeiDou: seconds of the BDT week (BDT = GPST - 14 s).
  auto c = kepler("C20", NavMessage::kBeiDouD1, toe, 0.0);
  c.transmission_time_sow = toe.to_week_tow(TimeScale::kBdt).tow_s - 600.0;
  EXPECT_EQ(orbits::transmission_time(c).value(), toe - 600.0);
  // Unknown: RINEX 0.9999E9, blank (stored as that), 0 (writers without the value).
  e.transmission_time_sow = 0.9999e9;
  EXPECT_FALSE(orbits::transmission_time(e));
  e.transmission_time_sow = 0.0;
  EXPECT_FALSE(orbits::transmission_time(e));
}

TEST(EphemerisDecoding, GlonassFrameTimeCountsTheUtcDay) {
  orbits::GlonassEphemeris g;
  g.satellite = SatelliteId::parse("R05").value();
  g.toe = utc("2024-05-03T00:15:00");
  g.message_frame_time_s = 0.0;  // a frame at 00:00:00 UTC (18 s after 00:00:00 GPST)
  EXPECT_EQ(orbits::transmission_time(g).value(), utc("2024-05-03T00:00:00"));
  EXPECT_EQ(orbits::transmission_time(g).value(), gpst("2024-05-03T00:00:18"));
  g.message_frame_time_s = 86370.0;  // 23:59:30 UTC of the day before
  EXPECT_EQ(orbits::transmission_time(g).value(), utc("2024-05-02T23:59:30"));
  g.toe = utc("2024-05-03T23:45:00");
  g.message_frame_time_s = 23.0 * 3600 + 30 * 60;
  EXPECT_EQ(orbits::transmission_time(g).value(), utc("2024-05-03T23:30:00"));
  g.message_frame_time_s = orbits::kUnknownTransmissionTime_s;
  EXPECT_FALSE(orbits::transmission_time(g));
}

class HeldFrom : public ::testing::Test {
 protected:
  std::optional<GnssTime> held(const std::vector<const char*>& signals) {
    std::vector<Signal> s;
    for (const char* code : signals) s.push_back(sig(code));
    const orbits::BroadcastEphemerides e(data);
    return ephemeris_held_from(e, sat, acquired, s);
  }
  orbits::NavigationData data;
  SatelliteId sat = SatelliteId::parse("G10").value();
  GnssTime acquired = gpst("2024-05-03T00:20:17");
};

TEST_F(HeldFrom, RisingSatelliteWaitsForTheDecodeTime) {
  // Transmitted long before the acquisition (a merged broadcast file): repeated since.
  data.kepler.push_back(kepler("G10", NavMessage::kGpsLnav, gpst("2024-05-03T02:00:00"), sow(gpst("2024-05-03T00:00:18"))));
  EXPECT_EQ(held({"G1C", "G2W"}).value(), acquired + 30.0);
}

TEST_F(HeldFrom, WaitsForALaterTransmission) {
  // NYA1's G10: its first record went out at 00:45:36; the previous record expired before.
  data.kepler.push_back(kepler("G10", NavMessage::kGpsLnav, gpst("2024-05-02T22:00:00"), sow(gpst("2024-05-02T20:00:18"))));
  data.kepler.push_back(kepler("G10", NavMessage::kGpsLnav, gpst("2024-05-03T02:00:00"), sow(gpst("2024-05-03T00:45:36"))));
  data.kepler.push_back(kepler("G10", NavMessage::kGpsLnav, gpst("2024-05-03T04:00:00"), sow(gpst("2024-05-03T02:00:18"))));
  EXPECT_EQ(held({"G1C"}).value(), gpst("2024-05-03T00:45:36"));
  // Still valid at the acquisition, the earlier record is held after the decode time.
  acquired = gpst("2024-05-02T23:59:00");
  EXPECT_EQ(held({"G1C"}).value(), acquired + 30.0);
}

TEST_F(HeldFrom, UnknownOrImpossibleTransmissionTimeFallsBackToTheDecodeTime) {
  data.kepler.push_back(kepler("G10", NavMessage::kGpsLnav, gpst("2024-05-03T02:00:00"), orbits::kUnknownTransmissionTime_s));
  EXPECT_EQ(held({"G1C"}).value(), acquired + 30.0);
  // After the end of the record's validity (toe + 2 h): a wrong field.
  data.kepler.front().transmission_time_sow = sow(gpst("2024-05-03T04:30:00"));
  EXPECT_EQ(held({"G1C"}).value(), acquired + 30.0);
  data.kepler.front().transmission_time_sow = sow(gpst("2024-05-03T01:30:00"));
  EXPECT_EQ(held({"G1C"}).value(), gpst("2024-05-03T01:30:00"));
}

TEST_F(HeldFrom, OnlyMessagesTheTrackedSignalsCarry) {
  sat = SatelliteId::parse("E10").value();
  const GnssTime toe = gpst("2024-05-03T00:20:00");
  data.kepler.push_back(kepler("E10", NavMessage::kGalileoFnav, toe, sow(gpst("2024-05-03T00:21:00"))));
  data.kepler.push_back(kepler("E10", NavMessage::kGalileoInav, toe, sow(gpst("2024-05-03T00:33:25"))));
  EXPECT_EQ(held({"E1C"}).value(), gpst("2024-05-03T00:33:25"));       // I/NAV only
  EXPECT_EQ(held({"E1C", "E5Q"}).value(), acquired + 50.0);            // F/NAV: decoded after 50 s
  // A file without the receiver's message: the other message's decode time, its transmission unused.
  data.kepler.pop_back();
  EXPECT_EQ(held({"E1C"}).value(), acquired + 50.0);
  // Nothing valid at or after the acquisition: nothing to decode.
  acquired = gpst("2024-05-03T05:00:00");
  EXPECT_FALSE(held({"E1C"}));
}

TEST_F(HeldFrom, GlonassTransmissionIsUtc) {
  sat = SatelliteId::parse("R05").value();
  orbits::GlonassEphemeris g;
  g.satellite = sat;
  g.toe = utc("2024-05-03T01:15:00");
  g.message_frame_time_s = 3600.0;  // 01:00:00 UTC = 01:00:18 GPST
  data.glonass.push_back(g);
  acquired = gpst("2024-05-03T00:59:40");
  // Read as GPST seconds of day it would be 01:00:10 (the decode time); as UTC it is later.
  EXPECT_EQ(held({"R1C"}).value(), gpst("2024-05-03T01:00:18"));
}

// ------------------------------------------------------------------------------------- generator


const GnssTime kStart = gpst("2020-06-25T00:00:00");
const Geodetic kSite{55.49, 8.46, 60.0};

const orbits::BroadcastEphemerides& nominal() {
  static const orbits::BroadcastEphemerides e(orbits::make_nominal_constellation(kStart, 7200.0).value());
  return e;
}

// The same records, all first transmitted 10 minutes after the start (those expiring before that
// left out: a record transmitted after its validity would be a wrong field, taken as unknown).
const orbits::BroadcastEphemerides& nominal_transmitted_late() {
  static const orbits::BroadcastEphemerides e([] {
    orbits::NavigationData data = orbits::make_nominal_constellation(kStart, 7200.0).value();
    std::erase_if(data.kepler, [](const orbits::KeplerEphemeris& r) {
      return r.toe + orbits::validity_half_window_s(r) < kStart + 600.0;
    });
    for (auto& r : data.kepler) {
      const TimeScale scale = r.satellite.system == GnssSystem::kBeiDou ? TimeScale::kBdt : TimeScale::kGpst;
      r.transmission_time_sow = (kStart + 600.0).to_week_tow(scale).tow_s;
    }
    return data;
  }());
  return e;
}

// Everything blocked while `blocked` is set.
class SwitchWorld final : public PathQuery {
 public:
  bool blocked = false;
  std::vector<RayOutcome> trace(const Eigen::Vector3d&, const std::vector<Eigen::Vector3d>& directions) const override {
    std::vector<RayOutcome> out(directions.size());
    for (auto& o : out) {
      o.blocked = blocked;
      if (blocked) o.blocking_object = "box";
    }
    return out;
  }
};

// Epochs every 10 s for `count` epochs, with the world blocked at the epochs in `blocked`.
std::vector<EpochObservations> run(bool output_requires_ephemeris, int count, const std::set<int>& blocked = {},
                                   std::set<const orbits::KeplerEphemeris*>* used = nullptr,
                                   const orbits::BroadcastEphemerides& ephemerides = nominal()) {
  const std::string text = skytrace::test::test_profile_yaml(0, output_requires_ephemeris);
  GeneratorSettings settings;
  settings.signals = {sig("G1C"), sig("E1C")};
  settings.elevation_mask_deg = 0.0;
  settings.profile = parse_profile(text, "test.yaml").value();
  settings.noise = true;
  settings.seed = 42;
  ObservationGenerator generator(settings, ephemerides, std::make_shared<StaticPosition>(geodetic_to_ecef(kSite)));
  SwitchWorld world;
  generator.set_world(&world, LocalFrame{kSite, 0.0});
  std::vector<EpochObservations> epochs;
  for (int i = 0; i < count; ++i) {
    world.blocked = blocked.count(i) > 0;
    epochs.push_back(generator.observe(kStart + 10.0 * i).value());
  }
  if (used != nullptr) *used = generator.used_kepler();
  return epochs;
}

const SatelliteObservation* find(const EpochObservations& e, const SatelliteId& sat) {
  for (const auto& s : e.satellites) {
    if (s.satellite == sat) return &s;
  }
  return nullptr;
}

// First epoch index at which `sat` is output, or -1.
int first_output(const std::vector<EpochObservations>& epochs, const SatelliteId& sat) {
  for (size_t i = 0; i < epochs.size(); ++i) {
    const SatelliteObservation* s = find(epochs[i], sat);
    if (s != nullptr && s->status == SatelliteStatus::kTracked) return static_cast<int>(i);
  }
  return -1;
}

TEST(GeneratorEphemerisDecoding, WarmStartOutputsWhatIsTrackedAtTheFirstEpoch) {
  // Even with every record first transmitted after the start: the receiver ran before and holds
  // the ephemerides of what it tracks.
  const auto with = run(true, 1, {}, nullptr, nominal_transmitted_late());
  const auto without = run(false, 1, {}, nullptr, nominal_transmitted_late());
  int tracked = 0;
  for (const auto& s : without[0].satellites) {
    const SatelliteObservation* w = find(with[0], s.satellite);
    ASSERT_NE(w, nullptr);
    EXPECT_EQ(w->status, s.status) << s.satellite.to_string();
    EXPECT_EQ(w->signals.size(), s.signals.size());
    tracked += s.status == SatelliteStatus::kTracked;
  }
  EXPECT_GT(tracked, 8);
}

TEST(GeneratorEphemerisDecoding, RisingSatelliteIsTrackedButOutputOnlyAfterTheDecodeTime) {
  constexpr int kEpochs = 720;  // 2 h at 10 s
  std::set<const orbits::KeplerEphemeris*> used;
  const auto with = run(true, kEpochs, {}, &used);
  const auto without = run(false, kEpochs);
  // Satellites that rise during the run (not tracked at the start): nominal records are
  // transmitted before they rise, so the decode time governs. A signal above the threshold from
  // halfway between epochs (5 s), acquired 3 s later: held from acquisition + 30 s = 38 s after
  // the epoch before the first tracked one, i.e. the 4th epoch after it.
  int rising = 0;
  for (const SatelliteId& sat : nominal().satellites()) {
    if (sat.system != GnssSystem::kGps && sat.system != GnssSystem::kGalileo) continue;
    const int first = first_output(without, sat);
    if (first <= 0) continue;
    ++rising;
    SCOPED_TRACE(sat.to_string());
    ASSERT_EQ(first_output(with, sat), first + 3);
    for (int i = first; i < first + 3; ++i) {
      const SatelliteObservation* s = find(with[static_cast<size_t>(i)], sat);
      EXPECT_EQ(s->status, SatelliteStatus::kNoEphemeris);
      EXPECT_TRUE(s->waiting_for_ephemeris);
      EXPECT_TRUE(s->signals.empty());
      EXPECT_GT(s->direction.elevation_deg, 10.0);  // the geometry is known
      EXPECT_NE(s->detail.find("not yet decoded"), std::string::npos) << s->detail;
    }
    // From then on the same measurements as a receiver that outputs at once: the channel, the
    // arc, the lock time and the noise streams ran while it waited. The first output starts the
    // user's arc (loss of lock), with 30 s of lock time behind it.
    const size_t at = static_cast<size_t>(first + 3);
    const SatelliteObservation* w = find(with[at], sat);
    const SatelliteObservation* o = find(without[at], sat);
    ASSERT_EQ(w->signals.size(), o->signals.size());
    ASSERT_FALSE(w->signals.empty());
    for (size_t k = 0; k < w->signals.size(); ++k) {
      EXPECT_TRUE(w->signals[k].loss_of_lock);
      EXPECT_FALSE(o->signals[k].loss_of_lock);
      EXPECT_DOUBLE_EQ(w->signals[k].lock_time_s, 30.0);
      EXPECT_EQ(w->signals[k].lock_time_s, o->signals[k].lock_time_s);
      EXPECT_EQ(w->signals[k].pseudorange_m, o->signals[k].pseudorange_m);
      EXPECT_EQ(w->signals[k].carrier_phase_cycles, o->signals[k].carrier_phase_cycles);
      EXPECT_EQ(w->signals[k].half_cycle_unresolved, o->signals[k].half_cycle_unresolved);
    }
  }
  EXPECT_GE(rising, 2);
  // The navigation file lists only records of satellites that were output.
  for (const orbits::KeplerEphemeris* e : used) {
    EXPECT_GE(first_output(with, e->satellite), 0) << e->satellite.to_string();
  }
}

TEST(GeneratorEphemerisDecoding, ReacquisitionKeepsTheEphemeris) {
  // Everything blocked for one epoch after half an hour: every satellite is acquired again, and
  // output at once as by a receiver without the rule (none waits for its navigation message).
  const auto with = run(true, 200, {180});
  const auto without = run(false, 200, {180});
  int reacquired = 0;
  for (const auto& s : without[181].satellites) {
    const SatelliteObservation* w = find(with[181], s.satellite);
    ASSERT_NE(w, nullptr);
    EXPECT_EQ(w->status, s.status) << s.satellite.to_string();
    if (s.status == SatelliteStatus::kTracked) {
      ++reacquired;
      EXPECT_TRUE(w->signals.front().loss_of_lock);
    }
  }
  EXPECT_GT(reacquired, 8);
}

TEST(GeneratorEphemerisDecoding, LostBeforeDecodingStartsOver) {
  const auto without = run(false, 720);
  for (const SatelliteId& sat : nominal().satellites()) {
    const int first = first_output(without, sat);
    if (first <= 0) continue;
    // Blocked at the second epoch of its wait: acquired again at the next, decoding from there.
    const auto with = run(true, first + 8, {first + 1});
    SCOPED_TRACE(sat.to_string());
    EXPECT_EQ(first_output(with, sat), first + 2 + 3);
    return;
  }
  FAIL() << "no rising satellite";
}

}  // namespace
}  // namespace skytrace::receiver
