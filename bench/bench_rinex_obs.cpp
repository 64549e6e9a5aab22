// RINEX observation writer and reader throughput, in observation values per second.
// Typical simulator load: ~100 satellites x 4 signals x 4 observables (C, L, D, S) at 1 Hz.
#include <benchmark/benchmark.h>

#include <cstdio>
#include <filesystem>
#include <random>

#include "skytrace/io/rinex_obs.hpp"

namespace {

using namespace skytrace;
using namespace skytrace::io;

constexpr int kSatellitesPerSystem = 25;  // 4 systems -> 100 satellites
constexpr const char* kSignals[4][4] = {{"1C", "2W", "5Q", "1L"},   // GPS
                                        {"1C", "2C", "1P", "2P"},   // GLONASS
                                        {"1C", "5Q", "7Q", "6C"},   // Galileo
                                        {"2I", "7I", "6I", "1P"}};  // BeiDou
constexpr GnssSystem kSystems[4] = {GnssSystem::kGps, GnssSystem::kGlonass, GnssSystem::kGalileo, GnssSystem::kBeiDou};

ObservationHeader bench_header() {
  ObservationHeader h;
  h.version = 3.04;
  h.program = "skytrace bench";
  h.date = "20200625 000000 UTC";
  h.marker_name = "BENCH";
  h.marker_type = "GROUND_CRAFT";
  h.approx_position_ecef_m = std::array<double, 3>{3582105.291, 532589.731, 5232754.805};
  h.signal_strength_unit = "DBHZ";
  for (int s = 0; s < 4; ++s) {
    auto& types = h.observation_types[kSystems[s]];
    for (const char kind : {'C', 'L', 'D', 'S'}) {
      for (const char* signal : kSignals[s]) types.push_back(ObservationType{std::string{kind} + signal, {}});
    }
  }
  return h;
}

// A few distinct epochs with realistic magnitudes, cycled so the digits keep changing.
std::vector<ObservationEpoch> bench_epochs(size_t count) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> range_m(2.0e7, 4.0e7), doppler_hz(-4000.0, 4000.0), cn0(25.0, 52.0);
  const GnssTime t0 = GnssTime::from_calendar(CalendarTime{2020, 6, 25, 0, 0, 0.0}, TimeScale::kGpst);
  std::vector<ObservationEpoch> epochs(count);
  for (size_t e = 0; e < count; ++e) {
    epochs[e].time = t0 + static_cast<double>(e);
    for (int s = 0; s < 4; ++s) {
      for (int n = 1; n <= kSatellitesPerSystem; ++n) {
        SatelliteObservations sat{SatelliteId{kSystems[s], static_cast<std::uint8_t>(n)}, {}};
        sat.values.resize(16);
        for (int k = 0; k < 4; ++k) {
          const double r = range_m(rng);
          sat.values[k] = {r, 0, 7};
          sat.values[4 + k] = {r / 0.19 + 1234.5678, 0, 7};  // phase in cycles, ~1e8..2e8
          sat.values[8 + k] = {doppler_hz(rng), 0, 0};
          sat.values[12 + k] = {cn0(rng), 0, 0};
        }
        epochs[e].satellites.push_back(std::move(sat));
      }
    }
  }
  return epochs;
}

std::filesystem::path bench_dir() {
  auto dir = std::filesystem::temp_directory_path() / "skytrace_bench_rinex_obs";
  std::filesystem::create_directories(dir);
  return dir;
}

void BM_FormatF14_3(benchmark::State& state) {
  std::vector<double> values(4096);
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> d(-3.0e8, 3.0e8);
  for (auto& v : values) v = d(rng);
  char out[16];
  size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(detail::format_f14_3(values[i++ & 4095], out));
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations()));
}
BENCHMARK(BM_FormatF14_3);

// Baseline the writer avoids: snprintf per value.
void BM_SnprintfF14_3(benchmark::State& state) {
  std::vector<double> values(4096);
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> d(-3.0e8, 3.0e8);
  for (auto& v : values) v = d(rng);
  char out[32];
  size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(std::snprintf(out, sizeof out, "%14.3f", values[i++ & 4095]));
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations()));
}
BENCHMARK(BM_SnprintfF14_3);

