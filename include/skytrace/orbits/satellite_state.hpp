// One interface for "where is satellite S at time t, how fast, and what is its clock".
#pragma once

#include <Eigen/Core>

#include <memory>
#include <string_view>
#include <vector>

#include "skytrace/core/error.hpp"
#include "skytrace/core/satellite.hpp"
#include "skytrace/core/time.hpp"

namespace skytrace::orbits {

// Satellite state at an instant t. Position and velocity are in the Earth-fixed frame of that same
// instant t (WGS84 / ITRF; PZ-90.11 and CGCS2000 are treated as identical at the centimetre level).
// The caller rotates the position into the frame at reception (Sagnac).
struct SatelliteState {
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity_mps = Eigen::Vector3d::Zero();
  // Satellite clock offset from system time as the clock polynomial (or precise clock product)
  // gives it: without the relativistic term and without group delays (the quantity SP3 holds).
  // For GLONASS, -tau_n + gamma_n (t - t_b); for SBAS, a_Gf0 + a_Gf1 (t - t_0).
  double clock_bias_s = 0.0;
  double clock_drift_s_per_s = 0.0;
  // The periodic relativistic clock correction to add to clock_bias_s for the signal's time
  // (Keplerian: F e sqrt(A) sin E; precise: -2 r.v / c^2). Zero for GLONASS and SBAS, whose
  // broadcast clocks already contain it.
  double relativistic_s = 0.0;
  double relativistic_drift_s_per_s = 0.0;
};

class SatelliteStateSource {
 public:
  virtual ~SatelliteStateSource() = default;
  // State at time t (on the GPST timeline). An error names the satellite and the time when the
  // source has no valid data for them.
  [[nodiscard]] virtual Result<SatelliteState> state(const SatelliteId& satellite, const GnssTime& t) const = 0;
  // The satellites this source knows.
  [[nodiscard]] virtual std::vector<SatelliteId> satellites() const = 0;
  [[nodiscard]] virtual std::string_view name() const = 0;
  // A source for one thread whose queries move forward in time (a run's generator), faster where
  // this source can reuse work between nearby times; nullptr: query this source itself.
  [[nodiscard]] virtual std::unique_ptr<SatelliteStateSource> sequential_view() const { return nullptr; }
};

}  // namespace skytrace::orbits
