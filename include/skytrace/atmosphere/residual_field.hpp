// What the broadcast atmosphere models leave: spatially and temporally correlated residual fields
// of the ionosphere and the troposphere, shared by every receiver of a scenario, so that double
// differences between receivers grow with their distance (parts per million of the baseline) as
// measured instead of vanishing (docs/models/atmosphere-residuals.md).
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "skytrace/atmosphere/ionex.hpp"
#include "skytrace/atmosphere/ionosphere.hpp"
#include "skytrace/core/frames.hpp"
#include "skytrace/core/time.hpp"

namespace skytrace::atmosphere {

// A stationary Gaussian random field over horizontal positions and time: standard deviation
// `sigma_m`, covariance exp(-d^2 / (2 L^2)) in distance d and exp(-dt^2 / (2 tau^2)) in time,
// drawn as a sum of random cosine modes (spectral method; the wavevectors and frequencies from
// the Gaussian spectrum, deterministic for a seed). The gradient per axis has standard deviation
// sigma / L, which is what a baseline sees.
class ResidualField {
 public:
  struct Settings {
    double sigma_m = 0.0;
    double correlation_length_m = 100e3;
    double correlation_time_s = 1800.0;
    int modes = 64;
    std::uint64_t seed = 1;
  };
  explicit ResidualField(const Settings& settings);
  // The field at a place (latitude/longitude; heights are ignored) and time.
  [[nodiscard]] double value_m(double latitude_deg, double longitude_deg, const GnssTime& t) const;
  // Sigma and length for a gradient of `ppm` parts per million (sigma / L = ppm 1e-6).
  [[nodiscard]] static Settings for_gradient_ppm(double ppm, double correlation_length_m, double correlation_time_s,
                                                 std::uint64_t seed);

 private:
  struct Mode {
    double kx_per_m, ky_per_m, omega_per_s, phase_rad;
  };
  double amplitude_m_ = 0.0;
  std::vector<Mode> modes_;
};

// A vertical ionosphere residual at the pierce point (thin shell at 350 km), scaled by the
// shell's mapping function, added to another model's L1 group delay (the phase is advanced by the
// same amount as for the model itself).
class IonosphereWithResidual final : public IonosphereModel {
 public:
  IonosphereWithResidual(std::shared_ptr<const IonosphereModel> model, ResidualField field)
      : model_(std::move(model)), field_(std::move(field)) {}
  [[nodiscard]] Result<std::optional<double>> delay_l1_m(const GnssTime& t, const Geodetic& receiver,
                                                         const AzimuthElevation& direction) const override;
  [[nodiscard]] std::string_view name() const override { return model_ ? model_->name() : "none"; }
  // The residual alone (for tests).
  [[nodiscard]] double residual_l1_m(const GnssTime& t, const Geodetic& receiver, const AzimuthElevation& direction) const;

 private:
  std::shared_ptr<const IonosphereModel> model_;  // nullptr: no model, the residual only
  ResidualField field_;
};

// A zenith wet troposphere residual at the receiver, mapped with Chao's wet mapping function.
[[nodiscard]] double troposphere_residual_m(const ResidualField& field, const GnssTime& t, const Geodetic& receiver,
                                            const AzimuthElevation& direction);

}  // namespace skytrace::atmosphere
