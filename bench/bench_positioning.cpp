// Single-point positioning cost per epoch: the real ESBC recording (GPS, GLONASS, Galileo,
// BeiDou: about 35 satellites per epoch) with its broadcast navigation file.
#include <benchmark/benchmark.h>

#include <filesystem>
#include <memory>

#include "skytrace/io/rinex_measurements.hpp"
#include "skytrace/io/rinex_obs.hpp"
#include "skytrace/orbits/rinex_nav.hpp"
#include "skytrace/positioning/spp.hpp"

namespace {

using namespace skytrace;

struct Data {
  std::unique_ptr<orbits::BroadcastEphemerides> ephemerides;
  std::optional<orbits::KlobucharCoefficients> klobuchar;
  std::vector<positioning::EpochMeasurements> epochs;
  std::string error;
};

const Data& data() {
  static const Data d = [] {
    Data out;
    const std::filesystem::path dir = std::filesystem::path(SKYTRACE_DEFAULT_SHARED_DATA) / "real/esbc_2020177";
    auto nav = orbits::read_rinex_nav(dir / "ESBC00DNK_R_20201770000_01D_MN.rnx");
    auto obs = io::read_rinex_obs(dir / "ESBC00DNK_R_20201770000_01D_30S_MO_first1h.rnx");
    if (!nav || !obs) {
      out.error = !nav ? nav.error().message : obs.error().message;
      return out;
    }
    out.klobuchar = nav->ionosphere.gps;
    out.ephemerides = std::make_unique<orbits::BroadcastEphemerides>(std::move(*nav));
    const io::MeasurementExtractor extractor(obs->header);
    for (const auto& epoch : obs->epochs) out.epochs.push_back(extractor.measurements(epoch));
    return out;
  }();
  return d;
}

positioning::SolverSettings settings(bool reject_outliers) {
  positioning::SolverSettings s;
  s.systems = {GnssSystem::kGps, GnssSystem::kGlonass, GnssSystem::kGalileo, GnssSystem::kBeiDou};
  s.reject_outliers = reject_outliers;
  return s;
}

// A tracking receiver: each epoch starts from the previous fix. Argument: residual test on/off.
void BM_SolveEpochWarm(benchmark::State& state) {
  const Data& d = data();
  if (!d.error.empty()) {
    state.SkipWithError(d.error.c_str());
    return;
  }
  positioning::SinglePointSolver solver(*d.ephemerides, settings(state.range(0) != 0), d.klobuchar);
  size_t i = 0, used = 0;
  for (auto _ : state) {
    auto fix = solver.solve(d.epochs[i++ % d.epochs.size()]);
    used += static_cast<size_t>(fix->satellites_used);
    benchmark::DoNotOptimize(fix);
  }
  state.counters["satellites_per_epoch"] = static_cast<double>(used) / static_cast<double>(state.iterations());
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_SolveEpochWarm)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

// A cold start: every epoch from the Earth's centre.
void BM_SolveEpochCold(benchmark::State& state) {
  const Data& d = data();
  if (!d.error.empty()) {
    state.SkipWithError(d.error.c_str());
    return;
  }
  size_t i = 0;
  for (auto _ : state) {
    positioning::SinglePointSolver solver(*d.ephemerides, settings(false), d.klobuchar);
    auto fix = solver.solve(d.epochs[i++ % d.epochs.size()]);
    benchmark::DoNotOptimize(fix);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_SolveEpochCold)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
