// RTK engine cost per epoch: the real ESBC recording (GPS, Galileo, BeiDou, GLONASS; about 30
// satellites in the double differences, every frequency tracked) as both rover and base (a zero
// baseline: the arithmetic is that of any baseline), with its broadcast navigation file. Includes
// both receivers' single-point fixes, slip detection, the filter update and LAMBDA.
#include <benchmark/benchmark.h>

#include <filesystem>
#include <memory>

#include "bench_support.hpp"
#include "skytrace/positioning/rtk.hpp"

namespace {

using namespace skytrace;

// The ESBC hour with two frequencies per system, as most RTK receivers track: L1/L2, E1/E5a,
// B1I/B2I, G1/G2; the header position is the base's.
struct Data {
  const bench::EsbcFirstHour* hour = nullptr;
  std::vector<positioning::EpochMeasurements> epochs;
  Eigen::Vector3d base_m = Eigen::Vector3d::Zero();
  std::string error;
};

const Data& data() {
  static const Data d = [] {
    Data out;
    out.hour = &bench::esbc_first_hour();
    out.error = out.hour->error.empty() && !out.hour->approx_position_m ? "no header position" : out.hour->error;
    if (!out.error.empty()) return out;
    for (positioning::EpochMeasurements m : out.hour->epochs) {
      std::erase_if(m.signals, [](const positioning::SignalMeasurement& s) {
        const char band = s.signal.band;
        switch (s.signal.system) {
          case GnssSystem::kGalileo: return band != '1' && band != '5';
          case GnssSystem::kBeiDou: return band != '2' && band != '7';
          default: return band != '1' && band != '2';
        }
      });
      out.epochs.push_back(std::move(m));
    }
    out.base_m = *out.hour->approx_position_m;
    return out;
  }();
  return d;
}

// Argument: systems (1: GPS + Galileo, 2: GPS + Galileo + BeiDou + GLONASS).
void BM_RtkEpoch(benchmark::State& state) {
  const Data& d = data();
  if (!d.error.empty()) {
    state.SkipWithError(d.error.c_str());
    return;
  }
  positioning::RtkSettings settings;
  settings.systems = {GnssSystem::kGps, GnssSystem::kGalileo};
  if (state.range(0) == 2) {
    settings.systems.push_back(GnssSystem::kBeiDou);
    settings.systems.push_back(GnssSystem::kGlonass);
  }
  settings.single_point.systems = settings.systems;
  positioning::RtkEngine engine(*d.hour->ephemerides, settings, d.hour->klobuchar);
  std::vector<positioning::BaseEpoch> bases;
  for (const auto& e : d.epochs) bases.push_back(positioning::BaseEpoch{e, d.base_m});
  size_t i = 0, satellites = 0, fixed = 0, solved = 0;
  for (auto _ : state) {
    const size_t k = i++ % d.epochs.size();
    auto fix = engine.solve(d.epochs[k], &bases[k]);
    if (fix) {
      satellites += static_cast<size_t>(fix->satellites_used);
      fixed += fix->type == positioning::FixType::kRtkFixed ? 1 : 0;
      ++solved;
    }
    benchmark::DoNotOptimize(fix);
  }
  state.counters["satellites"] = solved ? static_cast<double>(satellites) / static_cast<double>(solved) : 0.0;
  state.counters["fixed_share"] = solved ? static_cast<double>(fixed) / static_cast<double>(solved) : 0.0;
}
BENCHMARK(BM_RtkEpoch)->Arg(1)->Arg(2)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
