// Real against simulated observations: epoch matching, per-system common-part removal, statistics.
#include "skytrace/io/compare.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <unordered_map>
#include <utility>

#include "skytrace/core/constants.hpp"
#include "skytrace/core/frames.hpp"
#include "skytrace/core/satellite_catalog.hpp"

namespace skytrace::io {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// Epochs of the two files are the same instant when their times differ by at most this.
constexpr double kEpochMatchTolerance_s = 1e-3;
// Below this distance from the geocentre an APPROX POSITION XYZ is a placeholder (often 0 0 0).
constexpr double kMinimumStationRadius_m = 6.0e6;

// Where a signal's four observables sit in a file's type list of the signal's system.
struct SignalColumns {
  std::optional<size_t> code;
  std::optional<size_t> phase;
  std::optional<size_t> doppler;
  std::optional<size_t> strength;
};

SignalColumns signal_columns(const ObservationHeader& header, const Signal& signal) {
  const std::string suffix = signal.code();
  return {header.type_index(signal.system, "C" + suffix),
          header.type_index(signal.system, "L" + suffix),
          header.type_index(signal.system, "D" + suffix),
          header.type_index(signal.system, "S" + suffix)};
}

// An exact 0.000 counts as absent: receivers write it for observables they do not produce (the
// Trimble NetR9 at NYA1 writes D5X as .000 for every satellite), and RTKLIB reads it the same way.
const ObservationValue* value_at(const SatelliteObservations& s,
                                 const std::optional<size_t>& column) {
  if (!column || *column >= s.values.size() || !s.values[*column].value || *s.values[*column].value == 0.0) {
    return nullptr;
  }
  return &s.values[*column];
}

std::optional<double> number_at(const SatelliteObservations& s,
                                const std::optional<size_t>& column) {
  const ObservationValue* v = value_at(s, column);
  if (v == nullptr) return std::nullopt;
  return *v->value;
}

// A satellite tracks the signal when its pseudorange is there; a file without a pseudorange type
// for the signal tracks it when any observable is there.
bool is_tracked(const SatelliteObservations& s, const SignalColumns& c) {
  if (c.code) return value_at(s, c.code) != nullptr;
  return value_at(s, c.phase) != nullptr || value_at(s, c.doppler) != nullptr ||
         value_at(s, c.strength) != nullptr;
}

// Signals a file lists for a system (types with a RINEX 3 code of a catalogued signal).
std::set<Signal> listed_signals(const ObservationHeader& header, GnssSystem system) {
  std::set<Signal> out;
  const auto it = header.observation_types.find(system);
  if (it == header.observation_types.end()) return out;
  for (const auto& type : it->second) {
    const char kind = type.kind();
    if (type.code.size() != 3 || (kind != 'C' && kind != 'L' && kind != 'D' && kind != 'S'))
      continue;
    if (auto signal = Signal::from_code(system, std::string_view(type.code).substr(1)); signal)
      out.insert(*signal);
  }
  return out;
}

std::string signal_names(const std::set<Signal>& signals) {
  std::string out;
  for (const auto& s : signals) {
    if (!out.empty()) out += ' ';
    out += s.to_string();
  }
  return out.empty() ? "none" : out;
}

std::string time_text(const GnssTime& t) {
  return t.to_iso8601(TimeScale::kGpst, t.fraction_s() == 0.0 ? 0 : 3);
}

// Observation epochs (flags 0 and 1) in time order. Event epochs carry no observations and flag-6
// epochs report slips the receiver has already repaired, so neither takes part.
std::vector<const ObservationEpoch*> observation_epochs(const ObservationFile& file) {
  std::vector<const ObservationEpoch*> out;
  out.reserve(file.epochs.size());
  for (const auto& e : file.epochs) {
    if (e.flag == EpochFlag::kOk || e.flag == EpochFlag::kPowerFailure) out.push_back(&e);
  }
  std::stable_sort(out.begin(), out.end(),
                   [](const auto* a, const auto* b) { return a->time < b->time; });
  // A repeated time keeps its first record.
  out.erase(std::unique(out.begin(), out.end(),
                        [](const auto* a, const auto* b) {
                          return std::abs(b->time - a->time) <= kEpochMatchTolerance_s;
                        }),
            out.end());
  return out;
}

struct EpochPair {
  std::int64_t real_index = 0;
  std::int64_t sim_index = 0;
};

std::vector<EpochPair> match_epochs(const std::vector<const ObservationEpoch*>& real,
                                    const std::vector<const ObservationEpoch*>& sim,
                                    double tolerance_s) {
  std::vector<EpochPair> pairs;
  size_t i = 0;
  size_t j = 0;
  while (i < real.size() && j < sim.size()) {
    const double dt_s = real[i]->time - sim[j]->time;
    if (std::abs(dt_s) <= tolerance_s) {
      pairs.push_back({static_cast<std::int64_t>(i), static_cast<std::int64_t>(j)});
      ++i;
      ++j;
    } else if (dt_s < 0.0) {
      ++i;
    } else {
      ++j;
    }
  }
  return pairs;
}

// Follows the continuity of one signal's phase through every observation epoch of one file: a run
// is a stretch of consecutive epochs with the phase present and no loss of lock after its start.
class PhaseContinuity {
 public:
  PhaseContinuity(const std::vector<const ObservationEpoch*>& epochs, GnssSystem system,
                  std::optional<size_t> phase_column)
      : epochs_(epochs), system_(system), column_(phase_column) {}

