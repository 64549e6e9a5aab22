// Complex baseband samples of one band as an antenna delivers them: every satellite's code,
// navigation data and carrier on each of its paths (direct, reflected, diffracted) with the delay,
// Doppler, phase and power the observation engine computed, in white Gaussian noise whose density
// makes those powers the signals' C/N0, quantised to the chosen sample format.
#pragma once

#include <array>
#include <complex>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "skytrace/baseband/galileo_e1.hpp"
#include "skytrace/baseband/gps_l1ca.hpp"
#include "skytrace/baseband/glonass_l1of.hpp"
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

// A satellite's signal at one instant: the noise-free pseudorange (the satellite clock's
// transmission time follows from it), carrier phase and Doppler of its direct path, the C/N0 it would
// have unobstructed at the antenna's output (the noise density of the samples), and its paths
// (empty: the direct one alone).
struct Arrival {
  int id = 0;  // GPS: PRN; GLONASS: slot
  double carrier_hz = 1575.42e6;
  double pseudorange_m = 0.0;
  double carrier_phase_cycles = 0.0;
  double doppler_hz = 0.0;
  double antenna_cn0_dbhz = 0.0;
  std::vector<ArrivalPath> paths;
};

// The signals of one band: each satellite's code waveform (one period every code_period_ms()), its
// data symbols, and the band's centre (a carrier off it, GLONASS FDMA, sits at its offset).
class BandSignals {
 public:
  virtual ~BandSignals() = default;
  [[nodiscard]] virtual int code_period_ms() const { return 1; }  // Galileo E1: 4
  // Values per code period: the chips, or the sub-chips of a BOC waveform (Galileo E1: 12 a chip).
  [[nodiscard]] virtual int code_length() const = 0;
  // The waveform of one code period, code_length() values of unit mean square; `form` is one of
  // forms() variants (Galileo E1: its pilot's secondary chip agreeing with the data symbol or not).
  [[nodiscard]] virtual Result<const float*> code(int id, int form) = 0;
  [[nodiscard]] virtual int forms() const { return 1; }
  [[nodiscard]] virtual double centre_hz() const = 0;  // the band's centre: 0 Hz of the samples
  // The data symbol (+1 / -1) and the waveform's form of the code period that starts
  // `period * code_period_ms()` ms after the start of GPS week `first_week` (transmission time by
  // the satellite's clock, GPST).
  [[nodiscard]] virtual int sign(int id, std::int64_t period) = 0;
  [[nodiscard]] virtual int form(int /*id*/, std::int64_t /*period*/) { return 0; }
};

// GPS L1 C/A, ids PRN 1-32: LNAV from the record `record_at` gives (nullptr: no data).
[[nodiscard]] std::unique_ptr<BandSignals> make_gps_l1ca_signals(
    LnavCommon lnav, int first_week,
    std::function<const orbits::KeplerEphemeris*(int prn, const GnssTime& t)> record_at);
// GLONASS L1OF, ids the slots: FDMA channel and navigation strings from the record `record_at`
// gives (nullptr: no data), centred on 1602 MHz.
[[nodiscard]] std::unique_ptr<BandSignals> make_glonass_l1of_signals(
    GnavCommon gnav, int first_week,
    std::function<const orbits::GlonassEphemeris*(int slot, const GnssTime& t)> record_at);

struct SynthesizerSettings {
  double sample_rate_hz = 4e6;
  SampleFormat format = SampleFormat::kSc8;
  GnssTime start;  // receiver time of the first sample (GPST)
  std::uint64_t seed = 1;
  bool noise = true;
};

// BeiDou B1I, ids PRN 1-63: D1 (MEO and IGSO) or D2 (GEO: PRN 1-5, 59-63) from the record
// `record_at` gives (nullptr: no data), centred on 1561.098 MHz.
[[nodiscard]] std::unique_ptr<BandSignals> make_beidou_b1i_signals(
    orbits::IonosphereCoefficients ionosphere, int first_week,
    std::function<const orbits::KeplerEphemeris*(int prn, const GnssTime& t)> record_at);

// Galileo E1 OS (E1-B with I/NAV, E1-C pilot, CBOC), ids PRN 1-50: the record `record_at` gives
// (nullptr: no data), centred on 1575.42 MHz; 4 ms code periods.
[[nodiscard]] std::unique_ptr<BandSignals> make_galileo_e1_signals(
    InavCommon inav, int first_week,
    std::function<const orbits::KeplerEphemeris*(int prn, const GnssTime& t)> record_at);

class BasebandSynthesizer {
 public:
  BasebandSynthesizer(SynthesizerSettings settings, std::unique_ptr<BandSignals> signals);

  // The satellites' signals at `time_s` (receiver time since the start, increasing). The samples
  // from the previous instant up to this one are appended to `out`: between two instants the
  // code and carrier phases follow cubic curves through both instants' values and rates.
  [[nodiscard]] Status add_instant(double time_s, const std::vector<Arrival>& arrivals, std::string& out);

  [[nodiscard]] std::int64_t samples_written() const { return samples_written_; }
  [[nodiscard]] size_t most_satellites() const { return most_satellites_; }
  [[nodiscard]] double noise_sigma() const;  // per component, in the output's units

 private:
  struct Instant {
    double time_s = 0.0;
    std::map<int, Arrival> arrivals;
  };
  Status synthesize(const Instant& from, const Instant& to, std::string& out);
  void quantize(const float* re, const float* im, size_t n, std::string& out) const;

  SynthesizerSettings settings_;
  std::unique_ptr<BandSignals> signals_;
  int first_week_ = 0;
  double start_sow_ = 0.0;  // start's seconds of that week
  std::map<int, std::vector<const float*>> codes_;  // per id, each form's waveform
  std::optional<Instant> previous_;
  RandomStream noise_;
  std::int64_t samples_written_ = 0;
  size_t most_satellites_ = 0;
  std::vector<float> re_, im_;
};

}  // namespace skytrace::baseband
