#include "skytrace/baseband/synthesizer.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numbers>

#include "skytrace/core/constants.hpp"

namespace skytrace::baseband {
namespace {

constexpr int kLutBits = 10;
constexpr int kLutSize = 1 << kLutBits;

// Output units per unit of noise standard deviation (per component): room for the signals and
// about 8 sigma before int8 clips, 16 sigma for int16.
double output_scale(SampleFormat format) {
  switch (format) {
    case SampleFormat::kSc8: return 16.0;
    case SampleFormat::kSc16: return 2048.0;
    case SampleFormat::kGrComplex: return 1.0;
  }
  return 1.0;
}

struct CarrierTable {
  std::array<float, kLutSize> cos_table{};
  std::array<float, kLutSize> sin_table{};
  CarrierTable() {
    for (int i = 0; i < kLutSize; ++i) {
      const double angle = 2.0 * std::numbers::pi * (static_cast<double>(i) + 0.5) / kLutSize;
      cos_table[static_cast<size_t>(i)] = static_cast<float>(std::cos(angle));
      sin_table[static_cast<size_t>(i)] = static_cast<float>(std::sin(angle));
    }
  }
};
const CarrierTable& carrier_table() {
  static const CarrierTable table;
  return table;
}

// Cubic Hermite interpolation between (t0, y0, slope0) and (t1, y1, slope1).
double hermite(double t, double t0, double y0, double slope0, double t1, double y1, double slope1) {
  const double h = t1 - t0;
  const double s = (t - t0) / h;
  const double s2 = s * s;
  const double s3 = s2 * s;
  return (2 * s3 - 3 * s2 + 1) * y0 + (s3 - 2 * s2 + s) * h * slope0 + (-2 * s3 + 3 * s2) * y1 + (s3 - s2) * h * slope1;
}

}  // namespace

Result<SampleFormat> parse_sample_format(const std::string& name) {
  if (name == "sc8") return SampleFormat::kSc8;
  if (name == "sc16") return SampleFormat::kSc16;
  if (name == "gr_complex") return SampleFormat::kGrComplex;
  return make_error(ErrorCode::kInvalidArgument, "sample format '" + name + "': expected sc8, sc16 or gr_complex");
}

int bytes_per_sample(SampleFormat format) {
  switch (format) {
    case SampleFormat::kSc8: return 2;
    case SampleFormat::kSc16: return 4;
    case SampleFormat::kGrComplex: return 8;
  }
  return 2;
}

const char* gnss_sdr_item_type(SampleFormat format) {
  switch (format) {
    case SampleFormat::kSc8: return "ibyte";
    case SampleFormat::kSc16: return "ishort";
    case SampleFormat::kGrComplex: return "gr_complex";
  }
  return "ibyte";
}

BasebandSynthesizer::BasebandSynthesizer(SynthesizerSettings settings, std::unique_ptr<BandSignals> signals)
    : settings_(std::move(settings)), signals_(std::move(signals)), noise_(stream_key(settings_.seed, {0x1a1ca5ULL})) {
  const WeekTow start = settings_.start.to_week_tow(TimeScale::kGpst);
  first_week_ = start.week;
  start_sow_ = start.tow_s;
}

double BasebandSynthesizer::noise_sigma() const { return output_scale(settings_.format); }

Status BasebandSynthesizer::add_instant(double time_s, const std::vector<Arrival>& arrivals, std::string& out) {
  Instant now;
  now.time_s = time_s;
  for (const Arrival& a : arrivals) {
    if (!codes_.contains(a.id)) {
      std::vector<const float*> forms;
      for (int form = 0; form < signals_->forms(); ++form) {
        auto code = signals_->code(a.id, form);
        if (!code) return code.error();
        forms.push_back(*code);
      }
      codes_[a.id] = std::move(forms);
    }
    now.arrivals[a.id] = a;
  }
  most_satellites_ = std::max(most_satellites_, now.arrivals.size());
  if (previous_) {
    if (time_s <= previous_->time_s) {
      return make_error(ErrorCode::kInvalidArgument, "IQ samples: instants must increase in time");
    }
    if (auto st = synthesize(*previous_, now, out); !st) return st;
  }
  previous_ = std::move(now);
  return Ok{};
}

Status BasebandSynthesizer::synthesize(const Instant& from, const Instant& to, std::string& out) {
  const double fs = settings_.sample_rate_hz;
  const auto block = static_cast<std::int64_t>(std::floor(fs * 1e-3));  // samples per block, at most 1 ms
  const auto end_sample = static_cast<std::int64_t>(std::ceil(to.time_s * fs - 1e-6));
  const CarrierTable& lut = carrier_table();
  // Transmission times are counted in code periods from the run's first week's start: the start's
  // whole periods, and its fraction of one carried with the small numbers of the run.
  const int period_ms = signals_->code_period_ms();
  const double start_ms = start_sow_ * 1000.0;
  const auto start_ms_whole = static_cast<std::int64_t>(std::floor(start_ms));
  const std::int64_t start_periods_whole = start_ms_whole / period_ms;
  const double start_ms_fraction =
      static_cast<double>(start_ms_whole - start_periods_whole * period_ms) + (start_ms - static_cast<double>(start_ms_whole));

  struct Replica {
    const std::vector<const float*>* forms;
    int id;
    const Arrival* a0;
    const Arrival* a1;
    ArrivalPath path;
    double amplitude;  // linear, output units before scaling
    double carrier_offset_hz;
  };
  const int code_length = signals_->code_length();
  std::vector<Replica> replicas;
  for (const auto& [id, a0] : from.arrivals) {
    auto it = to.arrivals.find(id);
    if (it == to.arrivals.end()) continue;
    const double direct_amplitude = std::sqrt(2.0 * std::pow(10.0, a0.antenna_cn0_dbhz / 10.0) / fs);
    const std::vector<ArrivalPath> direct_only = {ArrivalPath{}};
    for (const ArrivalPath& path : a0.paths.empty() ? direct_only : a0.paths) {
      replicas.push_back(Replica{&codes_.at(id), id, &a0, &it->second, path, direct_amplitude * std::abs(path.amplitude),
                                 a0.carrier_hz - signals_->centre_hz()});
    }
  }

  while (samples_written_ < end_sample) {
    const std::int64_t n0 = samples_written_;
    const auto n = static_cast<size_t>(std::min(block, end_sample - n0));
    re_.assign(n, 0.0F);
    im_.assign(n, 0.0F);
    if (settings_.noise) {
      for (size_t i = 0; i < n; ++i) {
        re_[i] = static_cast<float>(noise_.gaussian());
        im_[i] = static_cast<float>(noise_.gaussian());
      }
    }
    const double tb = static_cast<double>(n0) / fs;
    const double te = static_cast<double>(n0 + static_cast<std::int64_t>(n)) / fs;
    for (Replica& r : replicas) {
      const Arrival& a0 = *r.a0;
      const Arrival& a1 = *r.a1;
      const double wavelength_m = constants::kSpeedOfLight_mps / a0.carrier_hz;
      auto range_at = [&](double t) {
        const double p = hermite(t, from.time_s, a0.pseudorange_m, -a0.doppler_hz * wavelength_m, to.time_s,
                                 a1.pseudorange_m, -a1.doppler_hz * wavelength_m);
        return p + r.path.excess_delay_m + r.path.excess_delay_rate_mps * (t - from.time_s);
      };
      auto phase_at = [&](double t) {  // baseband carrier phase, cycles
        const double l = hermite(t, from.time_s, a0.carrier_phase_cycles, -a0.doppler_hz, to.time_s,
                                 a1.carrier_phase_cycles, -a1.doppler_hz);
        const double excess_m = r.path.excess_delay_m + r.path.excess_delay_rate_mps * (t - from.time_s);
        // The carrier sits carrier_offset_hz from the band's centre (GLONASS FDMA).
        return -(l + excess_m / wavelength_m) + std::arg(r.path.amplitude) / (2.0 * std::numbers::pi) +
               r.carrier_offset_hz * t;
      };
      // Transmission time (satellite clock) in code periods since the first week's start, less the
      // start's whole periods.
      const double xb = ((tb - range_at(tb) / constants::kSpeedOfLight_mps) * 1000.0 + start_ms_fraction) / period_ms;
      const double xe = ((te - range_at(te) / constants::kSpeedOfLight_mps) * 1000.0 + start_ms_fraction) / period_ms;
      const auto period_b = static_cast<std::int64_t>(std::floor(xb));
      const double chip = (xb - static_cast<double>(period_b)) * code_length;
      const double chips_per_sample = (xe - xb) * code_length / static_cast<double>(n);
      const double phase_b = phase_at(tb);
      const double cycles_per_sample = (phase_at(te) - phase_b) / static_cast<double>(n);
      // Fixed point within the block: chips with 32 fractional bits, the carrier in 2^-32 cycles
      // (wrapping as the phase does).
      constexpr double kFraction = 4294967296.0;  // 2^32
      const auto chip_step = static_cast<std::uint64_t>(std::llround(chips_per_sample * kFraction));
      const auto carrier_step = static_cast<std::uint32_t>(
          static_cast<std::int64_t>(std::llround((cycles_per_sample - std::floor(cycles_per_sample)) * kFraction)));
      auto carrier = static_cast<std::uint32_t>(
          static_cast<std::int64_t>(std::llround((phase_b - std::floor(phase_b)) * kFraction)));
      auto chip_fixed = static_cast<std::uint64_t>(chip * kFraction);
      const std::uint64_t kCodeEnd = static_cast<std::uint64_t>(code_length) << 32;
      std::int64_t period = start_periods_whole + period_b;
      const auto amplitude = static_cast<float>(r.amplitude);
      const std::vector<const float*>& forms = *r.forms;
      const float* cos_table = lut.cos_table.data();
      const float* sin_table = lut.sin_table.data();
      size_t i = 0;
      while (i < n) {
        // Samples up to the next code period, whose data bit may differ.
        size_t segment = chip_fixed >= kCodeEnd ? 0 : static_cast<size_t>((kCodeEnd - chip_fixed + chip_step - 1) / chip_step);
        segment = std::min(segment, n - i);
        const float a = amplitude * static_cast<float>(signals_->sign(r.id, period));
        const float* code = forms.size() == 1 ? forms[0] : forms[static_cast<size_t>(signals_->form(r.id, period))];
        float* re = re_.data() + i;
        float* im = im_.data() + i;
        for (size_t k = 0; k < segment; ++k) {
          const float v = a * code[chip_fixed >> 32];
          const std::uint32_t lut_index = carrier >> (32 - kLutBits);
          re[k] += v * cos_table[lut_index];
          im[k] += v * sin_table[lut_index];
          chip_fixed += chip_step;
          carrier += carrier_step;
        }
        i += segment;
        if (chip_fixed >= kCodeEnd) {
          chip_fixed -= kCodeEnd;
          ++period;
        }
      }
    }
    quantize(re_.data(), im_.data(), n, out);
    samples_written_ += static_cast<std::int64_t>(n);
  }
  return Ok{};
}

void BasebandSynthesizer::quantize(const float* re, const float* im, size_t n, std::string& out) const {
  const auto scale = static_cast<float>(output_scale(settings_.format));
  const size_t at = out.size();
  out.resize(at + n * static_cast<size_t>(bytes_per_sample(settings_.format)));
  char* p = out.data() + at;
  switch (settings_.format) {
    case SampleFormat::kSc8:
      for (size_t i = 0; i < n; ++i) {
        p[2 * i] = static_cast<char>(static_cast<std::int8_t>(std::clamp(std::nearbyint(re[i] * scale), -127.0F, 127.0F)));
        p[2 * i + 1] = static_cast<char>(static_cast<std::int8_t>(std::clamp(std::nearbyint(im[i] * scale), -127.0F, 127.0F)));
      }
      break;
    case SampleFormat::kSc16:
      for (size_t i = 0; i < n; ++i) {
        const auto v_re = static_cast<std::int16_t>(std::clamp(std::nearbyint(re[i] * scale), -32767.0F, 32767.0F));
        const auto v_im = static_cast<std::int16_t>(std::clamp(std::nearbyint(im[i] * scale), -32767.0F, 32767.0F));
        std::memcpy(p + 4 * i, &v_re, 2);  // little-endian hosts: the file is little-endian
        std::memcpy(p + 4 * i + 2, &v_im, 2);
      }
      break;
    case SampleFormat::kGrComplex:
      for (size_t i = 0; i < n; ++i) {
        const float v_re = re[i] * scale;
        const float v_im = im[i] * scale;
        std::memcpy(p + 8 * i, &v_re, 4);
        std::memcpy(p + 8 * i + 4, &v_im, 4);
      }
      break;
  }
}

}  // namespace skytrace::baseband