  // Processes epochs up to and including `index`.
  void advance_to(std::int64_t index) {
    for (; next_ <= index && next_ < static_cast<std::int64_t>(epochs_.size()); ++next_) {
      const ObservationEpoch& epoch = *epochs_[static_cast<size_t>(next_)];
      for (const auto& s : epoch.satellites) {
        if (s.satellite.system != system_) continue;
        const ObservationValue* v = value_at(s, column_);
        if (v == nullptr) continue;
        Run& run = runs_[s.satellite.number];
        const bool lost_lock = (v->lli & 0x1U) != 0 || epoch.flag == EpochFlag::kPowerFailure;
        if (lost_lock || run.last_index != next_ - 1) run.start_index = next_;
        run.last_index = next_;
      }
    }
  }

  // True when the satellite's phase is present at every epoch from `from_index` to the last one
  // processed, without a loss of lock after `from_index`.
  [[nodiscard]] bool continuous_since(const SatelliteId& satellite, std::int64_t from_index) const {
    const Run& run = runs_[satellite.number];
    return run.last_index == next_ - 1 && run.start_index <= from_index;
  }

 private:
  struct Run {
    std::int64_t last_index = -2;
    std::int64_t start_index = 0;
  };
  const std::vector<const ObservationEpoch*>& epochs_;
  GnssSystem system_;
  std::optional<size_t> column_;
  std::array<Run, 256> runs_{};
  std::int64_t next_ = 0;
};

double median_of(std::vector<double> values) {
  const size_t n = values.size();
  const auto mid = values.begin() + static_cast<std::ptrdiff_t>(n / 2);
  std::nth_element(values.begin(), mid, values.end());
  if (n % 2 == 1) return *mid;
  const double upper = *mid;
  const double lower = *std::max_element(values.begin(), mid);
  return 0.5 * (lower + upper);
}

// Subtracts the median of one system-epoch's differences and appends the residuals; false when a
// single satellite leaves nothing to compare.
bool append_residuals(const std::vector<double>& differences, std::vector<double>& residuals) {
  if (differences.size() < 2) return false;
  const double median = median_of(differences);
  for (double d : differences) residuals.push_back(d - median);
  return true;
}

// Elevation of satellites seen from the real file's position, once per common epoch and satellite.
class ElevationMask {
 public:
  ElevationMask(const orbits::SatelliteStateSource* source, const Eigen::Vector3d& station_ecef_m,
                double min_elevation_deg, size_t epoch_count,
                std::function<std::optional<Eigen::Vector3d>(const GnssTime&)> receiver_position = {})
      : source_(source),
        station_ecef_m_(station_ecef_m),
        station_(ecef_to_geodetic(station_ecef_m)),
        min_elevation_deg_(min_elevation_deg),
        elevations_deg_(epoch_count),
        receiver_position_(std::move(receiver_position)) {}

  bool keeps(size_t epoch, const SatelliteId& satellite, const GnssTime& t) {
    if (source_ == nullptr) return true;
    auto& cache = elevations_deg_[epoch];
    auto it = cache.find(satellite);
    if (it == cache.end()) {
      double elevation_deg = kNaN;
      // The position at the epoch is enough for a mask: the ~0.07 s signal travel time moves the
      // satellite by about 0.001 degrees as seen from the ground.
      if (auto state = source_->state(satellite, t); state) {
        if (receiver_position_) {
          // A moving receiver: the mask looks from where it is at this epoch.
          if (auto p = receiver_position_(t)) {
            elevation_deg = azimuth_elevation(*p, ecef_to_geodetic(*p), state->position_m).elevation_deg;
          }
        } else {
          elevation_deg =
              azimuth_elevation(station_ecef_m_, station_, state->position_m).elevation_deg;
        }
      }
      if (std::isnan(elevation_deg)) {
        ++without_position_;
        ++without_position_by_system_[satellite.system];
      } else if (elevation_deg < min_elevation_deg_) {
        ++below_mask_;
      }
      it = cache.emplace(satellite, elevation_deg).first;
    }
    return !std::isnan(it->second) && it->second >= min_elevation_deg_;
  }

