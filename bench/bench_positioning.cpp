// Single-point positioning cost per epoch: the real ESBC recording (GPS, GLONASS, Galileo,
// BeiDou: about 35 satellites per epoch) with its broadcast navigation file.
#include <benchmark/benchmark.h>

#include <filesystem>
#include <memory>

#include "bench_support.hpp"
#include "skytrace/positioning/spp.hpp"

namespace {

using namespace skytrace;

using Data = bench::EsbcFirstHour;
const Data& data() { return bench::esbc_first_hour(); }

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
