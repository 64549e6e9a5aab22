// Interpolation of precise orbits (Lagrange, Neville's scheme with its derivative) and clocks
// (linear), and the satellite state built from them.
#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <utility>

#include "skytrace/core/constants.hpp"
#include "skytrace/orbits/precise.hpp"
#include "skytrace/orbits/precise_cache.hpp"

namespace skytrace::orbits {
namespace {

constexpr int kMinPoints = 2;
constexpr int kMaxPoints = 20;
// Times closer than this are the same instant (file epochs carry at most 8 decimals).
constexpr double kSameTime_s = 1e-6;
// Consecutive epochs further apart than this many intervals leave a gap.
constexpr double kGapIntervals = 1.5;
// Clock samples further apart than this many intervals are not interpolated between.
constexpr double kClockNeighbourIntervals = 2.0;
constexpr double kOmega_radps = constants::kEarthRotationRateGps_radps;

std::string time_text(const GnssTime& t) {
  const bool whole = std::abs(t.fraction_s()) < 1e-9;
  return t.to_iso8601(TimeScale::kGpst, whole ? 0 : 3);
}

// The Lagrange polynomial through (x_k, y_k), k < n, and its derivative with respect to x, both
// at x = 0 (Neville's recursion differentiated term by term).
void neville_at_zero(const std::array<double, kMaxPoints>& x, std::array<Eigen::Vector3d, kMaxPoints>& y, size_t n,
                     Eigen::Vector3d& value, Eigen::Vector3d& derivative) {
  std::array<Eigen::Vector3d, kMaxPoints> d;
  for (size_t k = 0; k < n; ++k) d[k].setZero();
  for (size_t m = 1; m < n; ++m) {
    for (size_t i = 0; i + m < n; ++i) {
      const size_t j = i + m;
      const double denominator = x[i] - x[j];
      const Eigen::Vector3d p = (x[i] * y[i + 1] - x[j] * y[i]) / denominator;
      d[i] = (y[i] - x[j] * d[i] - y[i + 1] + x[i] * d[i + 1]) / denominator;
      y[i] = p;
    }
  }
  value = y[0];
  derivative = d[0];
}

// Coordinates in the Earth-fixed frame at time t of a vector given in the Earth-fixed frame of
// an epoch dt_s = t - epoch earlier (the frame has turned by omega dt_s since).
// The Earth's rotation over dt_s as its cosine and sine.
struct FrameRotation {
  double c = 1.0, s = 0.0;
  FrameRotation() = default;
  explicit FrameRotation(double dt_s) : c(std::cos(kOmega_radps * dt_s)), s(std::sin(kOmega_radps * dt_s)) {}
  [[nodiscard]] Eigen::Vector3d operator()(const Eigen::Vector3d& v) const {
    return {c * v.x() + s * v.y(), -s * v.x() + c * v.y(), v.z()};
  }
};

Eigen::Vector3d omega_cross(const Eigen::Vector3d& r) { return {-kOmega_radps * r.y(), kOmega_radps * r.x(), 0.0}; }

// A two-body (Keplerian) orbit through a position and velocity: its position dt_s later, with the
// f and g functions of the eccentric anomaly difference (elliptic orbits).
struct TwoBody {
  Eigen::Vector3d r0_m, v0_mps;
  double radius0_m = 0.0, a_m = 0.0, n_radps = 0.0, e_cos_e0 = 0.0, e_sin_e0 = 0.0;

  static std::optional<TwoBody> through(const Eigen::Vector3d& r_m, const Eigen::Vector3d& v_mps) {
    constexpr double gm = constants::kGmGps_m3ps2;
    TwoBody k;
    k.r0_m = r_m;
    k.v0_mps = v_mps;
    k.radius0_m = r_m.norm();
    const double inverse_a = 2.0 / k.radius0_m - v_mps.squaredNorm() / gm;
    if (!(inverse_a > 0.0)) return std::nullopt;  // not elliptic
    k.a_m = 1.0 / inverse_a;
    k.n_radps = std::sqrt(gm * inverse_a * inverse_a * inverse_a);
    k.e_cos_e0 = 1.0 - k.radius0_m / k.a_m;
    k.e_sin_e0 = r_m.dot(v_mps) / std::sqrt(gm * k.a_m);
    return k;
  }