  [[nodiscard]] size_t below_mask() const { return below_mask_; }
  [[nodiscard]] size_t without_position() const { return without_position_; }
  [[nodiscard]] const std::map<GnssSystem, size_t>& without_position_by_system() const {
    return without_position_by_system_;
  }

 private:
  const orbits::SatelliteStateSource* source_;
  Eigen::Vector3d station_ecef_m_;
  Geodetic station_;
  double min_elevation_deg_;
  std::vector<std::unordered_map<SatelliteId, double>> elevations_deg_;
  std::function<std::optional<Eigen::Vector3d>(const GnssTime&)> receiver_position_;
  size_t below_mask_ = 0;
  size_t without_position_ = 0;
  std::map<GnssSystem, size_t> without_position_by_system_;
};

// GLONASS frequency channel per slot from both headers (the real file's wins).
std::map<int, int> glonass_channels(const ObservationHeader& real, const ObservationHeader& sim) {
  std::map<int, int> channels;
  for (const auto& s : sim.glonass_slots) channels[s.slot] = s.channel;
  for (const auto& s : real.glonass_slots) channels[s.slot] = s.channel;
  return channels;
}

bool strength_in_dbhz(const ObservationHeader& header) {
  std::string unit = header.signal_strength_unit;
  std::erase(unit, ' ');
  std::transform(unit.begin(), unit.end(), unit.begin(),
                 [](unsigned char c) { return static_cast<char>(std::toupper(c)); });
  return unit.empty() || unit == "DBHZ";
}

// One satellite's records of a signal's system at a common epoch, real and simulated side by side.
struct SatellitePair {
  SatelliteId satellite;
  const SatelliteObservations* real = nullptr;
  const SatelliteObservations* sim = nullptr;
};

std::vector<SatellitePair> pair_satellites(const ObservationEpoch& real,
                                           const ObservationEpoch& sim, GnssSystem system) {
  std::vector<SatellitePair> pairs;
  for (const auto& s : real.satellites) {
    if (s.satellite.system == system) pairs.push_back({s.satellite, &s, nullptr});
  }
  std::sort(pairs.begin(), pairs.end(),
            [](const auto& a, const auto& b) { return a.satellite < b.satellite; });
  pairs.erase(std::unique(pairs.begin(), pairs.end(),
                          [](const auto& a, const auto& b) { return a.satellite == b.satellite; }),
              pairs.end());
  const size_t real_count = pairs.size();
  for (const auto& s : sim.satellites) {
    if (s.satellite.system != system) continue;
    const auto end = pairs.begin() + static_cast<std::ptrdiff_t>(real_count);
    const auto it = std::lower_bound(
        pairs.begin(), end, s.satellite,
        [](const SatellitePair& p, const SatelliteId& id) { return p.satellite < id; });
    if (it != end && it->satellite == s.satellite) {
      if (it->sim == nullptr) it->sim = &s;
    } else {
      pairs.push_back({s.satellite, nullptr, &s});
    }
  }
  return pairs;
}

struct FileView {
  const ObservationFile* file = nullptr;
  std::vector<const ObservationEpoch*> epochs;
};

SignalComparison compare_signal(const Signal& signal, const FileView& real, const FileView& sim,
                                const std::vector<EpochPair>& pairs,
                                const std::map<int, int>& channels, ElevationMask& mask) {
  SignalComparison out;
  out.signal = signal;
  const SignalColumns rc = signal_columns(real.file->header, signal);
  const SignalColumns sc = signal_columns(sim.file->header, signal);
  const bool compare_cn0 =
      strength_in_dbhz(real.file->header) && strength_in_dbhz(sim.file->header);
  const SignalInfo* info = find_signal_info(signal);

  // Wavelength of a satellite's carrier, NaN for an FDMA satellite whose channel is unknown.
  auto wavelength_m = [&](const SatelliteId& satellite) {
    if (info == nullptr) return kNaN;
    int channel = 0;
    if (info->is_fdma()) {
      const auto it = channels.find(satellite.number);
      if (it == channels.end()) return kNaN;
      channel = it->second;
    }
    return constants::kSpeedOfLight_mps / info->carrier_frequency_hz(channel);
  };

  PhaseContinuity real_phase(real.epochs, signal.system, rc.phase);
  PhaseContinuity sim_phase(sim.epochs, signal.system, sc.phase);
  // Phases at the previous common epoch, by satellite number (NaN: absent).
  std::array<double, 256> previous_real_cycles{};
  std::array<double, 256> previous_sim_cycles{};
  previous_real_cycles.fill(kNaN);
  previous_sim_cycles.fill(kNaN);

  std::vector<double> pseudorange_residuals_m, doppler_residuals_mps, phase_residuals_m;
  std::vector<double> pseudorange_diffs_m, doppler_diffs_mps, phase_diffs_m;
  std::vector<SatelliteId> pseudorange_satellites;  // of pseudorange_diffs_m
  std::map<SatelliteId, std::vector<double>> pseudorange_residuals_by_satellite_m;
  double cn0_sum_dbhz = 0.0;
  double cn0_abs_sum_dbhz = 0.0;

  for (size_t k = 0; k < pairs.size(); ++k) {
    const auto& pair = pairs[k];
    const ObservationEpoch& re = *real.epochs[static_cast<size_t>(pair.real_index)];
    const ObservationEpoch& se = *sim.epochs[static_cast<size_t>(pair.sim_index)];
    // Real time tag minus simulated (0 for receivers that tag their epochs on the full second).
    const double tag_offset_s = re.time - se.time;
    real_phase.advance_to(pair.real_index);
    sim_phase.advance_to(pair.sim_index);
    pseudorange_diffs_m.clear();
    pseudorange_satellites.clear();
    doppler_diffs_mps.clear();
    phase_diffs_m.clear();
    std::array<double, 256> current_real_cycles{};
    std::array<double, 256> current_sim_cycles{};
    current_real_cycles.fill(kNaN);
    current_sim_cycles.fill(kNaN);

    for (const auto& sp : pair_satellites(re, se, signal.system)) {
      const std::uint8_t n = sp.satellite.number;
      // Phases are remembered before the mask so a satellite rising through it has a previous one.
      // Doppler to move the real side to the simulated epoch's time when the tags differ:
      // phase changes by D * dt cycles, the pseudorange by -wavelength * D * dt.
      std::optional<double> shift_doppler_hz;
      if (tag_offset_s != 0.0) {
        if (sp.sim != nullptr) shift_doppler_hz = number_at(*sp.sim, sc.doppler);
        if (!shift_doppler_hz && sp.real != nullptr) shift_doppler_hz = number_at(*sp.real, rc.doppler);
      }
      if (sp.real != nullptr) {
        if (auto l = number_at(*sp.real, rc.phase)) {
          current_real_cycles[n] = *l - (shift_doppler_hz ? *shift_doppler_hz * tag_offset_s : 0.0);
        }
      }
      if (sp.sim != nullptr) {
        if (auto l = number_at(*sp.sim, sc.phase)) current_sim_cycles[n] = *l;
      }
      if (!mask.keeps(k, sp.satellite, re.time)) continue;
      const bool real_tracks = sp.real != nullptr && is_tracked(*sp.real, rc);
      const bool sim_tracks = sp.sim != nullptr && is_tracked(*sp.sim, sc);
      out.real_tracked += real_tracks ? 1 : 0;
      out.sim_tracked += sim_tracks ? 1 : 0;
      out.both_tracked += (real_tracks && sim_tracks) ? 1 : 0;
      if (sp.real == nullptr || sp.sim == nullptr) continue;

      const auto real_pr = number_at(*sp.real, rc.code);
      const auto sim_pr = number_at(*sp.sim, sc.code);
      if (real_pr && sim_pr) {
        double shift_m = 0.0;
        if (shift_doppler_hz) {
          const double lambda_m = wavelength_m(sp.satellite);
          if (!std::isnan(lambda_m)) shift_m = lambda_m * *shift_doppler_hz * tag_offset_s;
        }
        pseudorange_diffs_m.push_back(*real_pr + shift_m - *sim_pr);
        pseudorange_satellites.push_back(sp.satellite);
      }

      const auto real_cn0 = number_at(*sp.real, rc.strength);
      const auto sim_cn0 = number_at(*sp.sim, sc.strength);
      if (compare_cn0 && real_cn0 && sim_cn0) {
        ++out.cn0_count;
        cn0_sum_dbhz += *real_cn0 - *sim_cn0;
        cn0_abs_sum_dbhz += std::abs(*real_cn0 - *sim_cn0);
      }

      const auto real_doppler = number_at(*sp.real, rc.doppler);
      const auto sim_doppler = number_at(*sp.sim, sc.doppler);
      const bool has_phase_step =
          k > 0 && !std::isnan(current_real_cycles[n]) && !std::isnan(current_sim_cycles[n]) &&
          !std::isnan(previous_real_cycles[n]) && !std::isnan(previous_sim_cycles[n]) &&
          real_phase.continuous_since(sp.satellite, pairs[k - 1].real_index) &&
          sim_phase.continuous_since(sp.satellite, pairs[k - 1].sim_index);
      if (!(real_doppler && sim_doppler) && !has_phase_step) continue;
      const double lambda_m = wavelength_m(sp.satellite);
      if (std::isnan(lambda_m)) {
        ++out.unknown_channel_satellite_epochs;
        continue;
      }
      // Range rate is -wavelength * Doppler (the Doppler is positive while the satellite
      // approaches).
      if (real_doppler && sim_doppler) {
        doppler_diffs_mps.push_back(-lambda_m * (*real_doppler - *sim_doppler));
      }
      if (has_phase_step) {
        const double real_step_m = lambda_m * (current_real_cycles[n] - previous_real_cycles[n]);
        const double sim_step_m = lambda_m * (current_sim_cycles[n] - previous_sim_cycles[n]);
        phase_diffs_m.push_back(real_step_m - sim_step_m);
      }
    }
    if (!pseudorange_diffs_m.empty()) {
      if (append_residuals(pseudorange_diffs_m, pseudorange_residuals_m)) {
        const size_t first = pseudorange_residuals_m.size() - pseudorange_diffs_m.size();
        for (size_t i = 0; i < pseudorange_satellites.size(); ++i) {
          pseudorange_residuals_by_satellite_m[pseudorange_satellites[i]].push_back(pseudorange_residuals_m[first + i]);
        }
      } else {
        ++out.single_satellite_epochs;
      }
    }
    append_residuals(doppler_diffs_mps, doppler_residuals_mps);
    append_residuals(phase_diffs_m, phase_residuals_m);
    previous_real_cycles = current_real_cycles;
    previous_sim_cycles = current_sim_cycles;
  }

  out.pseudorange_m = residual_statistics(std::move(pseudorange_residuals_m));
  for (auto& [satellite, residuals] : pseudorange_residuals_by_satellite_m) {
    out.pseudorange_by_satellite_m.emplace(satellite, residual_statistics(std::move(residuals)));
  }
  out.doppler_mps = residual_statistics(std::move(doppler_residuals_mps));
  out.phase_difference_m = residual_statistics(std::move(phase_residuals_m));
  if (out.cn0_count > 0) {
    out.cn0_bias_dbhz = cn0_sum_dbhz / static_cast<double>(out.cn0_count);
    out.cn0_mean_abs_difference_dbhz = cn0_abs_sum_dbhz / static_cast<double>(out.cn0_count);
  }
  return out;
}

// The signals to compare, in system then signal order.
Result<std::vector<Signal>> select_signals(const ObservationFile& real, const ObservationFile& sim,
                                           const CompareOptions& options) {
  std::set<GnssSystem> systems(options.systems.begin(), options.systems.end());
  if (systems.empty()) {
    for (const auto& [system, types] : real.header.observation_types) {
      if (sim.header.observation_types.contains(system)) systems.insert(system);
    }
  }
  std::set<Signal> real_signals, sim_signals;
  for (GnssSystem system : systems) {
    real_signals.merge(listed_signals(real.header, system));
    sim_signals.merge(listed_signals(sim.header, system));
  }
  std::vector<Signal> selected;
  if (!options.signals.empty()) {
    for (const auto& signal : options.signals) {
      if (!options.systems.empty() && !systems.contains(signal.system)) {
        return make_error(
            ErrorCode::kInvalidArgument,
            "signal " + signal.to_string() + " does not belong to the selected systems");
      }
      const auto real_listed = listed_signals(real.header, signal.system);
      const auto sim_listed = listed_signals(sim.header, signal.system);
      if (!real_listed.contains(signal) || !sim_listed.contains(signal)) {
        const bool in_real = real_listed.contains(signal);
        return make_error(ErrorCode::kNotFound,
                          fmt::format("signal {}: {} has no {} observations (its {} signals: {})",
                                      signal.to_string(), in_real ? "SIM" : "REAL",
                                      signal.to_string(), system_name(signal.system),
                                      signal_names(in_real ? sim_listed : real_listed)));
      }
      if (std::find(selected.begin(), selected.end(), signal) == selected.end())
        selected.push_back(signal);
    }
    std::sort(selected.begin(), selected.end());
  } else {
    std::set_intersection(real_signals.begin(), real_signals.end(), sim_signals.begin(),
                          sim_signals.end(), std::back_inserter(selected));
  }
  if (selected.empty()) {
    return make_error(ErrorCode::kNotFound,
                      fmt::format("no common signals to compare: REAL has {}; SIM has {}",
                                  signal_names(real_signals), signal_names(sim_signals)));
  }
  return selected;
}

nlohmann::json statistics_json(const ResidualStatistics& s) {
  return {{"count", s.count},
          {"abs_p68", s.abs_p68},
          {"abs_p95", s.abs_p95},
          {"mean", s.mean},
          {"rms", s.rms}};
}

std::string number_cell(double value, int decimals) {
  return std::isnan(value) ? std::string("-") : fmt::format("{:.{}f}", value, decimals);
}

}  // namespace

