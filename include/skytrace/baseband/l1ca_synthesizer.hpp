// Complex baseband samples of GPS L1 C/A as an antenna delivers them: every satellite's code,
// navigation data and carrier on each of its paths (direct, reflected, diffracted) with the delay,
// Doppler, phase and power the observation engine computed, in white Gaussian noise whose density
// makes those powers the signals' C/N0, quantised to the chosen sample format.
#pragma once

#include <array>
#include <complex>
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "skytrace/baseband/gps_l1ca.hpp"
#include "skytrace/core/random.hpp"
#include "skytrace/core/time.hpp"

namespace skytrace::baseband {

enum class SampleFormat { kSc8, kSc16, kGrComplex };  // interleaved I/Q: int8, int16, float32
[[nodiscard]] Result<SampleFormat> parse_sample_format(const std::string& name);
[[nodiscard]] int bytes_per_sample(SampleFormat format);  // one complex sample
// The GNSS-SDR item_type that reads the format as it is.
[[nodiscard]] const char* gnss_sdr_item_type(SampleFormat format);

// One path of a signal: relative to the direct path's delay, with its own complex amplitude
// (relative to the unobstructed direct signal, after the antenna).
struct ArrivalPath {
  double excess_delay_m = 0.0;
  double excess_delay_rate_mps = 0.0;
  std::complex<double> amplitude{1.0, 0.0};
};

// A satellite's L1 C/A signal at one instant: the noise-free pseudorange (the satellite clock's
// transmission time follows from it), carrier phase and Doppler of its direct path, the C/N0 it would
// have unobstructed at the antenna's output (the noise density of the samples), and its paths (empty: the direct one alone).
struct L1caArrival {
  int prn = 0;
  double pseudorange_m = 0.0;
  double carrier_phase_cycles = 0.0;
  double doppler_hz = 0.0;
  double antenna_cn0_dbhz = 0.0;
  std::vector<ArrivalPath> paths;
};

struct SynthesizerSettings {
  double sample_rate_hz = 4e6;
  SampleFormat format = SampleFormat::kSc8;
  GnssTime start;  // receiver time of the first sample (GPST)
  std::uint64_t seed = 1;
  bool noise = true;
  LnavCommon lnav;
  // The LNAV record a satellite broadcasts at a time (nullptr: none; its signal then carries no
  // data, as a satellite that is not set healthy would still transmit code).
  std::function<const orbits::KeplerEphemeris*(int prn, const GnssTime& t)> record_at;
};

class L1caSynthesizer {
 public:
  explicit L1caSynthesizer(SynthesizerSettings settings);

  // The satellites' signals at `time_s` (receiver time since the start, increasing). The samples
  // from the previous instant up to this one are appended to `out`: between two instants the
  // code and carrier phases follow cubic curves through both instants' values and rates.
  [[nodiscard]] Status add_instant(double time_s, const std::vector<L1caArrival>& arrivals, std::string& out);

  [[nodiscard]] std::int64_t samples_written() const { return samples_written_; }
  [[nodiscard]] size_t most_satellites() const { return most_satellites_; }
  [[nodiscard]] double noise_sigma() const;  // per component, in the output's units

 private:
  struct Instant {
    double time_s = 0.0;
    std::map<int, L1caArrival> arrivals;
  };
  struct Channel {
    std::array<std::int8_t, kCaCodeLength> code{};
    // The LNAV subframe in the buffer (start in seconds of the GPS week, week), for the data bits.
    int subframe_start_sow = -1;
    int subframe_week = -1;
    std::array<std::uint8_t, kLnavBitsPerSubframe> subframe{};
  };
  Status synthesize(const Instant& from, const Instant& to, std::string& out);
  // The data bit (+1 / -1) of the code period that starts `period_ms` ms after the start of the run's
  // first GPS week.
  int data_sign(int prn, Channel& channel, std::int64_t period_ms);
  void quantize(const float* re, const float* im, size_t n, std::string& out) const;

  SynthesizerSettings settings_;
  int first_week_ = 0;
  double start_sow_ = 0.0;  // start's seconds of that week (whole seconds expected)
  std::map<int, Channel> channels_;
  std::optional<Instant> previous_;
  RandomStream noise_;
  std::int64_t samples_written_ = 0;
  size_t most_satellites_ = 0;
  std::vector<float> re_, im_;
};

}  // namespace skytrace::baseband
