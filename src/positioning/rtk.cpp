#include "skytrace/positioning/rtk.hpp"

#include <Eigen/Dense>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <set>

#include "skytrace/atmosphere/models.hpp"
#include "skytrace/core/constants.hpp"
#include "skytrace/core/frames.hpp"

namespace skytrace::positioning {
namespace {

constexpr double kC = constants::kSpeedOfLight_mps;
constexpr double kDegPerRad = 180.0 / std::numbers::pi;
using Key = std::pair<SatelliteId, char>;

// ---- LAMBDA ----

// Q = L^T D L with L unit lower triangular (the factorisation from the last row, as LAMBDA uses it:
// the conditional variances D come out ordered for the decorrelation).
bool factor_ltdl(Eigen::MatrixXd q, Eigen::MatrixXd& l, Eigen::VectorXd& d) {
  const Eigen::Index n = q.rows();
  l = Eigen::MatrixXd::Zero(n, n);
  d = Eigen::VectorXd::Zero(n);
  for (Eigen::Index i = n - 1; i >= 0; --i) {
    d(i) = q(i, i);
    if (!(d(i) > 0.0)) return false;
    const double root = std::sqrt(d(i));
    for (Eigen::Index j = 0; j <= i; ++j) l(i, j) = q(i, j) / root;
    for (Eigen::Index j = 0; j < i; ++j) {
      for (Eigen::Index k = 0; k <= j; ++k) q(j, k) -= l(i, k) * l(i, j);
    }
    for (Eigen::Index j = 0; j <= i; ++j) l(i, j) /= l(i, i);
  }
  return true;
}

// Integer Gauss transformation: makes |L(i, j)| <= 1/2, applied to Z as well.
void integer_gauss(Eigen::MatrixXd& l, Eigen::MatrixXd& z, Eigen::Index i, Eigen::Index j) {
  const double mu = std::round(l(i, j));
  if (mu == 0.0) return;
  const Eigen::Index n = l.rows();
  for (Eigen::Index k = i; k < n; ++k) l(k, j) -= mu * l(k, i);
  z.col(j) -= mu * z.col(i);
}

// Swaps ambiguities j and j + 1 and updates L and D so that Q = L^T D L still holds.
void permute(Eigen::MatrixXd& l, Eigen::VectorXd& d, Eigen::Index j, double delta, Eigen::MatrixXd& z) {
  const Eigen::Index n = l.rows();
  const double eta = d(j) / delta;
  const double lambda = d(j + 1) * l(j + 1, j) / delta;
  d(j) = eta * d(j + 1);
  d(j + 1) = delta;
  for (Eigen::Index k = 0; k < j; ++k) {
    const double a0 = l(j, k), a1 = l(j + 1, k);
    l(j, k) = -l(j + 1, j) * a0 + a1;
    l(j + 1, k) = eta * a0 + lambda * a1;
  }
  l(j + 1, j) = lambda;
  for (Eigen::Index k = j + 2; k < n; ++k) std::swap(l(k, j), l(k, j + 1));
  z.col(j).swap(z.col(j + 1));
}

// Decorrelation (de Jonge & Tiberius 1996, the ordering of Chang et al. 2005): Z unimodular with
// Z^T Q Z = L^T D L nearly diagonal and D ascending towards the first index.
void reduce(Eigen::MatrixXd& l, Eigen::VectorXd& d, Eigen::MatrixXd& z) {
  const Eigen::Index n = l.rows();
  Eigen::Index j = n - 2, last_swap = n - 2;
  while (j >= 0) {
    if (j <= last_swap) {
      for (Eigen::Index i = j + 1; i < n; ++i) integer_gauss(l, z, i, j);
    }
    const double delta = d(j) + l(j + 1, j) * l(j + 1, j) * d(j + 1);
    if (delta + 1e-6 < d(j + 1)) {
      permute(l, d, j, delta, z);
      last_swap = j;
      j = n - 2;
    } else {
      --j;
    }
  }
}

double sign_of(double v) { return v <= 0.0 ? -1.0 : 1.0; }

// MLAMBDA search: depth-first enumeration from the last ambiguity, conditional estimates
// zb_k = zs_k + sum_{j>k} L(j, k) (z_j - zb_j), zig-zag around them, the ellipsoid shrunk to the
// worst of the `m` best candidates found so far.
void search(const Eigen::MatrixXd& l, const Eigen::VectorXd& d, const Eigen::VectorXd& zs, int m,
            std::vector<Eigen::VectorXd>& best, std::vector<double>& norms) {
  const Eigen::Index n = l.rows();
  Eigen::MatrixXd s = Eigen::MatrixXd::Zero(n, n);
  Eigen::VectorXd dist(n), zb(n), z(n), step(n);
  Eigen::Index k = n - 1;
  dist(k) = 0.0;
  zb(k) = zs(k);
  z(k) = std::round(zb(k));
  double y = zb(k) - z(k);
  step(k) = sign_of(y);
  double max_dist = std::numeric_limits<double>::infinity();
  int found = 0;
  size_t worst = 0;
  constexpr int kMaxLoops = 100000;  // a pathological Q must not hang the engine
  for (int loop = 0; loop < kMaxLoops; ++loop) {
    const double new_dist = dist(k) + y * y / d(k);
    if (new_dist < max_dist) {
      if (k != 0) {
        --k;
        dist(k) = new_dist;
        for (Eigen::Index i = 0; i <= k; ++i) s(k, i) = s(k + 1, i) + (z(k + 1) - zb(k + 1)) * l(k + 1, i);
        zb(k) = zs(k) + s(k, k);
        z(k) = std::round(zb(k));
        y = zb(k) - z(k);
        step(k) = sign_of(y);
      } else {
        if (found < m) {
          best.push_back(z);
          norms.push_back(new_dist);
          if (found == 0 || new_dist > norms[worst]) worst = static_cast<size_t>(found);
          ++found;
          if (found == m) max_dist = norms[worst];
        } else if (new_dist < norms[worst]) {
          best[worst] = z;
          norms[worst] = new_dist;
          worst = static_cast<size_t>(std::max_element(norms.begin(), norms.end()) - norms.begin());
          max_dist = norms[worst];
        }
        z(0) += step(0);
        y = zb(0) - z(0);
        step(0) = -step(0) - sign_of(step(0));
      }
    } else {
      if (k == n - 1) break;
      ++k;
      z(k) += step(k);
      y = zb(k) - z(k);
      step(k) = -step(k) - sign_of(step(k));
    }
  }
}

// ---- Measurements of one receiver, per satellite and band ----

struct BandObservation {
  const SignalMeasurement* phase = nullptr;  // the signal whose phase is used (resolved polarity)
  const SignalMeasurement* code = nullptr;   // the same signal, else the band's first with a code
};

// The first signal of each band (in the epoch's order) with a phase of known polarity carries the
// phase; the slip detector and the engine choose alike, so arcs are those of one signal.
std::map<Key, BandObservation> band_observations(const EpochMeasurements& epoch) {
  std::map<Key, BandObservation> out;
  for (const SignalMeasurement& m : epoch.signals) {
    BandObservation& o = out[Key{m.satellite, m.signal.band}];
    const bool has_phase = m.carrier_phase_cycles && *m.carrier_phase_cycles != 0.0 && !m.half_cycle_unresolved &&
                           std::isfinite(*m.carrier_phase_cycles);
    if (o.phase == nullptr && has_phase) {
      o.phase = &m;
      if (m.pseudorange_m > 0.0) o.code = &m;
    }
    if (o.code == nullptr && m.pseudorange_m > 0.0) o.code = &m;
  }
  return out;
}

double carrier_of(const SignalMeasurement& m) {
  if (m.carrier_hz > 0.0) return m.carrier_hz;
  if (m.signal.system == GnssSystem::kGlonass) return 0.0;  // needs the channel
  const SignalInfo* info = find_signal_info(m.signal);
  return info != nullptr ? info->carrier_frequency_hz() : 0.0;
}

double median_of(std::vector<double> v) {
  if (v.empty()) return 0.0;
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

}  // namespace

double IntegerSolution::ratio() const {
  if (squared_norms.size() < 2) return 0.0;
  if (squared_norms[0] <= 0.0) return std::numeric_limits<double>::infinity();
  return squared_norms[1] / squared_norms[0];
}

Result<IntegerSolution> lambda_search(const Eigen::VectorXd& float_ambiguities, const Eigen::MatrixXd& covariance,
                                      int candidates) {
  const Eigen::Index n = float_ambiguities.size();
  if (n == 0 || covariance.rows() != n || covariance.cols() != n || candidates < 1) {
    return make_error(ErrorCode::kInvalidArgument, "lambda_search: " + std::to_string(n) + " ambiguities with a " +
                                                       std::to_string(covariance.rows()) + "x" +
                                                       std::to_string(covariance.cols()) + " covariance");
  }
  if (!float_ambiguities.allFinite() || !covariance.allFinite()) {
    return make_error(ErrorCode::kInvalidArgument, "lambda_search: non-finite input");
  }
  Eigen::MatrixXd l;
  Eigen::VectorXd d;
  if (!factor_ltdl(0.5 * (covariance + covariance.transpose()), l, d)) {
    return make_error(ErrorCode::kInvalidArgument, "lambda_search: covariance not positive definite");
  }
  Eigen::MatrixXd z = Eigen::MatrixXd::Identity(n, n);
  reduce(l, d, z);
  // Search near the float values shifted to integers (only the fraction matters; large values
  // would lose digits in the conditional estimates).
  const Eigen::VectorXd zs_full = z.transpose() * float_ambiguities;
  const Eigen::VectorXd shift = zs_full.array().round();
  std::vector<Eigen::VectorXd> best;
  std::vector<double> norms;
  search(l, d, zs_full - shift, candidates, best, norms);
  if (best.empty()) return make_error(ErrorCode::kOutOfRange, "lambda_search: no candidate found");
  std::vector<size_t> order(best.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return norms[a] < norms[b]; });
  IntegerSolution out;
  const Eigen::PartialPivLU<Eigen::MatrixXd> zt(z.transpose());
  for (size_t i : order) {
    // Back from the decorrelated space: a = Z^-T z (Z unimodular: integer in, integer out).
    const Eigen::VectorXd a = zt.solve(best[i] + shift);
    out.candidates.push_back(a.array().round().matrix());
    out.squared_norms.push_back(norms[i]);
  }
  return out;
}

DoubleDifferenceGroup form_double_differences(const std::vector<SingleDifference>& group, bool reference_by_variance) {
  DoubleDifferenceGroup out;
  const auto n = static_cast<Eigen::Index>(group.size());
  if (group.empty()) return out;
  for (size_t i = 1; i < group.size(); ++i) {
    const SingleDifference& a = group[i];
    const SingleDifference& best = group[out.reference];
    const bool better = reference_by_variance ? a.variance_m2 < best.variance_m2 ||
                                                    (a.variance_m2 == best.variance_m2 && a.elevation_deg > best.elevation_deg)
                                              : a.elevation_deg > best.elevation_deg;
    if (better) out.reference = i;
  }
  for (size_t i = 0; i < group.size(); ++i) {
    if (i != out.reference) out.others.push_back(i);
  }
  const auto m = static_cast<Eigen::Index>(out.others.size());
  out.difference = Eigen::MatrixXd::Zero(m, n);
  Eigen::VectorXd y(n), variance(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    y(i) = group[static_cast<size_t>(i)].value_m;
    variance(i) = group[static_cast<size_t>(i)].variance_m2;
  }
  for (Eigen::Index r = 0; r < m; ++r) {
    out.difference(r, static_cast<Eigen::Index>(out.others[static_cast<size_t>(r)])) = 1.0;
    out.difference(r, static_cast<Eigen::Index>(out.reference)) = -1.0;
  }
  out.values_m = out.difference * y;
  out.covariance_m2 = out.difference * variance.asDiagonal() * out.difference.transpose();
  return out;
}

std::vector<std::pair<SatelliteId, char>> SlipDetector::update(const EpochMeasurements& epoch) {
  std::vector<Key> new_arcs;
  const auto bands = band_observations(epoch);
  const GnssTime& t = epoch.receiver_time;
  // Doppler test residuals (m) per key, then their median removed: a receiver clock jump moves
  // every phase alike.
  std::vector<std::pair<Key, double>> doppler_residuals;
  std::map<SatelliteId, std::vector<std::pair<char, double>>> phases_m;  // for geometry-free
  std::set<Key> flagged;
  for (const auto& [key, obs] : bands) {
    if (obs.phase == nullptr) {
      last_.erase(key);
      continue;
    }
    const SignalMeasurement& m = *obs.phase;
    const double carrier_hz = carrier_of(m);
    const double wavelength_m = carrier_hz > 0.0 ? kC / carrier_hz : 0.0;
    const double phase = *m.carrier_phase_cycles;
    const auto it = last_.find(key);
    bool slip = it == last_.end() || m.loss_of_lock;
    if (it != last_.end()) {
      const double dt_s = t - it->second.time;
      if (!(dt_s > 0.0) || dt_s > settings_.max_gap_s || it->second.wavelength_m != wavelength_m) slip = true;
      if (!slip && settings_.doppler_m > 0.0 && wavelength_m > 0.0 && m.doppler_hz && it->second.doppler_hz) {
        // Phase has the sign of the range; Doppler is positive when the range shrinks.
        const double predicted_cycles = -0.5 * (*m.doppler_hz + *it->second.doppler_hz) * dt_s;
        doppler_residuals.emplace_back(key, (phase - it->second.phase_cycles - predicted_cycles) * wavelength_m);
      }
    }
    if (slip) flagged.insert(key);
    if (wavelength_m > 0.0) phases_m[key.first].emplace_back(key.second, phase * wavelength_m);
    last_[key] = Last{t, phase, m.doppler_hz, wavelength_m};
  }
  if (doppler_residuals.size() >= 2) {
    std::vector<double> values;
    for (const auto& r : doppler_residuals) values.push_back(r.second);
    const double common_m = median_of(values);
    for (const auto& [key, residual_m] : doppler_residuals) {
      if (std::abs(residual_m - common_m) > settings_.doppler_m) flagged.insert(key);
    }
  }
  if (settings_.geometry_free_m > 0.0) {
    for (auto& [sat, list] : phases_m) {
      if (list.size() < 2) {
        last_geometry_free_m_.erase(sat);
        continue;
      }
      std::sort(list.begin(), list.end());
      const double gf_m = list[0].second - list[1].second;
      const auto it = last_geometry_free_m_.find(sat);
      if (it != last_geometry_free_m_.end() && t - it->second.first <= settings_.max_gap_s &&
          std::abs(gf_m - it->second.second) > settings_.geometry_free_m) {
        // Which band slipped is unknown: both start again.
        for (const auto& [band, value] : list) flagged.insert(Key{sat, band});
      }
      last_geometry_free_m_[sat] = {t, gf_m};
    }
  }
  new_arcs.assign(flagged.begin(), flagged.end());
  return new_arcs;
}

RtkEngine::RtkEngine(const orbits::BroadcastEphemerides& ephemerides, RtkSettings settings,
                     std::optional<orbits::KlobucharCoefficients> klobuchar)
    : settings_(std::move(settings)),
      rover_solver_(ephemerides, settings_.single_point, klobuchar),
      base_solver_(ephemerides, settings_.single_point, klobuchar),
      rover_slips_(settings_.slips),
      base_slips_(settings_.slips) {}

void RtkEngine::reset_filter() {
  initialised_ = false;
  consecutive_fixes_ = 0;
  ambiguities_.clear();
  x_.resize(0);
  p_.resize(0, 0);
}

void RtkEngine::add_state(const Key& key, double value_cycles, double variance_cycles2) {
  const Eigen::Index n = x_.size();
  x_.conservativeResize(n + 1);
  x_(n) = value_cycles;
  Eigen::MatrixXd p = Eigen::MatrixXd::Zero(n + 1, n + 1);
  p.topLeftCorner(n, n) = p_;
  p(n, n) = variance_cycles2;
  p_ = std::move(p);
  ambiguities_[key] = Ambiguity{n, 0, key.first.system != GnssSystem::kGlonass || settings_.fix_glonass};
}

void RtkEngine::remove_states(const std::vector<Key>& keys) {
  std::vector<Eigen::Index> removed;
  for (const Key& key : keys) {
    const auto it = ambiguities_.find(key);
    if (it == ambiguities_.end()) continue;
    removed.push_back(it->second.index);
    ambiguities_.erase(it);
  }
  if (removed.empty()) return;
  std::vector<Eigen::Index> keep;
  std::vector<Eigen::Index> new_index(static_cast<size_t>(x_.size()), -1);
  for (Eigen::Index i = 0; i < x_.size(); ++i) {
    if (std::find(removed.begin(), removed.end(), i) != removed.end()) continue;
    new_index[static_cast<size_t>(i)] = static_cast<Eigen::Index>(keep.size());
    keep.push_back(i);
  }
  const auto m = static_cast<Eigen::Index>(keep.size());
  Eigen::VectorXd x(m);
  Eigen::MatrixXd p(m, m);
  for (Eigen::Index i = 0; i < m; ++i) {
    x(i) = x_(keep[static_cast<size_t>(i)]);
    for (Eigen::Index j = 0; j < m; ++j) p(i, j) = p_(keep[static_cast<size_t>(i)], keep[static_cast<size_t>(j)]);
  }
  x_ = std::move(x);
  p_ = std::move(p);
  for (auto& [key, amb] : ambiguities_) amb.index = new_index[static_cast<size_t>(amb.index)];
}

Result<PositionFix> RtkEngine::solve(const EpochMeasurements& rover, const BaseEpoch* base) {
  auto rover_fix = rover_solver_.solve(rover);
  if (!rover_fix) return rover_fix.error();
  PositionFix fix = std::move(*rover_fix);
  // The slip detectors see every epoch, so that arcs stay continuous across epochs without a fix.
  const std::vector<Key> rover_new_arcs = rover_slips_.update(rover);
  std::vector<Key> base_new_arcs;
  if (base != nullptr) base_new_arcs = base_slips_.update(base->measurements);
  if (fix.type == FixType::kNone) return fix;

  PositionFix::Relative relative;
  const auto fallback = [&](std::string why) {
    fix.message = std::move(why);
    fix.relative = relative;
    return fix;
  };
  if (base == nullptr) return fallback("RTK: no base observations");
  relative.age_s = rover.receiver_time - base->measurements.receiver_time;
  if (std::abs(relative.age_s) > settings_.max_age_s) {
    return fallback(fmt::format("RTK: base observations {:.1f} s old (at most {:.1f} s)", relative.age_s,
                                settings_.max_age_s));
  }
  if (!base->position_ecef_m.allFinite() || base->position_ecef_m.norm() < 6.0e6) {
    return fallback("RTK: no base position");
  }
  auto base_fix = base_solver_.solve(base->measurements);
  if (!base_fix) return base_fix.error().with_context("base observations");
  if (base_fix->type == FixType::kNone) return fallback("RTK: base observations without a fix: " + base_fix->message);
  const double base_offset_m = (base_fix->position_ecef_m - base->position_ecef_m).norm();
  if (base_offset_m > settings_.max_base_position_error_m) {
    return fallback(fmt::format("RTK: the base position is {:.0f} m from the base's own single-point fix (at most "
                                "{:.0f} m): check the base position",
                                base_offset_m, settings_.max_base_position_error_m));
  }
  const Eigen::Vector3d& base_m = base->position_ecef_m;
  if ((base_m - last_base_position_m_).norm() > 1e-3) {
    reset_filter();  // another base: other single differences
    last_base_position_m_ = base_m;
  }

  // ---- The time update ----
  const int position_states = settings_.estimate_velocity && settings_.dynamics == RtkDynamics::kKinematic ? 6 : 3;
  const GnssTime& t = rover.receiver_time;
  if (!initialised_) {
    x_ = Eigen::VectorXd::Zero(position_states);
    p_ = Eigen::MatrixXd::Zero(position_states, position_states);
    x_.head<3>() = fix.position_ecef_m;
    p_.topLeftCorner<3, 3>() = Eigen::Matrix3d::Identity() * 900.0;
    if (position_states == 6) {
      if (fix.velocity_valid) x_.segment<3>(3) = fix.velocity_ecef_mps;
      p_.block<3, 3>(3, 3) = Eigen::Matrix3d::Identity() * (fix.velocity_valid ? 1.0 : 100.0);
    }
    ambiguities_.clear();
    initialised_ = true;
  } else {
    const double dt_s = std::max(t - last_time_, 0.0);
    if (settings_.dynamics == RtkDynamics::kKinematic && position_states == 3) {
      // No dynamics model: the position starts again from the single-point fix every epoch (the
      // ambiguities carry the information from epoch to epoch).
      x_.head<3>() = fix.position_ecef_m;
      p_.topRows<3>().setZero();
      p_.leftCols<3>().setZero();
      const double sigma_m = std::max(settings_.position_noise_mps * std::sqrt(std::max(dt_s, 1.0)), 1.0);
      p_.topLeftCorner<3, 3>() = Eigen::Matrix3d::Identity() * sigma_m * sigma_m;
    } else if (position_states == 6) {
      Eigen::MatrixXd f = Eigen::MatrixXd::Identity(x_.size(), x_.size());
      f.block<3, 3>(0, 3) = Eigen::Matrix3d::Identity() * dt_s;
      x_ = f * x_;
      p_ = f * p_ * f.transpose();
      const double q = settings_.acceleration_noise_mps2 * settings_.acceleration_noise_mps2;
      p_.block<3, 3>(0, 0) += Eigen::Matrix3d::Identity() * q * dt_s * dt_s * dt_s / 3.0;
      p_.block<3, 3>(0, 3) += Eigen::Matrix3d::Identity() * q * dt_s * dt_s / 2.0;
      p_.block<3, 3>(3, 0) += Eigen::Matrix3d::Identity() * q * dt_s * dt_s / 2.0;
      p_.block<3, 3>(3, 3) += Eigen::Matrix3d::Identity() * q * dt_s;
    }
    for (auto& [key, amb] : ambiguities_) {
      p_(amb.index, amb.index) += settings_.ambiguity_noise_cycles * settings_.ambiguity_noise_cycles * dt_s;
    }
  }
  last_time_ = t;

  // ---- Single differences ----
  std::map<SatelliteId, const SatelliteUse*> rover_sats, base_sats;
  for (const SatelliteUse& use : fix.satellites) {
    if (use.has_geometry) rover_sats[use.satellite] = &use;
  }
  for (const SatelliteUse& use : base_fix->satellites) {
    if (use.has_geometry) base_sats[use.satellite] = &use;
  }
  const auto system_wanted = [&](GnssSystem system) {
    if (settings_.systems.empty()) return system != GnssSystem::kSbas;
    return std::find(settings_.systems.begin(), settings_.systems.end(), system) != settings_.systems.end();
  };
  const auto rover_bands = band_observations(rover);
  const auto base_bands = band_observations(base->measurements);
  const Geodetic base_geodetic = ecef_to_geodetic(base_m);
  const Eigen::Vector3d rover_m = x_.head<3>();
  const Geodetic rover_geodetic = ecef_to_geodetic(rover_m);
  const bool troposphere = settings_.single_point.troposphere_saastamoinen;

  struct Row {
    Key key;
    double wavelength_m = 0.0;
    double elevation_deg = 0.0;
    Eigen::Vector3d line_of_sight;  // rover to satellite
    std::optional<double> phase_m;  // rover minus base: observed + satellite clock - range - troposphere
    std::optional<double> code_m;
    double variance_phase_m2 = 0.0;
  };
  std::vector<Row> rows;
  std::set<SatelliteId> common;
  const double ratio2 = settings_.code_phase_ratio * settings_.code_phase_ratio;
  for (const auto& [key, r] : rover_bands) {
    if (!system_wanted(key.first.system)) continue;
    const auto b = base_bands.find(key);
    const auto rs = rover_sats.find(key.first);
    const auto bs = base_sats.find(key.first);
    if (b == base_bands.end() || rs == rover_sats.end() || bs == base_sats.end()) continue;
    const double rover_el = rs->second->direction.elevation_deg, base_el = bs->second->direction.elevation_deg;
    if (rover_el < settings_.elevation_mask_deg || base_el < settings_.elevation_mask_deg) continue;
    const SignalMeasurement* any_r = r.phase != nullptr ? r.phase : r.code;
    const SignalMeasurement* any_b = b->second.phase != nullptr ? b->second.phase : b->second.code;
    if (any_r == nullptr || any_b == nullptr) continue;
    if (settings_.min_cn0_dbhz > 0.0 &&
        ((any_r->cn0_dbhz > 0.0 && any_r->cn0_dbhz < settings_.min_cn0_dbhz) ||
         (any_b->cn0_dbhz > 0.0 && any_b->cn0_dbhz < settings_.min_cn0_dbhz))) {
      continue;
    }
    const double carrier_hz = carrier_of(*any_r);
    if (!(carrier_hz > 0.0)) continue;
    Row row;
    row.key = key;
    row.wavelength_m = kC / carrier_hz;
    row.elevation_deg = rover_el;
    const Eigen::Vector3d& sat_r = rs->second->satellite_position_m;
    const Eigen::Vector3d& sat_b = bs->second->satellite_position_m;
    const double range_r = (sat_r - rover_m).norm(), range_b = (sat_b - base_m).norm();
    row.line_of_sight = (sat_r - rover_m) / range_r;
    double model_r = range_r - rs->second->satellite_clock_m;
    double model_b = range_b - bs->second->satellite_clock_m;
    if (troposphere) {
      model_r += atmosphere::saastamoinen_delay_m(rover_geodetic, rover_el).value_or(0.0);
      model_b += atmosphere::saastamoinen_delay_m(base_geodetic, base_el).value_or(0.0);
    }
    const auto phase_sigma2 = [&](double el_deg) {
      const double sin_el = std::max(std::sin(el_deg / kDegPerRad), 0.05);
      return settings_.sigma_phase_zenith_m * settings_.sigma_phase_zenith_m +
             std::pow(settings_.sigma_phase_elevation_m / sin_el, 2);
    };
    // C/N0 weighting: the weaker signal's tracking jitter (variance as 1 / (C/N0)).
    const auto cn0_factor = [&](const SignalMeasurement* m) {
      if (settings_.cn0_weighting_dbhz <= 0.0 || m->cn0_dbhz <= 0.0) return 1.0;
      return std::max(1.0, std::pow(10.0, (settings_.cn0_weighting_dbhz - m->cn0_dbhz) / 10.0));
    };
    row.variance_phase_m2 = phase_sigma2(rover_el) * cn0_factor(any_r) + phase_sigma2(base_el) * cn0_factor(any_b);
    if (r.code != nullptr && b->second.code != nullptr) {
      row.code_m = (r.code->pseudorange_m - model_r) - (b->second.code->pseudorange_m - model_b);
    }
    if (r.phase != nullptr && b->second.phase != nullptr) {
      row.phase_m = (*r.phase->carrier_phase_cycles * row.wavelength_m - model_r) -
                    (*b->second.phase->carrier_phase_cycles * kC / carrier_of(*b->second.phase) - model_b);
      if (!std::isfinite(*row.phase_m) || carrier_of(*b->second.phase) != carrier_hz) row.phase_m.reset();
    }
    if (!row.code_m && !row.phase_m) continue;
    common.insert(key.first);
    rows.push_back(row);
  }
  if (common.size() < 4) {
    return fallback(fmt::format("RTK: {} satellite(s) in common with the base above the masks (at least 4 needed)",
                                common.size()));
  }

  // ---- Ambiguity states: slips, outages, new arcs ----
  {
    std::vector<Key> drop(rover_new_arcs.begin(), rover_new_arcs.end());
    drop.insert(drop.end(), base_new_arcs.begin(), base_new_arcs.end());
    // Epochs, not seconds: a 30 s file must not lose every ambiguity between its epochs.
    std::set<Key> observed;
    for (const Row& row : rows) {
      if (row.phase_m && row.code_m) observed.insert(row.key);
    }
    for (auto& [key, amb] : ambiguities_) {
      amb.missed_epochs = observed.count(key) > 0 ? 0 : amb.missed_epochs + 1;
      if (amb.missed_epochs > settings_.max_outage_epochs) drop.push_back(key);
    }
    remove_states(drop);
  }
  for (const Row& row : rows) {
    if (!row.phase_m || !row.code_m) continue;
    const auto it = ambiguities_.find(row.key);
    if (it == ambiguities_.end()) {
      add_state(row.key, (*row.phase_m - *row.code_m) / row.wavelength_m,
                settings_.initial_ambiguity_sigma_cycles * settings_.initial_ambiguity_sigma_cycles);
    }
  }

  // ---- The measurement update: double differences per system and band ----
  const Eigen::Index n = x_.size();
  std::map<std::pair<GnssSystem, char>, std::vector<size_t>> groups;
  for (size_t i = 0; i < rows.size(); ++i) groups[{rows[i].key.first.system, rows[i].key.second}].push_back(i);
  struct DdRow {
    Eigen::RowVectorXd h;
    double innovation_m = 0.0;
  };
  std::vector<DdRow> dd_rows;
  std::vector<Eigen::MatrixXd> dd_blocks;
  int phase_rows = 0;
  std::set<SatelliteId> used_sats;
  // Per phase group, its reference and members (for the ambiguity resolution).
  struct PhaseGroup {
    Key reference;
    std::vector<Key> others;
    std::vector<double> elevations_deg;
    std::vector<double> variances_m2;
  };
  std::vector<PhaseGroup> phase_groups;
  for (const auto& [group_key, members] : groups) {
    for (int kind = 0; kind < 2; ++kind) {  // 0 phase, 1 code
      std::vector<SingleDifference> sds;
      std::vector<size_t> index;
      for (size_t i : members) {
        const Row& row = rows[i];
        const bool has = kind == 0 ? row.phase_m && ambiguities_.count(row.key) > 0 : row.code_m.has_value();
        if (!has) continue;
        SingleDifference sd;
        sd.satellite = row.key.first;
        sd.band = row.key.second;
        sd.wavelength_m = row.wavelength_m;
        sd.value_m = kind == 0 ? *row.phase_m : *row.code_m;
        sd.variance_m2 = kind == 0 ? row.variance_phase_m2 : row.variance_phase_m2 * ratio2;
        sd.elevation_deg = row.elevation_deg;
        sds.push_back(sd);
        index.push_back(i);
      }
      if (sds.size() < 2) continue;
      const DoubleDifferenceGroup dd = form_double_differences(sds, settings_.cn0_weighting_dbhz > 0.0);
      // Single-difference design rows: d(observed - model)/d(state) with the sign of the model.
      const auto m = static_cast<Eigen::Index>(sds.size());
      Eigen::MatrixXd h_sd = Eigen::MatrixXd::Zero(m, n);
      Eigen::VectorXd predicted = Eigen::VectorXd::Zero(m);
      for (Eigen::Index i = 0; i < m; ++i) {
        const Row& row = rows[index[static_cast<size_t>(i)]];
        h_sd.block<1, 3>(i, 0) = -row.line_of_sight.transpose();
        if (kind == 0) {
          const Eigen::Index a = ambiguities_.at(row.key).index;
          h_sd(i, a) = row.wavelength_m;
          predicted(i) = row.wavelength_m * x_(a);
        }
      }
      // The values are observed minus modelled at the current position: the innovation is that
      // minus the ambiguity terms; the position part enters through H.
      const Eigen::MatrixXd h_dd = dd.difference * h_sd;
      const Eigen::VectorXd innovation = dd.values_m - dd.difference * predicted;
      std::vector<Eigen::Index> keep;
      for (Eigen::Index r = 0; r < innovation.size(); ++r) {
        if (std::abs(innovation(r)) <= settings_.max_innovation_m) keep.push_back(r);
      }
      if (keep.empty()) continue;
      Eigen::MatrixXd block(static_cast<Eigen::Index>(keep.size()), static_cast<Eigen::Index>(keep.size()));
      for (size_t i = 0; i < keep.size(); ++i) {
        for (size_t j = 0; j < keep.size(); ++j) block(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = dd.covariance_m2(keep[i], keep[j]);
        dd_rows.push_back(DdRow{h_dd.row(keep[i]), innovation(keep[i])});
      }
      dd_blocks.push_back(std::move(block));
      used_sats.insert(sds[dd.reference].satellite);
      for (Eigen::Index r : keep) used_sats.insert(sds[dd.others[static_cast<size_t>(r)]].satellite);
      if (kind == 0) {
        phase_rows += static_cast<int>(keep.size());
        PhaseGroup pg;
        pg.reference = Key{sds[dd.reference].satellite, sds[dd.reference].band};
        for (Eigen::Index r : keep) {
          const SingleDifference& sd = sds[dd.others[static_cast<size_t>(r)]];
          pg.others.emplace_back(sd.satellite, sd.band);
          pg.elevations_deg.push_back(sd.elevation_deg);
          pg.variances_m2.push_back(sd.variance_m2);
        }
        phase_groups.push_back(std::move(pg));
      }
    }
  }
  if (dd_rows.size() < 3) return fallback("RTK: too few double differences with the base");
  // R is block diagonal (one block per group and kind): the blocks update the filter one after the
  // other, which equals one joint update and costs n^2 m instead of n m^2.
  {
    const Eigen::VectorXd x_before = x_;
    size_t first = 0;
    for (const Eigen::MatrixXd& block : dd_blocks) {
      const Eigen::Index m = block.rows();
      Eigen::MatrixXd h(m, n);
      Eigen::VectorXd v(m);
      for (Eigen::Index i = 0; i < m; ++i) {
        const DdRow& row = dd_rows[first + static_cast<size_t>(i)];
        h.row(i) = row.h;
        // The innovation at the state the previous blocks left (the model is linear in it).
        v(i) = row.innovation_m - row.h.dot(x_ - x_before);
      }
      first += static_cast<size_t>(m);
      const Eigen::MatrixXd ph = p_ * h.transpose();
      const Eigen::LLT<Eigen::MatrixXd> s_llt(h * ph + block);
      if (s_llt.info() != Eigen::Success) return fallback("RTK: singular innovation covariance");
      const Eigen::MatrixXd k_gain = s_llt.solve(ph.transpose()).transpose();
      x_ += k_gain * v;
      p_.noalias() -= k_gain * ph.transpose();
    }
    p_ = 0.5 * (p_ + p_.transpose());
  }

  // ---- Output: float, then integers ----
  Eigen::Vector3d position_m = x_.head<3>();
  Eigen::Matrix3d covariance_m2 = p_.topLeftCorner<3, 3>();
  FixType type = phase_rows > 0 ? FixType::kRtkFloat : FixType::kDgnss;
  std::string note;
  if (type == FixType::kRtkFloat && settings_.ambiguity_mode != AmbiguityMode::kFloat) {
    // Double-differenced ambiguities that may be fixed, with the elevation of their satellite.
    struct Candidate {
      Eigen::Index plus, minus;
      double drop_key;  // smallest left out first
      SatelliteId satellite;
    };
    std::vector<Candidate> candidates;
    for (const PhaseGroup& pg : phase_groups) {
      const Ambiguity& ref = ambiguities_.at(pg.reference);
      if (!ref.fixable) continue;
      for (size_t i = 0; i < pg.others.size(); ++i) {
        const Ambiguity& amb = ambiguities_.at(pg.others[i]);
        if (!amb.fixable) continue;
        // The order of leaving out: lowest first, or (C/N0 weighting) largest variance first.
        const double drop_key = settings_.cn0_weighting_dbhz > 0.0 ? -pg.variances_m2[i] : pg.elevations_deg[i];
        candidates.push_back(Candidate{amb.index, ref.index, drop_key, pg.others[i].first});
      }
    }
    // Satellites in the order the partial sets leave them out.
    std::vector<std::pair<double, SatelliteId>> by_elevation;
    for (const Candidate& c : candidates) by_elevation.emplace_back(c.drop_key, c.satellite);
    std::sort(by_elevation.begin(), by_elevation.end());
    by_elevation.erase(std::unique(by_elevation.begin(), by_elevation.end(),
                                   [](const auto& a, const auto& b) { return a.second == b.second; }),
                       by_elevation.end());
    std::set<SatelliteId> left_out;
    for (int attempt = 0; attempt <= settings_.max_partial_drops; ++attempt) {
      if (attempt > 0) {
        if (static_cast<size_t>(attempt) > by_elevation.size()) break;
        left_out.insert(by_elevation[static_cast<size_t>(attempt - 1)].second);
      }
      std::vector<const Candidate*> set;
      for (const Candidate& c : candidates) {
        if (left_out.count(c.satellite) == 0) set.push_back(&c);
      }
      const auto m = static_cast<Eigen::Index>(set.size());
      if (m < settings_.min_fixed_ambiguities) break;
      Eigen::MatrixXd transform = Eigen::MatrixXd::Zero(m, n);
      for (Eigen::Index i = 0; i < m; ++i) {
        transform(i, set[static_cast<size_t>(i)]->plus) = 1.0;
        transform(i, set[static_cast<size_t>(i)]->minus) = -1.0;
      }
      const Eigen::VectorXd a_float = transform * x_;
      const Eigen::MatrixXd q_aa = transform * p_ * transform.transpose();
      auto integers = lambda_search(a_float, q_aa, 2);
      if (!integers) break;
      relative.ratio = std::min(integers->ratio(), 999.9);
      if (relative.ratio < settings_.ratio_threshold) continue;
      const Eigen::VectorXd& a_fixed = integers->candidates.front();
      const Eigen::MatrixXd q_xa = p_.topRows<3>() * transform.transpose();
      const Eigen::LLT<Eigen::MatrixXd> q_llt(q_aa);
      position_m = x_.head<3>() - q_xa * q_llt.solve(a_float - a_fixed);
      covariance_m2 = p_.topLeftCorner<3, 3>() - q_xa * q_llt.solve(q_xa.transpose());
      type = FixType::kRtkFixed;
      relative.fixed_ambiguities = static_cast<int>(m);
      ++consecutive_fixes_;
      if (settings_.ambiguity_mode == AmbiguityMode::kFixAndHold && consecutive_fixes_ >= settings_.min_hold_epochs) {
        // Hold: the fixed double differences as tight observations of the float filter.
        const Eigen::MatrixXd pt = p_ * transform.transpose();
        Eigen::MatrixXd s = transform * pt;
        s.diagonal().array() += settings_.hold_sigma_cycles * settings_.hold_sigma_cycles;
        const Eigen::MatrixXd gain = s.llt().solve(pt.transpose()).transpose();
        x_ += gain * (a_fixed - a_float);
        p_ -= gain * pt.transpose();
        p_ = 0.5 * (p_ + p_.transpose());
      }
      break;
    }
    if (type != FixType::kRtkFixed) {
      consecutive_fixes_ = 0;
      if (relative.ratio > 0.0) note = fmt::format("ratio {:.2f} below {:.1f}", relative.ratio, settings_.ratio_threshold);
    }
  }

  fix.type = type;
  fix.position_ecef_m = position_m;
  fix.position = ecef_to_geodetic(position_m);
  const Eigen::Matrix3d to_enu = ecef_to_enu_rotation(fix.position);
  fix.covariance_enu_m2 = to_enu * covariance_m2 * to_enu.transpose();
  fix.satellites_used = static_cast<int>(used_sats.size());
  relative.baseline_enu_m = ecef_to_enu_rotation(base_geodetic) * (position_m - base_m);
  relative.baseline_valid = true;
  fix.relative = relative;
  fix.message = note;
  return fix;
}

void add_baseline_heading(PositionFix& fix) {
  if (fix.type != FixType::kRtkFixed || !fix.relative || !fix.relative->baseline_valid) return;
  auto& r = *fix.relative;
  const double e = r.baseline_enu_m.x(), n = r.baseline_enu_m.y(), u = r.baseline_enu_m.z();
  const double h2 = e * e + n * n, h = std::sqrt(h2);
  if (h < 0.05) return;  // antennas on top of each other: no direction
  constexpr double kDeg = 180.0 / std::numbers::pi;
  double heading = std::atan2(e, n) * kDeg;
  if (heading < 0.0) heading += 360.0;
  r.heading_deg = heading;
  r.pitch_deg = std::atan2(u, h) * kDeg;
  const Eigen::Matrix3d& c = fix.covariance_enu_m2;
  const Eigen::RowVector3d dh(n / h2, -e / h2, 0.0);
  const double l2 = h2 + u * u;
  const Eigen::RowVector3d dp(-u * e / (h * l2), -u * n / (h * l2), h / l2);
  r.heading_sigma_deg = std::sqrt(std::max(0.0, (dh * c * dh.transpose())(0, 0))) * kDeg;
  r.pitch_sigma_deg = std::sqrt(std::max(0.0, (dp * c * dp.transpose())(0, 0))) * kDeg;
}

}  // namespace skytrace::positioning