ResidualStatistics residual_statistics(std::vector<double> residuals) {
  ResidualStatistics s;
  s.count = residuals.size();
  if (residuals.empty()) return s;
  double sum = 0.0;
  double sum_squares = 0.0;
  for (double r : residuals) {
    sum += r;
    sum_squares += r * r;
  }
  const auto n = static_cast<double>(residuals.size());
  s.mean = sum / n;
  s.rms = std::sqrt(sum_squares / n);
  for (double& r : residuals) r = std::abs(r);
  std::sort(residuals.begin(), residuals.end());
  // Linear interpolation between order statistics at rank p (n - 1).
  auto percentile = [&](double p) {
    const double rank = p * (n - 1.0);
    const auto lower = static_cast<size_t>(std::floor(rank));
    const size_t upper = std::min(lower + 1, residuals.size() - 1);
    return residuals[lower] +
           (rank - static_cast<double>(lower)) * (residuals[upper] - residuals[lower]);
  };
  s.abs_p68 = percentile(0.68);
  s.abs_p95 = percentile(0.95);
  return s;
}

double SignalComparison::real_in_sim_fraction() const {
  return real_tracked == 0 ? kNaN
                           : static_cast<double>(both_tracked) / static_cast<double>(real_tracked);
}

double SignalComparison::sim_in_real_fraction() const {
  return sim_tracked == 0 ? kNaN
                          : static_cast<double>(both_tracked) / static_cast<double>(sim_tracked);
}

