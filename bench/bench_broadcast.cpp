// Broadcast ephemeris evaluation cost: one Keplerian satellite-epoch (orbit, velocity, clock), a
// 15-minute GLONASS propagation, and BroadcastEphemerides::state with selection among a realistic
// number of records. Times vary from call to call so nothing can be hoisted out of the loop.
#include <benchmark/benchmark.h>

#include <cstdint>

#include "skytrace/orbits/broadcast.hpp"

namespace {

using namespace skytrace;
using namespace skytrace::orbits;

// A GPS LNAV record (G07 of 2020-06-25 12:00 GPST) as a template for the others.
KeplerEphemeris gps_record() {
  KeplerEphemeris e;
  e.satellite = SatelliteId{GnssSystem::kGps, 7};
  e.toc = GnssTime::from_week_tow(TimeScale::kGpst, 2111, 388800.0);
  e.toe = e.toc;
  e.af0_s = -3.125914372504e-04;
  e.af1_s_per_s = -8.753886504564e-12;
  e.crs_m = 0.375;
  e.delta_n_rad_per_s = 5.106998441270e-09;
  e.m0_rad = -2.196298569634;
  e.cuc_rad = -2.980232238770e-07;
  e.eccentricity = 1.403154002037e-02;
  e.cus_rad = 5.675479769707e-06;
  e.sqrt_a_sqrtm = 5.153651992798e+03;
  e.cic_rad = 2.533197402954e-07;
  e.omega0_rad = -5.655694076531e-01;
  e.cis_rad = -8.381903171539e-08;
  e.i0_rad = 9.530046994424e-01;
  e.crc_m = 262.96875;
  e.omega_rad = -2.385949900139;
  e.omega_dot_rad_per_s = -8.173197589343e-09;
  e.idot_rad_per_s = 1.078616357272e-10;
  e.group_delays.tgd_s = -1.117587089539e-08;
  e.fit_interval_h = 4.0;
  return e;
}

void BM_EvaluateKepler(benchmark::State& state) {
  const KeplerEphemeris eph = gps_record();
  std::uint32_t i = 0;
  for (auto _ : state) {
    const GnssTime t = eph.toe + (static_cast<double>(i++ % 14400) - 7200.0) * 0.999;
    SatelliteState s = evaluate_kepler(eph, t);
    benchmark::DoNotOptimize(s);
  }
}
BENCHMARK(BM_EvaluateKepler);

void BM_EvaluateKeplerBeidouGeo(benchmark::State& state) {
  KeplerEphemeris eph = gps_record();
  eph.satellite = SatelliteId{GnssSystem::kBeiDou, 3};
  eph.sqrt_a_sqrtm = 6493.0;
  eph.i0_rad = 0.065;
  std::uint32_t i = 0;
  for (auto _ : state) {
    const GnssTime t = eph.toe + (static_cast<double>(i++ % 14400) - 7200.0) * 0.999;
    SatelliteState s = evaluate_kepler(eph, t);
    benchmark::DoNotOptimize(s);
  }
}
BENCHMARK(BM_EvaluateKeplerBeidouGeo);

void BM_EvaluateGlonass15Minutes(benchmark::State& state) {
  GlonassEphemeris eph;
  eph.satellite = SatelliteId{GnssSystem::kGlonass, 2};
  eph.toe = GnssTime::from_calendar(CalendarTime{2020, 6, 25, 12, 15, 0.0}, TimeScale::kUtc);
  eph.position_m = Eigen::Vector3d(-9983247.070312, 5047906.738281, 22965040.52734);
  eph.velocity_mps = Eigen::Vector3d(-2054.879188538, -2364.778518677, -379.1494369507);
  eph.acceleration_mps2 = Eigen::Vector3d(9.3e-7, 0.0, -2.79e-6);
  std::uint32_t i = 0;
  for (auto _ : state) {
    const GnssTime t = eph.toe + 900.0 - static_cast<double>(i++ % 16) * 0.25;
    SatelliteState s = evaluate_glonass(eph, t);
    benchmark::DoNotOptimize(s);
  }
}
BENCHMARK(BM_EvaluateGlonass15Minutes);

// 100 satellites (32 GPS, 36 Galileo, 32 BeiDou MEO/IGSO numbers) with 12 records each, toes every
// 2 h across a day; state() picks the record and evaluates it.
void BM_BroadcastStateWithSelection(benchmark::State& state) {
  NavigationData data;
  const KeplerEphemeris base = gps_record();
  const GnssTime day = GnssTime::from_week_tow(TimeScale::kGpst, 2111, 345600.0);
  std::vector<SatelliteId> satellites;
  auto add_system = [&](GnssSystem system, int count, int first, NavMessage message) {
    for (int n = first; n < first + count; ++n) {
      const SatelliteId id{system, static_cast<std::uint8_t>(n)};
      satellites.push_back(id);
      for (int r = 0; r < 12; ++r) {
        KeplerEphemeris e = base;
        e.satellite = id;
        e.message = message;
        e.toe = day + r * 7200.0;
        e.toc = e.toe;
        e.m0_rad += 0.3 * n + 0.01 * r;
        e.omega0_rad += 0.7 * n;
        data.kepler.push_back(e);
      }
    }
  };
  add_system(GnssSystem::kGps, 32, 1, NavMessage::kGpsLnav);
  add_system(GnssSystem::kGalileo, 36, 1, NavMessage::kGalileoInav);
  add_system(GnssSystem::kBeiDou, 32, 6, NavMessage::kBeiDouD1);
  const BroadcastEphemerides ephemerides(std::move(data));
  std::uint32_t i = 0;
  for (auto _ : state) {
    const SatelliteId& id = satellites[i % satellites.size()];
    const GnssTime t = day + static_cast<double>((i * 37) % 86400);
    ++i;
    auto s = ephemerides.state(id, t);
    benchmark::DoNotOptimize(s);
  }
}
BENCHMARK(BM_BroadcastStateWithSelection);

}  // namespace

BENCHMARK_MAIN();