// write_epoch alone (buffering and file writes included; finish() outside the timed loop).
void BM_WriteEpoch(benchmark::State& state) {
  auto epochs = bench_epochs(16);
  const GnssTime t0 = epochs[0].time;
  const auto path = bench_dir() / "write_epoch.rnx";
  RinexObsWriter writer;
  if (!writer.open(path, bench_header()).ok()) {
    state.SkipWithError("cannot open the writer");
    return;
  }
  size_t k = 0;
  for (auto _ : state) {
    ObservationEpoch& epoch = epochs[k % epochs.size()];
    epoch.time = t0 + static_cast<double>(k);
    if (!writer.write_epoch(epoch).ok()) {
      state.SkipWithError("write_epoch failed");
      break;
    }
    ++k;
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations()) * 100 * 16);
  (void)writer.finish();
  std::filesystem::remove(path);
}
BENCHMARK(BM_WriteEpoch)->Unit(benchmark::kMicrosecond);

// A whole file: open, N epochs, finish() (header + copy of the body + rename).
void BM_WriteWholeFile(benchmark::State& state) {
  auto epochs = bench_epochs(16);
  const GnssTime t0 = epochs[0].time;
  const auto count = static_cast<size_t>(state.range(0));
  const auto path = bench_dir() / "whole.rnx";
  for (auto _ : state) {
    RinexObsWriter writer;
    if (!writer.open(path, bench_header()).ok()) {
      state.SkipWithError("cannot open the writer");
      return;
    }
    for (size_t k = 0; k < count; ++k) {
      ObservationEpoch& epoch = epochs[k % epochs.size()];
      epoch.time = t0 + static_cast<double>(k);
      if (!writer.write_epoch(epoch).ok()) {
        state.SkipWithError("write_epoch failed");
        return;
      }
    }
    if (!writer.finish().ok()) {
      state.SkipWithError("finish failed");
      return;
    }
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * count) * 100 * 16);
  state.counters["file_MB"] = static_cast<double>(std::filesystem::file_size(path)) / 1e6;
  std::filesystem::remove(path);
}
BENCHMARK(BM_WriteWholeFile)->Arg(3600)->Unit(benchmark::kMillisecond)->Iterations(2);

// Reading the simulator's own output (values as written above).
void BM_ReadWrittenFile(benchmark::State& state) {
  const auto path = bench_dir() / "read.rnx";
  const auto epochs = bench_epochs(600);
  if (!write_rinex_obs(path, bench_header(), epochs).ok()) {
    state.SkipWithError("cannot write the input");
    return;
  }
  for (auto _ : state) {
    auto file = read_rinex_obs(path);
    if (!file.ok()) {
      state.SkipWithError("read failed");
      return;
    }
    benchmark::DoNotOptimize(file->epochs.data());
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations()) * 600 * 100 * 16);
  std::filesystem::remove(path);
}
BENCHMARK(BM_ReadWrittenFile)->Unit(benchmark::kMillisecond);

// A real recording: ESBC first hour (RINEX 3.05, 120 epochs, 5278 satellite records).
void BM_ReadEsbcFirstHour(benchmark::State& state) {
  const std::filesystem::path path = std::filesystem::path(SKYTRACE_DEFAULT_SHARED_DATA) /
                                     "real/esbc_2020177/ESBC00DNK_R_20201770000_01D_30S_MO_first1h.rnx";
  if (!std::filesystem::exists(path)) {
    state.SkipWithError("shared data absent");
    return;
  }
  size_t values = 0;
  for (auto _ : state) {
    auto file = read_rinex_obs(path);
    if (!file.ok()) {
      state.SkipWithError("read failed");
      return;
    }
    values = 0;
    for (const auto& e : file->epochs) {
      for (const auto& s : e.satellites) values += s.values.size();
    }
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * values));
}
BENCHMARK(BM_ReadEsbcFirstHour)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