Result<ComparisonReport> compare_observations(const ObservationFile& real,
                                              const ObservationFile& sim,
                                              const CompareOptions& options) {
  if (!std::isfinite(options.min_elevation_deg) || options.min_elevation_deg < -90.0 ||
      options.min_elevation_deg > 90.0) {
    return make_error(
        ErrorCode::kInvalidArgument,
        fmt::format("minimum elevation {} deg is outside -90..90", options.min_elevation_deg));
  }
  if (!std::isfinite(options.epoch_tolerance_s) || options.epoch_tolerance_s < 0.0 ||
      options.epoch_tolerance_s > 0.5) {
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("epoch tolerance {} s is outside 0..0.5", options.epoch_tolerance_s));
  }
  FileView real_view{&real, observation_epochs(real)};
  FileView sim_view{&sim, observation_epochs(sim)};
  if (real_view.epochs.empty() || sim_view.epochs.empty()) {
    return make_error(ErrorCode::kOutOfRange, std::string("no common epochs: ") +
                                                  (real_view.epochs.empty() ? "REAL" : "SIM") +
                                                  " has no observation epoch");
  }
  const auto pairs = match_epochs(real_view.epochs, sim_view.epochs, options.epoch_tolerance_s);
  if (pairs.empty()) {
    return make_error(
        ErrorCode::kOutOfRange,
        fmt::format(
            "no common epochs (matched to {} ms): REAL covers {} to {}, SIM covers {} to {} GPST",
            options.epoch_tolerance_s * 1e3,
            time_text(real_view.epochs.front()->time), time_text(real_view.epochs.back()->time),
            time_text(sim_view.epochs.front()->time), time_text(sim_view.epochs.back()->time)));
  }
  auto signals = select_signals(real, sim, options);
  if (!signals) return signals.error();

  Eigen::Vector3d station_ecef_m = Eigen::Vector3d::Zero();
  if (options.satellite_source != nullptr && !options.receiver_position) {
    const auto& approx = real.header.approx_position_ecef_m;
    if (!approx || Eigen::Vector3d((*approx)[0], (*approx)[1], (*approx)[2]).norm() <
                       kMinimumStationRadius_m) {
      return make_error(
          ErrorCode::kNotFound,
          "REAL has no usable APPROX POSITION XYZ in its header: the elevation mask needs the "
          "receiver position");
    }
    station_ecef_m = Eigen::Vector3d((*approx)[0], (*approx)[1], (*approx)[2]);
  }
  ElevationMask mask(options.satellite_source, station_ecef_m, options.min_elevation_deg,
                     pairs.size(), options.receiver_position);

  ComparisonReport report;
  report.real_epochs = real_view.epochs.size();
  report.sim_epochs = sim_view.epochs.size();
  report.common_epochs = pairs.size();
  report.first_common_epoch = real_view.epochs[static_cast<size_t>(pairs.front().real_index)]->time;
  report.last_common_epoch = real_view.epochs[static_cast<size_t>(pairs.back().real_index)]->time;
  report.elevation_mask_applied = options.satellite_source != nullptr;
  report.min_elevation_deg = options.min_elevation_deg;
  report.mask_from_receiver_track = report.elevation_mask_applied && static_cast<bool>(options.receiver_position);
  const auto channels = glonass_channels(real.header, sim.header);
  for (const auto& signal : *signals) {
    report.signals.push_back(compare_signal(signal, real_view, sim_view, pairs, channels, mask));
  }
  report.below_mask_satellite_epochs = mask.below_mask();
  report.without_position_satellite_epochs = mask.without_position();
  report.without_position_by_system = mask.without_position_by_system();
  return report;
}

