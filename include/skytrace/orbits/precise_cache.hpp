// Precise orbits for one thread's queries that move forward in time (a run's generator): each
// satellite's interpolated orbit over the SP3 interval in use is fitted once by Chebyshev series,
// then evaluated at every epoch in that interval (docs/performance.md: the full interpolation with
// its two-body passes costs about 1.5 us, a series a few dozen ns).
#pragma once

#include <Eigen/Core>

#include <array>
#include <memory>
#include <unordered_map>

#include "skytrace/orbits/precise.hpp"

namespace skytrace::orbits {

class PreciseOrbitCache final : public SatelliteStateSource {
 public:
  // Nodes of each fit (degree kNodes - 1). On 15-minute GNSS orbits the series reproduces the
  // interpolation it replaces to well below a micrometre (test PreciseOrbitCache).
  static constexpr int kNodes = 12;

  explicit PreciseOrbitCache(const PreciseEphemerides& precise) : precise_(precise) {}

  // The same values as precise.state() to within the fit's error, and the same errors: a time
  // outside the data's brackets, or in an interval the interpolation cannot serve at every node,
  // goes to the full interpolation. Not thread-safe: one cache per thread.
  [[nodiscard]] Result<SatelliteState> state(const SatelliteId& satellite, const GnssTime& t) const override;
  [[nodiscard]] Result<PreciseEphemerides::Orbit> orbit(const SatelliteId& satellite, const GnssTime& t) const;
  [[nodiscard]] std::vector<SatelliteId> satellites() const override { return precise_.satellites(); }
  [[nodiscard]] std::string_view name() const override { return precise_.name(); }

 private:
  // One satellite's fit over the SP3 interval [start, end] (epochs[first], epochs[first + 1]).
  struct Fit {
    GnssTime start, end;
    double half_span_s = 0.0;
    bool usable = false;  // false: every node did not interpolate; the full interpolation serves
    std::array<Eigen::Vector3d, kNodes> position_coefficients;
    std::array<Eigen::Vector3d, kNodes> velocity_coefficients;
  };
  void refit(Fit& fit, const SatelliteId& satellite, size_t first) const;

  const PreciseEphemerides& precise_;
  mutable std::unordered_map<SatelliteId, Fit> fits_;
};

}  // namespace skytrace::orbits
