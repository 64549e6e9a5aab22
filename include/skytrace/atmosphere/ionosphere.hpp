// Ionosphere models behind one interface, so the observation engine can take the broadcast
// Klobuchar model or a global ionosphere map (IONEX, see ionex.hpp) as the truth.
#pragma once

#include <optional>
#include <string_view>

#include "skytrace/atmosphere/models.hpp"
#include "skytrace/core/error.hpp"
#include "skytrace/core/frames.hpp"
#include "skytrace/core/time.hpp"
#include "skytrace/orbits/ephemeris.hpp"

namespace skytrace::atmosphere {

// GPS L1 carrier frequency, the reference of delay_l1_m.
inline constexpr double kIonosphereReferenceFrequency_hz = 1575.42e6;

// First-order ionospheric group delay in metres of a signal of `frequency_hz` crossing `stec_tecu`
// TEC units of slant total electron content: 40.3 / f^2 * STEC (1 TECU = 1e16 electrons / m^2).
// The carrier phase is advanced by the same amount.
inline constexpr double kIonosphereDelayFactor_m_hz2_per_tecu = 40.3e16;
[[nodiscard]] constexpr double ionosphere_group_delay_m(double stec_tecu, double frequency_hz) {
  return kIonosphereDelayFactor_m_hz2_per_tecu * stec_tecu / (frequency_hz * frequency_hz);
}

class IonosphereModel {
 public:
  virtual ~IonosphereModel() = default;
  // Group delay on GPS L1 (1575.42 MHz) in metres for a receiver at `receiver` looking in
  // `direction` at time t (GPST timeline); another frequency f scales it by (1575.42 MHz / f)^2.
  // nullopt below the horizon (never a silent 0); an error when the model has no data for t or
  // for the pierce point (IONEX: outside the file's maps or a missing grid value).
  [[nodiscard]] virtual Result<std::optional<double>> delay_l1_m(
      const GnssTime& t, const Geodetic& receiver, const AzimuthElevation& direction) const = 0;
  [[nodiscard]] virtual std::string_view name() const = 0;
};

// The GPS broadcast model (IS-GPS-200 20.3.3.5.2.5) with the coefficients of a navigation file's
// header. Defined everywhere at all times: it never returns an error.
class KlobucharIonosphere final : public IonosphereModel {
 public:
  explicit KlobucharIonosphere(orbits::KlobucharCoefficients coefficients)
      : coefficients_(coefficients) {}

  [[nodiscard]] Result<std::optional<double>> delay_l1_m(
      const GnssTime& t, const Geodetic& receiver,
      const AzimuthElevation& direction) const override {
    return klobuchar_delay_l1_m(coefficients_, t, receiver, direction);
  }
  [[nodiscard]] std::string_view name() const override { return "klobuchar"; }
  [[nodiscard]] const orbits::KlobucharCoefficients& coefficients() const { return coefficients_; }

 private:
  orbits::KlobucharCoefficients coefficients_;
};

}  // namespace skytrace::atmosphere