Result<ComparisonReport> compare_observation_files(const std::filesystem::path& real_path,
                                                   const std::filesystem::path& sim_path,
                                                   const CompareOptions& options) {
  auto real = read_rinex_obs(real_path);
  if (!real) return real.error().with_context("REAL");
  auto sim = read_rinex_obs(sim_path);
  if (!sim) return sim.error().with_context("SIM");
  auto report = compare_observations(*real, *sim, options);
  if (!report) return report.error();
  report->real_name = real_path.string();
  report->sim_name = sim_path.string();
  for (const auto* file : {&*real, &*sim}) {
    report->warnings.insert(report->warnings.end(), file->warnings.begin(), file->warnings.end());
  }
  return report;
}

Result<std::vector<GnssSystem>> parse_system_letters(std::string_view text) {
  std::vector<GnssSystem> systems;
  for (char c : text) {
    if (c == ',' || c == ' ') continue;
    auto system = system_from_letter(c);
    if (!system) return system.error().with_context("systems '" + std::string(text) + "'");
    if (std::find(systems.begin(), systems.end(), *system) == systems.end())
      systems.push_back(*system);
  }
  if (systems.empty())
    return make_error(ErrorCode::kInvalidArgument,
                      "systems: empty list (expected letters such as GE)");
  return systems;
}

