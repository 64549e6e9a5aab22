// Observation synthesis cost (the hot path of every run): ObservationGenerator::observe over the
// nominal constellation, every system, the PolarX5 profile with its clock, loop noise, slips and
// Klobuchar, open sky. One iteration is one epoch (1 s apart); items are satellite-epochs.
#include <benchmark/benchmark.h>

#include <memory>

#include "skytrace/atmosphere/ionosphere.hpp"
#include "skytrace/orbits/nominal.hpp"
#include "skytrace/receiver/observation_generator.hpp"

namespace {

using namespace skytrace;
using namespace skytrace::receiver;

void BM_ObserveNominalPolarx5(benchmark::State& state) {
  const GnssTime start = GnssTime::parse_iso8601("2026-03-01T12:00:00", TimeScale::kGpst).value();
  const double span_s = 6.0 * 3600.0;
  auto data = orbits::make_nominal_constellation(start, span_s).value();
  const auto klobuchar = data.ionosphere.gps;
  const orbits::BroadcastEphemerides ephemerides(std::move(data));
  GeneratorSettings settings;
  for (const char* name : {"G1C", "G2W", "G5Q", "R1C", "R2C", "E1C", "E5Q", "E7Q", "C2I", "C6I", "C1P", "C5P", "J1C",
                           "J5Q", "I5A"}) {
    settings.signals.push_back(Signal::parse(name).value());
  }
  settings.profile = builtin_profile("septentrio-polarx5").value();
  if (klobuchar) settings.ionosphere = std::make_shared<atmosphere::KlobucharIonosphere>(*klobuchar);
  settings.noise = true;
  settings.ideal_clock = false;
  settings.seed = 42;
  const Geodetic site{48.15, 11.57, 520.0};
  auto generator = std::make_unique<ObservationGenerator>(settings, ephemerides,
                                                          std::make_shared<StaticPosition>(geodetic_to_ecef(site)));
  double t_s = 0.0;
  std::int64_t satellite_epochs = 0;
  for (auto _ : state) {
    if (t_s >= span_s) {  // start over within the records' span
      state.PauseTiming();
      generator = std::make_unique<ObservationGenerator>(settings, ephemerides,
                                                         std::make_shared<StaticPosition>(geodetic_to_ecef(site)));
      t_s = 0.0;
      state.ResumeTiming();
    }
    auto epoch = generator->observe(start + t_s);
    t_s += 1.0;
    satellite_epochs += static_cast<std::int64_t>(epoch->satellites.size());
    benchmark::DoNotOptimize(epoch);
  }
  state.SetItemsProcessed(satellite_epochs);
}
BENCHMARK(BM_ObserveNominalPolarx5)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
