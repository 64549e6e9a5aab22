// GLONASS FDMA broadcast orbit: numerical integration of the broadcast state vector.
//
// GLONASS ICD Edition 5.1 (2008), appendix A.3.1.2: the equations of motion in the rotating PZ-90
// frame hold the central term, the J2 (C20) zonal term, the centrifugal and Coriolis terms, and
// the broadcast lunisolar acceleration, which is held constant over the interval. Integrated with
// 4th-order Runge-Kutta in steps of at most 60 s, full steps first and the remainder last, the way
// RTKLIB does it, so that both give the same state to far below a millimetre.
#include <array>
#include <cmath>
#include <limits>

#include "skytrace/core/constants.hpp"
#include "skytrace/orbits/broadcast.hpp"

namespace skytrace::orbits {
namespace {

namespace k = skytrace::constants;

// State: position (m) then velocity (m/s), PZ-90 Earth-fixed.
using State = std::array<double, 6>;

constexpr double kMaxStep_s = 60.0;
// Beyond a day from t_b a broadcast GLONASS state means nothing (it is valid for +-15 min); the
// bound also keeps a wild time (a pseudorange of 1e308 m) from integrating for ever.
constexpr double kMaxPropagation_s = 86400.0;

State derivative(const State& x, const Eigen::Vector3d& lunisolar_mps2) {
  constexpr double mu = k::kGmGlonass_m3ps2;
  constexpr double omega = k::kEarthRotationRateGlonass_radps;
  constexpr double ae = k::kGlonassEarthSemiMajorAxis_m;
  const double r2_m2 = x[0] * x[0] + x[1] * x[1] + x[2] * x[2];
  const double r_m = std::sqrt(r2_m2);
  const double r3_m3 = r2_m2 * r_m;
  // 3/2 J2 mu ae^2 / r^5 (the ICD writes it with C20 = -J2).
  const double j2_term = 1.5 * k::kGlonassJ2 * mu * ae * ae / (r2_m2 * r3_m3);
  const double z2_ratio = 5.0 * x[2] * x[2] / r2_m2;
  const double radial = -mu / r3_m3 - j2_term * (1.0 - z2_ratio);
  State dx{};
  dx[0] = x[3];
  dx[1] = x[4];
  dx[2] = x[5];
  dx[3] = (radial + omega * omega) * x[0] + 2.0 * omega * x[4] + lunisolar_mps2.x();
  dx[4] = (radial + omega * omega) * x[1] - 2.0 * omega * x[3] + lunisolar_mps2.y();
  dx[5] = (radial - 2.0 * j2_term) * x[2] + lunisolar_mps2.z();
  return dx;
}

State add_scaled(const State& x, const State& dx, double h_s) {
  State out{};
  for (size_t i = 0; i < out.size(); ++i) out[i] = x[i] + dx[i] * h_s;
  return out;
}

void runge_kutta_step(State& x, double h_s, const Eigen::Vector3d& lunisolar_mps2) {
  const State k1 = derivative(x, lunisolar_mps2);
  const State k2 = derivative(add_scaled(x, k1, 0.5 * h_s), lunisolar_mps2);
  const State k3 = derivative(add_scaled(x, k2, 0.5 * h_s), lunisolar_mps2);
  const State k4 = derivative(add_scaled(x, k3, h_s), lunisolar_mps2);
  for (size_t i = 0; i < x.size(); ++i) x[i] += (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]) * h_s / 6.0;
}

}  // namespace

namespace {

State initial_state(const GlonassEphemeris& eph) {
  return {eph.position_m.x(),   eph.position_m.y(),   eph.position_m.z(),
          eph.velocity_mps.x(), eph.velocity_mps.y(), eph.velocity_mps.z()};
}

SatelliteState to_satellite_state(const GlonassEphemeris& eph, const State& x, double dt_s) {
  SatelliteState state;
  state.position_m = Eigen::Vector3d(x[0], x[1], x[2]);
  state.velocity_mps = Eigen::Vector3d(x[3], x[4], x[5]);
  // The broadcast -tau_n + gamma_n (t - t_b) already contains the relativistic effect (ICD 3.3.3).
  state.clock_bias_s = eph.minus_tau_n_s + eph.gamma_n * dt_s;
  state.clock_drift_s_per_s = eph.gamma_n;
  return state;
}

// NaN everywhere: callers test position_m.allFinite() (positioning drops the satellite).
SatelliteState unusable_state() {
  constexpr double nan = std::numeric_limits<double>::quiet_NaN();
  SatelliteState state;
  state.position_m = Eigen::Vector3d::Constant(nan);
  state.velocity_mps = Eigen::Vector3d::Constant(nan);
  state.clock_bias_s = nan;
  state.clock_drift_s_per_s = nan;
  return state;
}

}  // namespace

SatelliteState evaluate_glonass(const GlonassEphemeris& eph, const GnssTime& t) {
  const double dt_s = t - eph.toe;
  if (!(std::abs(dt_s) <= kMaxPropagation_s)) return unusable_state();
  State x = initial_state(eph);
  double remaining_s = dt_s;
  const double step_s = remaining_s < 0.0 ? -kMaxStep_s : kMaxStep_s;
  // The 1 ns guard ends the loop on rounding residue of the subtraction.
  while (std::abs(remaining_s) > 1e-9) {
    const double h_s = std::abs(remaining_s) < kMaxStep_s ? remaining_s : step_s;
    runge_kutta_step(x, h_s, eph.acceleration_mps2);
    remaining_s -= h_s;
  }
  return to_satellite_state(eph, x, dt_s);
}

SatelliteState GlonassOrbitCache::evaluate(const GlonassEphemeris& eph, const GnssTime& t) {
  const double dt_s = t - eph.toe;
  if (!(std::abs(dt_s) <= kMaxPropagation_s)) return unusable_state();
  const double step_s = dt_s < 0.0 ? -kMaxStep_s : kMaxStep_s;
  // The full steps evaluate_glonass takes, counted with the same subtractions.
  double remaining_s = dt_s;
  size_t full_steps = 0;
  while (std::abs(remaining_s) > 1e-9 && std::abs(remaining_s) >= kMaxStep_s) {
    remaining_s -= step_s;
    ++full_steps;
  }
  Nodes& nodes = nodes_[&eph];
  auto& chain = dt_s < 0.0 ? nodes.backward : nodes.forward;
  if (chain.empty()) chain.push_back(initial_state(eph));
  while (chain.size() <= full_steps) {
    State next = chain.back();
    runge_kutta_step(next, step_s, eph.acceleration_mps2);
    chain.push_back(next);
  }
  State x = chain[full_steps];
  if (std::abs(remaining_s) > 1e-9) runge_kutta_step(x, remaining_s, eph.acceleration_mps2);
  return to_satellite_state(eph, x, dt_s);
}

}  // namespace skytrace::orbits