Result<std::vector<Signal>> parse_signal_list(std::string_view text) {
  std::vector<Signal> signals;
  size_t start = 0;
  while (start <= text.size()) {
    size_t end = text.find(',', start);
    if (end == std::string_view::npos) end = text.size();
    std::string_view item = text.substr(start, end - start);
    while (!item.empty() && item.front() == ' ') item.remove_prefix(1);
    while (!item.empty() && item.back() == ' ') item.remove_suffix(1);
    if (!item.empty()) {
      auto signal = Signal::parse(item);
      if (!signal) return signal.error();
      signals.push_back(*signal);
    }
    start = end + 1;
  }
  if (signals.empty())
    return make_error(ErrorCode::kInvalidArgument, "signals: empty list (expected e.g. G1C,E1C)");
  return signals;
}

std::string format_comparison_table(const ComparisonReport& r) {
  std::string out;
  auto line = std::back_inserter(out);
  fmt::format_to(line, "# REAL: {} ({} epochs)\n", r.real_name.empty() ? "-" : r.real_name,
                 r.real_epochs);
  fmt::format_to(line, "# SIM:  {} ({} epochs)\n", r.sim_name.empty() ? "-" : r.sim_name,
                 r.sim_epochs);
  fmt::format_to(line, "# common epochs: {}, {} to {} GPST\n", r.common_epochs,
                 time_text(r.first_common_epoch), time_text(r.last_common_epoch));
  if (r.elevation_mask_applied) {
    std::string per_system;
    for (const auto& [system, count] : r.without_position_by_system) {
      per_system += fmt::format("{}{} {}", per_system.empty() ? " (" : ", ", system_name(system), count);
    }
    if (!per_system.empty()) per_system += ")";
    fmt::format_to(line,
                   "# elevation mask: {:.1f} deg seen from {}; dropped {} "
                   "satellite-epochs below it and {} without an ephemeris{}\n",
                   r.min_elevation_deg,
                   r.mask_from_receiver_track ? "the receiver's track" : "REAL's APPROX POSITION XYZ",
                   r.below_mask_satellite_epochs,
                   r.without_position_satellite_epochs, per_system);
  } else {
    fmt::format_to(line, "# elevation mask: none (no navigation data to compute elevations)\n");
  }
  out +=
      "# residual = real - sim - median over the system's satellites at the epoch; p68/p95 of "
      "|residual|\n"
      "# pr: pseudorange; dop: Doppler as range rate; dphi: carrier phase change between common "
      "epochs;\n"
      "# cn0: C/N0 (bias = mean real - sim, mad = mean |real - sim|); real_in_sim/sim_in_real: "
      "tracked overlap\n";

  const std::vector<std::string> header = {"signal",          "pr_n",           "pr_p68_m",
                                           "pr_p95_m",        "pr_mean_m",      "pr_rms_m",
                                           "dop_n",           "dop_p68_mps",    "dop_p95_mps",
                                           "dop_mean_mps",    "dop_rms_mps",    "dphi_n",
                                           "dphi_p68_m",      "dphi_p95_m",     "dphi_mean_m",
                                           "dphi_rms_m",      "cn0_n",          "cn0_bias_dbhz",
                                           "cn0_mad_dbhz",    "real_tracked",   "sim_tracked",
                                           "real_in_sim_pct", "sim_in_real_pct"};
  std::vector<std::vector<std::string>> rows;
  for (const auto& s : r.signals) {
    auto stats = [](std::vector<std::string>& row, const ResidualStatistics& st, int decimals) {
      row.push_back(std::to_string(st.count));
      row.push_back(number_cell(st.abs_p68, decimals));
      row.push_back(number_cell(st.abs_p95, decimals));
      row.push_back(number_cell(st.mean, decimals));
      row.push_back(number_cell(st.rms, decimals));
    };
    std::vector<std::string> row = {s.signal.to_string()};
    stats(row, s.pseudorange_m, 3);
    stats(row, s.doppler_mps, 4);
    stats(row, s.phase_difference_m, 4);
    row.push_back(std::to_string(s.cn0_count));
    row.push_back(number_cell(s.cn0_bias_dbhz, 2));
    row.push_back(number_cell(s.cn0_mean_abs_difference_dbhz, 2));
    row.push_back(std::to_string(s.real_tracked));
    row.push_back(std::to_string(s.sim_tracked));
    row.push_back(number_cell(100.0 * s.real_in_sim_fraction(), 1));
    row.push_back(number_cell(100.0 * s.sim_in_real_fraction(), 1));
    rows.push_back(std::move(row));
  }
  std::vector<size_t> widths(header.size());
  for (size_t c = 0; c < header.size(); ++c) {
    widths[c] = header[c].size();
    for (const auto& row : rows) widths[c] = std::max(widths[c], row[c].size());
  }
  auto emit = [&](const std::vector<std::string>& cells) {
    std::string text;
    for (size_t c = 0; c < cells.size(); ++c) {
      // The signal name is left-aligned, numbers right-aligned.
      text += c == 0 ? fmt::format("{:<{}}", cells[c], widths[c])
                     : fmt::format("  {:>{}}", cells[c], widths[c]);
    }
    out += text + "\n";
  };
  emit(header);
  for (const auto& row : rows) emit(row);
  return out;
}