  [[nodiscard]] Eigen::Vector3d position_at(double dt_s) const {
    // Kepler's equation in differences: n dt = dE - e cos E0 sin dE + e sin E0 (1 - cos dE).
    const double mean_s = n_radps * dt_s;
    double de = mean_s;
    for (int iteration = 0; iteration < 20; ++iteration) {
      const double sin_de = std::sin(de), cos_de = std::cos(de);
      const double residual = de - e_cos_e0 * sin_de + e_sin_e0 * (1.0 - cos_de) - mean_s;
      const double slope = 1.0 - e_cos_e0 * cos_de + e_sin_e0 * sin_de;
      const double step = residual / slope;
      de -= step;
      if (std::abs(step) < 1e-15) break;
    }
    const double c = std::cos(de), s = std::sin(de);
    const double f = 1.0 - a_m / radius0_m * (1.0 - c);
    const double g = dt_s - (de - s) / n_radps;
    return f * r0_m + g * v0_mps;
  }
};

// Linear clock interpolation over a time-sorted sequence (SP3 epochs or clock-file samples).
// Neighbours must be at most kClockNeighbourIntervals apart; beyond the data it extrapolates by
// up to one interval, only at the ends of the whole product.
template <typename TimeAt, typename ValueAt>
Result<PreciseEphemerides::Clock> interpolate_clock(size_t count, TimeAt time_at, ValueAt value_at, const GnssTime& t,
                                                    double interval_s, const GnssTime& product_first,
                                                    const GnssTime& product_last,
                                                    const std::function<Error(ErrorCode, const std::string&)>& fail) {
  const double reach_s = kClockNeighbourIntervals * interval_s + kSameTime_s;
  // upper: first index whose time is after t.
  size_t lo = 0, hi = count;
  while (lo < hi) {
    const size_t mid = (lo + hi) / 2;
    if (time_at(mid) - t > kSameTime_s) hi = mid; else lo = mid + 1;
  }
  const size_t upper = lo;
  // Nearest valid samples at or before t and after t, within reach.
  std::optional<size_t> previous, next;
  for (size_t k = upper; k-- > 0;) {
    if (t - time_at(k) > reach_s) break;
    if (value_at(k)) { previous = k; break; }
  }
  for (size_t k = upper; k < count; ++k) {
    if (time_at(k) - t > reach_s) break;
    if (value_at(k)) { next = k; break; }
  }
  auto valid_before = [&](size_t k) -> std::optional<size_t> {
    for (size_t j = k; j-- > 0;) {
      if (time_at(k) - time_at(j) > reach_s) break;
      if (value_at(j)) return j;
    }
    return std::nullopt;
  };
  auto valid_after = [&](size_t k) -> std::optional<size_t> {
    for (size_t j = k + 1; j < count; ++j) {
      if (time_at(j) - time_at(k) > reach_s) break;
      if (value_at(j)) return j;
    }
    return std::nullopt;
  };
  auto line = [&](size_t a, size_t b) {
    const double slope = (*value_at(b) - *value_at(a)) / (time_at(b) - time_at(a));
    return PreciseEphemerides::Clock{*value_at(a) + slope * (t - time_at(a)), slope};
  };

  if (previous && std::abs(t - time_at(*previous)) <= kSameTime_s) {  // on a sample
    if (auto after = valid_after(*previous)) return line(*previous, *after);
    if (auto before = valid_before(*previous)) return line(*before, *previous);
    return fail(ErrorCode::kOutOfRange, "isolated clock sample: no neighbour within " +
                                            std::to_string(static_cast<int>(reach_s)) + " s for the drift");
  }
  if (previous && next) {
    if (time_at(*next) - time_at(*previous) <= reach_s) return line(*previous, *next);
  }
  if (previous && !next && std::abs(time_at(*previous) - product_last) <= kSameTime_s &&
      t - time_at(*previous) <= interval_s + kSameTime_s) {
    if (auto before = valid_before(*previous)) return line(*before, *previous);
  }
  if (next && !previous && std::abs(time_at(*next) - product_first) <= kSameTime_s &&
      time_at(*next) - t <= interval_s + kSameTime_s) {
    if (auto after = valid_after(*next)) return line(*next, *after);
  }
  if (t < product_first - interval_s || t > product_last + interval_s) {
    return fail(ErrorCode::kOutOfRange, "the clocks cover " + time_text(product_first) + " to " +
                                            time_text(product_last) + " GPST");
  }
  std::string why = "no clock samples within " + std::to_string(static_cast<int>(std::lround(reach_s))) +
                    " s on both sides (nominal interval " + std::to_string(static_cast<int>(std::lround(interval_s))) +
                    " s)";
  if (previous) why += "; previous sample " + time_text(time_at(*previous));
  if (next) why += "; next sample " + time_text(time_at(*next));
  return fail(ErrorCode::kOutOfRange, why);
}

// Most frequent spacing of a sample series (rounded to 1 ms), or 0 with fewer than two samples.
double nominal_spacing_s(const std::vector<ClockSample>& samples) {
  std::map<long long, int> histogram;
  for (size_t k = 1; k < samples.size(); ++k) {
    const double spacing_s = samples[k].time - samples[k - 1].time;
    if (spacing_s > 0.0) ++histogram[std::llround(spacing_s * 1000.0)];
  }
  long long best_ms = 0;
  int best_count = 0;
  for (const auto& [spacing_ms, count] : histogram) {
    if (count > best_count) {
      best_count = count;
      best_ms = spacing_ms;
    }
  }
  return static_cast<double>(best_ms) / 1000.0;
}

// Spans of [from, to] in which works(t) is false. Probes at from, at every grid time inside
// (from, to) (grid sorted), at to, and halfway between consecutive probes; a span runs from the
// last probe that worked before it (or from) to the first one after it (or to).
template <typename Works>
std::vector<PreciseEphemerides::Span> failing_spans(const std::vector<GnssTime>& grid, const GnssTime& from,
                                                    const GnssTime& to, Works works) {
  std::vector<GnssTime> knots{from};
  auto inside = std::lower_bound(grid.begin(), grid.end(), from);
  for (; inside != grid.end() && *inside < to; ++inside) {
    if (*inside - knots.back() > kSameTime_s) knots.push_back(*inside);
  }
  if (to - knots.back() > kSameTime_s) knots.push_back(to);
  std::vector<PreciseEphemerides::Span> gaps;
  GnssTime last_working = from;
  bool in_gap = false;
  auto visit = [&](const GnssTime& t) {
    const bool ok = works(t);
    if (!ok && !in_gap) {
      in_gap = true;
    } else if (ok && in_gap) {
      gaps.push_back({last_working, t});
      in_gap = false;
    }
    if (ok) last_working = t;
  };
  for (size_t k = 0; k < knots.size(); ++k) {
    visit(knots[k]);
    if (k + 1 < knots.size()) visit(knots[k] + 0.5 * (knots[k + 1] - knots[k]));
  }
  if (in_gap) gaps.push_back({last_working, to});
  return gaps;
}

}  // namespace

Result<PreciseEphemerides> PreciseEphemerides::create(Sp3Data orbits, std::optional<RinexClockData> clocks,
                                                      PreciseOptions options) {
  if (options.interpolation_points < kMinPoints || options.interpolation_points > kMaxPoints) {
    return make_error(ErrorCode::kInvalidArgument, "interpolation_points must be " + std::to_string(kMinPoints) +
                                                       " to " + std::to_string(kMaxPoints) + ", got " +
                                                       std::to_string(options.interpolation_points));
  }
  if (orbits.epochs.empty()) return make_error(ErrorCode::kInvalidArgument, "SP3 data hold no epochs");
  // Data built by hand must keep the layout the readers produce (lookups rely on it).
  for (size_t k = 1; k < orbits.epochs.size(); ++k) {
    if (!(orbits.epochs[k] - orbits.epochs[k - 1] > kSameTime_s)) {
      return make_error(ErrorCode::kInvalidArgument, "SP3 data: epochs not strictly increasing at index " +
                                                         std::to_string(k));
    }
  }
  if (orbits.records.size() != orbits.satellites.size() ||
      !std::is_sorted(orbits.satellites.begin(), orbits.satellites.end()) ||
      std::adjacent_find(orbits.satellites.begin(), orbits.satellites.end()) != orbits.satellites.end()) {
    return make_error(ErrorCode::kInvalidArgument, "SP3 data: satellites must be sorted, unique and have records");
  }
  for (size_t k = 0; k < orbits.records.size(); ++k) {
    if (orbits.records[k].size() != orbits.epochs.size()) {
      return make_error(ErrorCode::kInvalidArgument, "SP3 data: records of " + orbits.satellites[k].to_string() +
                                                         " do not match the epochs");
    }
  }
  if (clocks) {
    for (const auto& [satellite, samples] : clocks->satellite_clocks) {
      for (size_t k = 1; k < samples.size(); ++k) {
        if (!(samples[k].time - samples[k - 1].time > kSameTime_s)) {
          return make_error(ErrorCode::kInvalidArgument, "clock data of " + satellite.to_string() +
                                                             ": samples not strictly increasing in time");
        }
      }
    }
  }
  if (!(orbits.interval_s > 0.0)) {
    // Estimate from the epochs when the header gave none.
    double smallest_s = 0.0;
    for (size_t k = 1; k < orbits.epochs.size(); ++k) {
      const double spacing_s = orbits.epochs[k] - orbits.epochs[k - 1];
      if (smallest_s == 0.0 || spacing_s < smallest_s) smallest_s = spacing_s;
    }
    if (!(smallest_s > 0.0)) return make_error(ErrorCode::kInvalidArgument, "SP3 data: epoch interval unknown");
    orbits.interval_s = smallest_s;
  }
  return PreciseEphemerides(std::move(orbits), std::move(clocks), options);
}

PreciseEphemerides::PreciseEphemerides(Sp3Data orbits, std::optional<RinexClockData> clocks, PreciseOptions options)
    : orbits_(std::move(orbits)), clocks_(std::move(clocks)), options_(options) {
  if (!clocks_) return;
  bool first = true;
  for (const auto& [satellite, samples] : clocks_->satellite_clocks) {
    if (samples.empty()) continue;
    clock_interval_s_[satellite] = nominal_spacing_s(samples);
    if (first || samples.front().time < clock_first_) clock_first_ = samples.front().time;
    if (first || samples.back().time > clock_last_) clock_last_ = samples.back().time;
    first = false;
  }
}

std::string PreciseEphemerides::orbit_coverage() const {
  return "the SP3 data cover " + time_text(orbits_.epochs.front()) + " to " + time_text(orbits_.epochs.back()) +
         " GPST";
}

Result<PreciseEphemerides::Orbit> PreciseEphemerides::orbit(const SatelliteId& satellite, const GnssTime& t) const {
  auto fail = [&](ErrorCode code, const std::string& why) {
    return make_error(code, "no precise orbit for " + satellite.to_string() + " at " + time_text(t) + " GPST (" +
                                why + ")");
  };
  const auto* series = orbits_.series(satellite);
  if (series == nullptr) return fail(ErrorCode::kNotFound, "satellite not in the SP3 data");
  const auto& epochs = orbits_.epochs;
  const size_t count = epochs.size();
  const double interval_s = orbits_.interval_s;
  const double gap_s = kGapIntervals * interval_s;
  const auto n = static_cast<size_t>(options_.interpolation_points);

  if (t - epochs.front() < -interval_s - kSameTime_s || t - epochs.back() > interval_s + kSameTime_s) {
    return fail(ErrorCode::kOutOfRange, orbit_coverage());
  }
  // [lo, hi]: the samples bracketing t (equal when t is on a sample or beyond the data).
  const size_t upper = static_cast<size_t>(
      std::upper_bound(epochs.begin(), epochs.end(), t) - epochs.begin());
  size_t lo = 0, hi = 0;
  if (upper == 0) {
    lo = hi = 0;
  } else if (upper == count) {
    lo = hi = count - 1;
  } else {
    lo = upper - 1;
    hi = upper;
  }
  if (std::abs(t - epochs[lo]) <= kSameTime_s) hi = lo;
  if (std::abs(epochs[hi] - t) <= kSameTime_s) lo = hi;
  auto valid = [&](size_t k) { return (*series)[k].has_position; };
  if (!valid(lo) || !valid(hi)) {
    const size_t missing = valid(lo) ? hi : lo;
    return fail(ErrorCode::kOutOfRange, "position missing at " + time_text(epochs[missing]) + "; " + orbit_coverage());
  }
  if (epochs[hi] - epochs[lo] > gap_s) {
    return fail(ErrorCode::kOutOfRange, "gap in the SP3 epochs from " + time_text(epochs[lo]) + " to " +
                                            time_text(epochs[hi]));
  }
  // The run of consecutive valid samples around the bracket (only as far as a window needs).
  size_t run_lo = lo, run_hi = hi;
  while (run_lo > 0 && lo - run_lo < n && valid(run_lo - 1) && epochs[run_lo] - epochs[run_lo - 1] <= gap_s) --run_lo;
  while (run_hi + 1 < count && run_hi - hi < n && valid(run_hi + 1) && epochs[run_hi + 1] - epochs[run_hi] <= gap_s) {
    ++run_hi;
  }
  if (run_hi - run_lo + 1 < n) {
    return fail(ErrorCode::kOutOfRange, "only " + std::to_string(run_hi - run_lo + 1) +
                                            " consecutive samples from " + time_text(epochs[run_lo]) + " to " +
                                            time_text(epochs[run_hi]) + ", " + std::to_string(n) + " needed");
  }
  // Centre the window: half of the points at or before t, half after, clamped to the run.
  const long wanted = static_cast<long>(lo) + 1 - static_cast<long>((n + 1) / 2);
  const long start = std::clamp(wanted, static_cast<long>(run_lo), static_cast<long>(run_hi + 1 - n));

  std::array<double, kMaxPoints> x{};
  std::array<Eigen::Vector3d, kMaxPoints> y;
  // The samples' positions in the frame of t (kept for the two-body passes below).
  std::array<Eigen::Vector3d, kMaxPoints> position_in_frame;
  std::array<FrameRotation, kMaxPoints> rotation;
  bool all_velocities = options_.use_velocity_records;
  const bool inertial = options_.frame == InterpolationFrame::kInertial;
  for (size_t k = 0; k < n; ++k) {
    const size_t e = static_cast<size_t>(start) + k;
    const double dt_s = t - epochs[e];
    x[k] = -dt_s / interval_s;  // normalised abscissa keeps the polynomial well conditioned
    const Sp3Record& r = (*series)[e];
    if (inertial) rotation[k] = FrameRotation(dt_s);
    position_in_frame[k] = inertial ? rotation[k](r.position_m) : r.position_m;
    y[k] = position_in_frame[k];
    all_velocities = all_velocities && r.has_velocity;
  }
  Orbit out;
  Eigen::Vector3d derivative;
  neville_at_zero(x, y, n, out.position_m, derivative);
  Eigen::Vector3d velocity_in_frame = derivative / interval_s;  // d/dx -> d/dt
  if (all_velocities) {
    for (size_t k = 0; k < n; ++k) {
      const size_t e = static_cast<size_t>(start) + k;
      const Sp3Record& r = (*series)[e];
      y[k] = inertial ? rotation[k](r.velocity_mps + omega_cross(r.position_m)) : r.velocity_mps;
    }
    Eigen::Vector3d unused;
    neville_at_zero(x, y, n, velocity_in_frame, unused);
  }
  if (inertial && options_.two_body_reference) {
    // Further passes on the residuals from the two-body orbit through the current estimate: they
    // are small and smooth (perturbations), so the polynomial's truncation error nearly vanishes,
    // notably for eccentric orbits and near the ends of the data. t itself lies on the
    // reference, so each pass adds the interpolated residual to the estimate. A poor first
    // estimate (extrapolation) needs a second pass or third pass.
    constexpr int kMaxPasses = 4;
    constexpr double kConverged_m = 1e-5;
    std::array<Eigen::Vector3d, kMaxPoints> residual;
    for (int pass = 0; pass < kMaxPasses; ++pass) {
      const auto reference = TwoBody::through(out.position_m, velocity_in_frame);
      if (!reference) break;
      for (size_t k = 0; k < n; ++k) {
        const size_t e = static_cast<size_t>(start) + k;
        residual[k] = position_in_frame[k] - reference->position_at(-(t - epochs[e]));
      }
      Eigen::Vector3d residual_here, residual_rate;
      neville_at_zero(x, residual, n, residual_here, residual_rate);
      out.position_m += residual_here;
      if (!all_velocities) velocity_in_frame += residual_rate / interval_s;
      if (residual_here.norm() < kConverged_m) break;
    }
  }
  // In the inertial variant the polynomial describes motion in a non-rotating frame: remove the
  // frame rotation to get the velocity relative to the Earth-fixed frame.
  out.velocity_mps = inertial ? Eigen::Vector3d(velocity_in_frame - omega_cross(out.position_m)) : velocity_in_frame;
  return out;
}

Result<PreciseEphemerides::Clock> PreciseEphemerides::sp3_clock(const SatelliteId& satellite, const GnssTime& t) const {
  auto fail = [&](ErrorCode code, const std::string& why) {
    return make_error(code, "no precise clock for " + satellite.to_string() + " at " + time_text(t) +
                                " GPST in the SP3 data (" + why + ")");
  };
  const auto* series = orbits_.series(satellite);
  if (series == nullptr) return fail(ErrorCode::kNotFound, "satellite not in the SP3 data");
  const auto& epochs = orbits_.epochs;
  return interpolate_clock(
      epochs.size(), [&](size_t k) { return epochs[k]; },
      [&](size_t k) -> std::optional<double> {
        const Sp3Record& r = (*series)[k];
        return r.has_clock ? std::optional<double>(r.clock_s) : std::nullopt;
      },
      t, orbits_.interval_s, epochs.front(), epochs.back(), fail);
}

Result<PreciseEphemerides::Clock> PreciseEphemerides::file_clock(const SatelliteId& satellite,
                                                                 const std::vector<ClockSample>& samples,
                                                                 const GnssTime& t) const {
  auto fail = [&](ErrorCode code, const std::string& why) {
    return make_error(code, "no precise clock for " + satellite.to_string() + " at " + time_text(t) +
                                " GPST in the clock file (" + why + ")");
  };
  const auto it = clock_interval_s_.find(satellite);
  const double interval_s = it != clock_interval_s_.end() && it->second > 0.0 ? it->second : 30.0;
  return interpolate_clock(
      samples.size(), [&](size_t k) { return samples[k].time; },
      [&](size_t k) { return std::optional<double>(samples[k].bias_s); }, t, interval_s, clock_first_, clock_last_,
      fail);
}

Result<PreciseEphemerides::Clock> PreciseEphemerides::clock(const SatelliteId& satellite, const GnssTime& t) const {
  if (clocks_) {
    const auto* samples = clocks_->series(satellite);
    if (samples != nullptr && !samples->empty()) {
      auto from_file = file_clock(satellite, *samples, t);
      if (from_file || !options_.sp3_clock_fallback) return from_file;
    } else if (!options_.sp3_clock_fallback) {
      return make_error(ErrorCode::kNotFound, "no precise clock for " + satellite.to_string() + " at " +
                                                  time_text(t) + " GPST (satellite not in the clock file)");
    }
  }
  return sp3_clock(satellite, t);
}

Result<SatelliteState> PreciseEphemerides::state(const SatelliteId& satellite, const GnssTime& t) const {
  auto orbit_here = orbit(satellite, t);
  if (!orbit_here) return orbit_here.error();
  auto clock_here = clock(satellite, t);
  if (!clock_here) return clock_here.error();
  return state_from(*orbit_here, *clock_here);
}

SatelliteState PreciseEphemerides::state_from(const Orbit& orbit, const Clock& clock) {
  SatelliteState s;
  s.position_m = orbit.position_m;
  s.velocity_mps = orbit.velocity_mps;
  s.clock_bias_s = clock.bias_s;
  s.clock_drift_s_per_s = clock.drift_s_per_s;
  // IGS clocks exclude the periodic relativistic term for every system (GLONASS included):
  // dt_rel = -2 r.v / c^2. r.v is the same with Earth-fixed or inertial velocity (r.(w x r) = 0).
  // Its rate -2 (|v_i|^2 + r.a) / c^2 with the inertial velocity and, at this level, the
  // two-body acceleration (r.a = -GM / |r|).
  constexpr double c2 = constants::kSpeedOfLight_mps * constants::kSpeedOfLight_mps;
  const Eigen::Vector3d& r = s.position_m;
  s.relativistic_s = -2.0 * r.dot(s.velocity_mps) / c2;
  const Eigen::Vector3d v_inertial = s.velocity_mps + omega_cross(r);
  s.relativistic_drift_s_per_s = -2.0 * (v_inertial.squaredNorm() - constants::kGmGps_m3ps2 / r.norm()) / c2;
  return s;
}

std::unique_ptr<SatelliteStateSource> PreciseEphemerides::sequential_view() const {
  return std::make_unique<PreciseOrbitCache>(*this);
}

PreciseEphemerides::Span PreciseEphemerides::orbit_span() const {
  return {orbits_.epochs.front(), orbits_.epochs.back()};
}

std::optional<PreciseEphemerides::Span> PreciseEphemerides::clock_file_span() const {
  if (!clocks_ || clock_interval_s_.empty()) return std::nullopt;
  return Span{clock_first_, clock_last_};
}

PreciseEphemerides::Coverage PreciseEphemerides::coverage(const SatelliteId& satellite, const GnssTime& from,
                                                          const GnssTime& to) const {
  Coverage c;
  const auto* series = orbits_.series(satellite);
  c.in_orbits = series != nullptr && std::any_of(series->begin(), series->end(),
                                                 [](const Sp3Record& r) { return r.has_position; });
  const std::vector<ClockSample>* samples = clocks_ ? clocks_->series(satellite) : nullptr;
  const bool file_clocks = samples != nullptr && !samples->empty();
  const bool sp3_clocks = (!clocks_ || options_.sp3_clock_fallback) && series != nullptr &&
                          std::any_of(series->begin(), series->end(), [](const Sp3Record& r) { return r.has_clock; });
  c.in_clocks = file_clocks || sp3_clocks;
  if (!c.in_orbits) {
    c.orbit_gaps.push_back({from, to});
  } else {
    c.orbit_gaps = failing_spans(orbits_.epochs, from, to, [&](const GnssTime& t) { return orbit(satellite, t).ok(); });
  }
  if (!c.in_clocks) {
    c.clock_gaps.push_back({from, to});
  } else {
    std::vector<GnssTime> grid;
    if (file_clocks) {
      for (const ClockSample& sample : *samples) grid.push_back(sample.time);
    }
    if (sp3_clocks) {
      const size_t own = grid.size();
      grid.insert(grid.end(), orbits_.epochs.begin(), orbits_.epochs.end());
      std::inplace_merge(grid.begin(), grid.begin() + static_cast<long>(own), grid.end());
    }
    c.clock_gaps = failing_spans(grid, from, to, [&](const GnssTime& t) { return clock(satellite, t).ok(); });
  }
  return c;
}

std::vector<SatelliteId> PreciseEphemerides::satellites() const {
  std::vector<SatelliteId> out;
  for (size_t k = 0; k < orbits_.satellites.size(); ++k) {
    const auto& records = orbits_.records[k];
    if (std::none_of(records.begin(), records.end(), [](const Sp3Record& r) { return r.has_position; })) continue;
    const SatelliteId& satellite = orbits_.satellites[k];
    if (clocks_ && !options_.sp3_clock_fallback) {
      const auto* samples = clocks_->series(satellite);
      if (samples == nullptr || samples->empty()) continue;
    }
    out.push_back(satellite);
  }
  return out;
}

}  // namespace skytrace::orbits
