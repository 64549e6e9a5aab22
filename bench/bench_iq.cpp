// IQ sample generation (baseband/synthesizer): seconds of GPS L1 C/A, Galileo E1, GLONASS L1OF and BeiDou B1I samples per second of CPU
// on one core, for the case (12 satellites, 3 paths each, 4 MS/s, sc8) and its parts.
// Items processed = complex samples; "real time" is items_per_second >= the sample rate.
#include <benchmark/benchmark.h>

#include <memory>
#include <string>
#include <vector>

#include "skytrace/baseband/synthesizer.hpp"
#include "skytrace/core/constants.hpp"

namespace {

using namespace skytrace;
using namespace skytrace::baseband;

// `satellites` satellites of PRN 1.., each with `paths` paths (the direct one and reflections 5-40
// m longer at -6 to -12 dB), ranges 20,000-25,000 km, Dopplers -4 to +4 kHz, C/N0 40-50 dB-Hz.
std::vector<Arrival> arrivals_at(double t, int satellites, int paths) {
  const double wavelength_m = constants::kSpeedOfLight_mps / 1575.42e6;
  std::vector<Arrival> out;
  for (int k = 0; k < satellites; ++k) {
    Arrival a;
    a.id = k + 1;
    a.doppler_hz = -4000.0 + 8000.0 * k / std::max(1, satellites - 1);
    a.pseudorange_m = 20.0e6 + 4.0e5 * k - a.doppler_hz * wavelength_m * t;
    a.carrier_phase_cycles = a.pseudorange_m / wavelength_m;
    a.antenna_cn0_dbhz = 40.0 + k % 11;
    for (int p = 0; p < paths; ++p) {
      a.paths.push_back(ArrivalPath{p == 0 ? 0.0 : 5.0 + 12.0 * p, 0.1 * p,
                                    std::polar(p == 0 ? 1.0 : std::pow(10.0, -(3.0 + 3.0 * p) / 20.0), 0.7 * p)});
    }
    out.push_back(std::move(a));
  }
  return out;
}

// One second of samples per iteration from `arrivals(t)`; items = complex samples, and the
// speed against real time at `sample_rate_hz`.
template <typename Arrivals>
void run_seconds(benchmark::State& state, double sample_rate_hz, std::unique_ptr<BandSignals> signals,
                 Arrivals arrivals, bool noise = true) {
  SynthesizerSettings settings;
  settings.sample_rate_hz = sample_rate_hz;
  settings.format = SampleFormat::kSc8;
  settings.start = GnssTime::from_week_tow(TimeScale::kGpst, 2111, 345600.0);
  settings.noise = noise;
  BasebandSynthesizer synthesizer(settings, std::move(signals));
  std::string bytes;
  double t = 0.0;
  (void)synthesizer.add_instant(t, arrivals(t), bytes);
  std::int64_t samples = 0;
  for (auto _ : state) {
    bytes.clear();
    t += 1.0;
    if (!synthesizer.add_instant(t, arrivals(t), bytes)) state.SkipWithError("failed");
    benchmark::DoNotOptimize(bytes.data());
    samples += static_cast<std::int64_t>(bytes.size() / 2);
  }
  state.SetItemsProcessed(samples);
  state.counters["realtime_x"] =
      benchmark::Counter(static_cast<double>(samples) / sample_rate_hz, benchmark::Counter::kIsRate);
}

void BM_L1caSamples(benchmark::State& state) {
  const int satellites = static_cast<int>(state.range(0));
  const int paths = static_cast<int>(state.range(1));
  run_seconds(state, static_cast<double>(state.range(2)), make_gps_l1ca_signals({}, 2111, nullptr),
              [&](double t) { return arrivals_at(t, satellites, paths); }, state.range(3) != 0);
}
// satellites, paths, sample rate, noise
BENCHMARK(BM_L1caSamples)
    ->Args({12, 3, 4000000, 1})  // the case
    ->Args({12, 1, 4000000, 1})
    ->Args({12, 3, 4000000, 0})  // without the noise
    ->Args({0, 0, 4000000, 1})   // the noise alone
    ->Args({12, 3, 8000000, 1})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(3);

// GLONASS L1OF: `satellites` satellites on channels -7..+6 at 9 MS/s (the band's least rate), one
// path each, without data (the strings' cost is per 10 ms symbol).
void BM_GlonassSamples(benchmark::State& state) {
  const int satellites = static_cast<int>(state.range(0));
  run_seconds(state, 9e6, make_glonass_l1of_signals({}, 2111, nullptr), [&](double t) {
    std::vector<Arrival> out;
    for (int k = 0; k < satellites; ++k) {
      Arrival a;
      a.id = k + 1;
      a.carrier_hz = 1602.0e6 + 562.5e3 * (k % 14 - 7);
      const double wavelength_m = constants::kSpeedOfLight_mps / a.carrier_hz;
      a.doppler_hz = -3000.0 + 500.0 * k;
      a.pseudorange_m = 19.5e6 + 3.0e5 * k - a.doppler_hz * wavelength_m * t;
      a.carrier_phase_cycles = a.pseudorange_m / wavelength_m;
      a.antenna_cn0_dbhz = 45.0;
      out.push_back(std::move(a));
    }
    return out;
  });
}
BENCHMARK(BM_GlonassSamples)->Arg(10)->Unit(benchmark::kMillisecond)->Iterations(3);

// `satellites` satellites of ids first_id.. on one carrier, one path each: Dopplers -3 to +3 kHz,
// ranges from `range_m` 300 km apart, C/N0 45 dB-Hz.
std::vector<Arrival> one_path_arrivals(double t, int satellites, int first_id, double carrier_hz, double range_m) {
  const double wavelength_m = constants::kSpeedOfLight_mps / carrier_hz;
  std::vector<Arrival> out;
  for (int k = 0; k < satellites; ++k) {
    Arrival a;
    a.id = first_id + k;
    a.carrier_hz = carrier_hz;
    a.doppler_hz = -3000.0 + 600.0 * k;
    a.pseudorange_m = range_m + 3.0e5 * k - a.doppler_hz * wavelength_m * t;
    a.carrier_phase_cycles = a.pseudorange_m / wavelength_m;
    a.antenna_cn0_dbhz = 45.0;
    out.push_back(std::move(a));
  }
  return out;
}

// BeiDou B1I: `satellites` MEO satellites (PRN 19..) at 5 MS/s, one path each, D1 without records.
void BM_BeidouB1iSamples(benchmark::State& state) {
  const int satellites = static_cast<int>(state.range(0));
  run_seconds(state, 5e6, make_beidou_b1i_signals({}, 2111, nullptr),
              [&](double t) { return one_path_arrivals(t, satellites, 19, 1561.098e6, 21.5e6); });
}
BENCHMARK(BM_BeidouB1iSamples)->Arg(10)->Unit(benchmark::kMillisecond)->Iterations(3);

// Galileo E1 OS (CBOC, 4 ms periods, I/NAV without records): `satellites` satellites at 5 MS/s,
// one path each.
void BM_GalileoE1Samples(benchmark::State& state) {
  const int satellites = static_cast<int>(state.range(0));
  run_seconds(state, 5e6, make_galileo_e1_signals({}, 2111, nullptr),
              [&](double t) { return one_path_arrivals(t, satellites, 1, 1575.42e6, 23.5e6); });
}
BENCHMARK(BM_GalileoE1Samples)->Arg(10)->Unit(benchmark::kMillisecond)->Iterations(3);

}  // namespace

BENCHMARK_MAIN();