std::string comparison_to_json(const ComparisonReport& r) {
  nlohmann::json j;
  j["real"] = {{"file", r.real_name}, {"epochs", r.real_epochs}};
  j["sim"] = {{"file", r.sim_name}, {"epochs", r.sim_epochs}};
  j["warnings"] = r.warnings;
  j["common_epochs"] = r.common_epochs;
  j["first_common_epoch_gpst"] = r.first_common_epoch.to_iso8601(TimeScale::kGpst, 3);
  j["last_common_epoch_gpst"] = r.last_common_epoch.to_iso8601(TimeScale::kGpst, 3);
  nlohmann::json without_position = nlohmann::json::object();
  for (const auto& [system, count] : r.without_position_by_system) {
    without_position[std::string(system_name(system))] = count;
  }
  j["elevation_mask"] = {
      {"applied", r.elevation_mask_applied},
      {"min_elevation_deg",
       r.elevation_mask_applied ? nlohmann::json(r.min_elevation_deg) : nlohmann::json()},
      {"below_mask_satellite_epochs", r.below_mask_satellite_epochs},
      {"without_position_satellite_epochs", r.without_position_satellite_epochs},
      {"from_receiver_track", r.mask_from_receiver_track},
      {"without_position_by_system", without_position}};
  j["residual_definition"] =
      "real - sim minus the per-epoch median over the system's satellites; abs_p68/abs_p95 are "
      "percentiles of |residual|; doppler as range rate (-wavelength * D)";
  nlohmann::json rows = nlohmann::json::array();
  for (const auto& s : r.signals) {
    // Per satellite, with its block from the catalogue at the first common epoch ("" when unknown).
    nlohmann::json by_satellite = nlohmann::json::object();
    for (const auto& [satellite, stats] : s.pseudorange_by_satellite_m) {
      nlohmann::json entry = statistics_json(stats);
      const auto info = satellite_info(satellite, r.first_common_epoch);
      entry["block"] = info ? info->block : std::string();
      by_satellite[satellite.to_string()] = std::move(entry);
    }
    rows.push_back({{"signal", s.signal.to_string()},
                    {"system", std::string(system_name(s.signal.system))},
                    {"pseudorange_m", statistics_json(s.pseudorange_m)},
                    {"pseudorange_by_satellite_m", std::move(by_satellite)},
                    {"doppler_mps", statistics_json(s.doppler_mps)},
                    {"phase_difference_m", statistics_json(s.phase_difference_m)},
                    {"cn0_dbhz",
                     {{"count", s.cn0_count},
                      {"bias", s.cn0_bias_dbhz},
                      {"mean_abs_difference", s.cn0_mean_abs_difference_dbhz}}},
                    {"overlap",
                     {{"real_tracked", s.real_tracked},
                      {"sim_tracked", s.sim_tracked},
                      {"both_tracked", s.both_tracked},
                      {"real_in_sim", s.real_in_sim_fraction()},
                      {"sim_in_real", s.sim_in_real_fraction()}}},
                    {"single_satellite_epochs", s.single_satellite_epochs},
                    {"unknown_channel_satellite_epochs", s.unknown_channel_satellite_epochs}});
  }
  j["signals"] = std::move(rows);
  return j.dump(2) + "\n";
}

}  // namespace skytrace::io
