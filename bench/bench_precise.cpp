// Precise-product cost: reading a daily SP3 file and a 30 s clock file, and one satellite state
// (10-point inertial Lagrange with the two-body reference, clock from the clock file) at times that
// change from call to call. Uses the real GRG files of ../shared/data (skipped when absent).
#include <benchmark/benchmark.h>

#include "bench_support.hpp"

#include <cstdlib>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>
#include <algorithm>

#include "skytrace/orbits/precise.hpp"
#include "skytrace/orbits/precise_cache.hpp"

namespace {

using namespace skytrace;
using namespace skytrace::orbits;

using skytrace::bench::shared_file;

const std::string kOrbit = "real/esbc_2020177/GRG0MGXFIN_20201770000_01D_15M_ORB.SP3";
const std::string kClock = "real/esbc_2020177/GRG0MGXFIN_20201770000_01D_30S_CLK.CLK";

void BM_ReadSp3(benchmark::State& state) {
  const auto path = shared_file(kOrbit);
  if (!std::filesystem::exists(path)) return state.SkipWithError("shared data absent");
  for (auto _ : state) benchmark::DoNotOptimize(read_sp3(path));
}
BENCHMARK(BM_ReadSp3)->Unit(benchmark::kMillisecond);

void BM_ReadClock(benchmark::State& state) {
  const auto path = shared_file(kClock);
  if (!std::filesystem::exists(path)) return state.SkipWithError("shared data absent");
  for (auto _ : state) benchmark::DoNotOptimize(read_rinex_clock(path));
}
BENCHMARK(BM_ReadClock)->Unit(benchmark::kMillisecond)->Iterations(3);

void BM_State(benchmark::State& state) {
  const auto orbit_path = shared_file(kOrbit);
  const auto clock_path = shared_file(kClock);
  if (!std::filesystem::exists(orbit_path) || !std::filesystem::exists(clock_path)) {
    return state.SkipWithError("shared data absent");
  }
  PreciseOptions options;
  options.two_body_reference = state.range(0) != 0;
  auto source = PreciseEphemerides::create(read_sp3(orbit_path).value(), read_rinex_clock(clock_path).value(), options);
  if (!source.ok()) return state.SkipWithError(source.error().message.c_str());
  const SatelliteId satellite{GnssSystem::kGps, 5};
  const GnssTime start = GnssTime::from_calendar({2020, 6, 25, 2, 0, 0.0}, TimeScale::kGpst);
  double offset_s = 0.0;
  for (auto _ : state) {
    offset_s = offset_s > 72000.0 ? 0.0 : offset_s + 7.77;
    benchmark::DoNotOptimize(source->state(satellite, start + offset_s));
  }
}
BENCHMARK(BM_State)->Arg(1)->Arg(0)->ArgName("two_body");

// The same states as a run's generator asks for them: 40 satellites each 1 s (the fits per SP3
// interval of PreciseOrbitCache, refitted every 900 s; Arg 0: the full interpolation every time).
void BM_StateSequential(benchmark::State& state) {
  const auto orbit_path = shared_file(kOrbit);
  const auto clock_path = shared_file(kClock);
  if (!std::filesystem::exists(orbit_path) || !std::filesystem::exists(clock_path)) {
    return state.SkipWithError("shared data absent");
  }
  auto source = PreciseEphemerides::create(read_sp3(orbit_path).value(), read_rinex_clock(clock_path).value());
  if (!source.ok()) return state.SkipWithError(source.error().message.c_str());
  const auto view = state.range(0) != 0 ? source->sequential_view() : nullptr;
  const SatelliteStateSource& states = view != nullptr ? *view : *source;
  std::vector<SatelliteId> satellites = source->satellites();
  satellites.resize(std::min<size_t>(satellites.size(), 40));
  const GnssTime start = GnssTime::from_calendar({2020, 6, 25, 2, 0, 0.0}, TimeScale::kGpst);
  double offset_s = 0.0;
  size_t next = 0;
  for (auto _ : state) {
    if (next == satellites.size()) {
      next = 0;
      offset_s = offset_s > 72000.0 ? 0.0 : offset_s + 1.0;
    }
    benchmark::DoNotOptimize(states.state(satellites[next++], start + offset_s));
  }
}
BENCHMARK(BM_StateSequential)->Arg(1)->Arg(0)->ArgName("cache");

}  // namespace

BENCHMARK_MAIN();
