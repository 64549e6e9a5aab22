// Code multipath error envelopes against the analytic envelope of an early-minus-late DLL with one
// reflection (BPSK, infinite bandwidth): Braasch, "Multipath effects", in Parkinson & Spilker,
// GPS: Theory and Applications I (1996), ch. 14; Kaplan & Hegarty, Understanding GPS (2006),
// section 6.4. Also the carrier-phase bound asin(a), lone NLOS paths, and correlation shapes.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>

#include "skytrace/receiver/multipath.hpp"

namespace skytrace::receiver {
namespace {

constexpr double kChipM = 299792458.0 / 1.023e6;  // GPS C/A chip
constexpr double kWavelengthM = 299792458.0 / 1575.42e6;

// Envelope (chips) for relative amplitude a < 1, spacing d <= 1 chip, delay delta (chips): the
// in-phase (upper) branch for sign = +1, the anti-phase (lower) branch for sign = -1.
double analytic_envelope_chips(double a, double d, double delta, int sign) {
  if (sign > 0) {
    if (delta <= (1.0 + a) * d / 2.0) return a * delta / (1.0 + a);
    if (delta <= 1.0 - d / 2.0 + a * d / 2.0) return a * d / 2.0;
    if (delta <= 1.0 + d / 2.0) return a * (1.0 + d / 2.0 - delta) / (2.0 - a);
    return 0.0;
  }
  if (delta <= (1.0 - a) * d / 2.0) return -a * delta / (1.0 - a);
  if (delta <= 1.0 - d / 2.0 - a * d / 2.0) return -a * d / 2.0;
  if (delta <= 1.0 + d / 2.0) return -a * (1.0 + d / 2.0 - delta) / (2.0 + a);
  return 0.0;
}

// One reflection whose total phase (coefficient plus excess path) is `phase_rad`.
std::vector<ReceivedPath> one_reflection(double a, double delay_m, double phase_rad) {
  ReceivedPath reflected;
  reflected.excess_delay_m = delay_m;
  // The receiver adds -2 pi delay / wavelength; cancel it so the net relative phase is phase_rad.
  reflected.amplitude = std::polar(a, phase_rad + 2.0 * std::numbers::pi * delay_m / kWavelengthM);
  return {ReceivedPath{}, reflected};
}

TEST(MultipathEnvelope, BpskEarlyLateMatchesTheAnalyticEnvelope) {
  const CorrelationFunction bpsk = CorrelationFunction::bpsk();
  for (const double a : {0.1, 0.5, 0.8}) {
    for (const double d : {1.0, 0.5, 0.1}) {
      for (double delta = 0.0; delta <= 1.6; delta += 0.0125) {
        for (const int sign : {1, -1}) {
          const auto paths = one_reflection(a, delta * kChipM, sign > 0 ? 0.0 : std::numbers::pi);
          const MultipathErrors e = multipath_errors(bpsk, kChipM, kWavelengthM, d, paths);
          EXPECT_NEAR(e.code_m / kChipM, analytic_envelope_chips(a, d, delta, sign), 1e-7)
              << "a " << a << " d " << d << " delta " << delta << " sign " << sign;
        }
      }
    }
  }
}

TEST(MultipathEnvelope, MaximumErrorIsHalfTheSpacingTimesAmplitude) {
  // The plateau of the envelope: a d / 2 chips, e.g. 0.5 * 0.1 / 2 * 293 m = 7.3 m for a narrow
  // correlator and a -6 dB reflection, 73 m for a wide one.
  const CorrelationFunction bpsk = CorrelationFunction::bpsk();
  for (const double d : {1.0, 0.1}) {
    double worst_m = 0.0;
    for (double delta = 0.0; delta <= 1.6; delta += 0.005) {
      for (double phase = 0.0; phase < 2.0 * std::numbers::pi; phase += std::numbers::pi / 8.0) {
        const MultipathErrors e = multipath_errors(bpsk, kChipM, kWavelengthM, d, one_reflection(0.5, delta * kChipM, phase));
        worst_m = std::max(worst_m, std::abs(e.code_m));
      }
    }
    EXPECT_NEAR(worst_m, 0.5 * d / 2.0 * kChipM, 1e-6 * kChipM) << d;
  }
}

TEST(MultipathEnvelope, CarrierPhaseErrorBoundedByArcsineOfAmplitude) {
  // At a short delay the phase error is atan(a sin p / (1 + a cos p)), at most asin(a) (Kaplan &
  // Hegarty 6.4): a = 0.5 gives 30 degrees, 1.6 cm at L1.
  const CorrelationFunction bpsk = CorrelationFunction::bpsk();
  double worst_m = 0.0;
  for (double phase = 0.0; phase < 2.0 * std::numbers::pi; phase += 0.001) {
    const auto paths = one_reflection(0.5, 0.0, phase);
    const MultipathErrors e = multipath_errors(bpsk, kChipM, kWavelengthM, 0.1, paths);
    const double expected_rad = std::atan2(0.5 * std::sin(phase), 1.0 + 0.5 * std::cos(phase));
    EXPECT_NEAR(e.phase_m, -expected_rad * kWavelengthM / (2.0 * std::numbers::pi), 1e-9);
    EXPECT_NEAR(e.power_db, 10.0 * std::log10(std::norm(1.0 + std::polar(0.5, phase))), 1e-9);
    worst_m = std::max(worst_m, std::abs(e.phase_m));
  }
  EXPECT_NEAR(worst_m, std::asin(0.5) / (2.0 * std::numbers::pi) * kWavelengthM, 1e-5);
}

TEST(MultipathEnvelope, LoneReflectedPathGivesItsWholeDelay) {
  // NLOS: code, phase and rate follow the one path; the power is its own.
  ReceivedPath p;
  p.excess_delay_m = 33.77;
  p.excess_delay_rate_mps = 0.012;
  p.amplitude = std::polar(0.3, 0.4);
  for (const auto& correlation : {CorrelationFunction::bpsk(), CorrelationFunction::boc(1, 1)}) {
    const MultipathErrors e = multipath_errors(correlation, kChipM, kWavelengthM, 0.1, {p});
    EXPECT_NEAR(e.code_m, 33.77, 1e-6);
    EXPECT_NEAR(e.phase_m, 33.77 - 0.4 / (2.0 * std::numbers::pi) * kWavelengthM, 1e-9);
    EXPECT_NEAR(e.range_rate_mps, 0.012, 1e-9);
    EXPECT_NEAR(e.power_db, 20.0 * std::log10(0.3), 1e-9);
  }
}

TEST(MultipathEnvelope, RangeRateFollowsTheRotatingPhase) {
  // Direct plus a reflection whose delay grows: the phase error changes at the rate predicted by
  // differencing the phase error between two close instants.
  const CorrelationFunction bpsk = CorrelationFunction::bpsk();
  ReceivedPath reflected;
  reflected.excess_delay_m = 5.0;
  reflected.excess_delay_rate_mps = 0.02;
  reflected.amplitude = 0.4;
  const MultipathErrors now = multipath_errors(bpsk, kChipM, kWavelengthM, 0.1, {ReceivedPath{}, reflected});
  ReceivedPath later = reflected;
  const double dt = 1e-3;
  later.excess_delay_m += reflected.excess_delay_rate_mps * dt;
  const MultipathErrors next = multipath_errors(bpsk, kChipM, kWavelengthM, 0.1, {ReceivedPath{}, later});
  EXPECT_NEAR(now.range_rate_mps, (next.phase_m - now.phase_m) / dt, 1e-4);
  EXPECT_NE(now.range_rate_mps, 0.0);
}

TEST(CorrelationShapes, BpskAndBoc) {
  const CorrelationFunction bpsk = CorrelationFunction::bpsk();
  EXPECT_DOUBLE_EQ(bpsk(0.0), 1.0);
  EXPECT_DOUBLE_EQ(bpsk(0.25), 0.75);
  EXPECT_DOUBLE_EQ(bpsk(-1.0), 0.0);
  // BOC(1,1): 1 - 3|t| to -1/2 at half a chip, back to 0 at one chip.
  const CorrelationFunction boc11 = CorrelationFunction::boc(1, 1);
  EXPECT_DOUBLE_EQ(boc11(0.5), -0.5);
  EXPECT_DOUBLE_EQ(boc11(1.0 / 6.0), 0.5);
  EXPECT_DOUBLE_EQ(boc11(0.75), -0.25);
  EXPECT_DOUBLE_EQ(boc11(1.2), 0.0);
  // BOC(10,5): 4 segments (+ - + -) per chip, R at quarter chips = 1, -3/4, 1/2, -1/4, 0.
  const CorrelationFunction boc105 = CorrelationFunction::boc(10, 5);
  EXPECT_DOUBLE_EQ(boc105(0.25), -0.75);
  EXPECT_DOUBLE_EQ(boc105(0.5), 0.5);
  EXPECT_DOUBLE_EQ(boc105(0.75), -0.25);
  // The modulation table: L1C TMBOC and E1 CBOC as BOC(1,1).
  EXPECT_DOUBLE_EQ(CorrelationFunction::of(Modulation{Modulation::Kind::kCboc, 1, 1})(0.5), -0.5);
}

TEST(MultipathEnvelope, Boc11ByHand) {
  // BOC(1,1), a = 0.5 in phase, delay 0.3 chips, d = 0.1: all four correlator samples lie on the
  // peak's slopes of -3 per chip (|t| < 1/2), so 6 eps = a * 3 * d, eps = a d / 2 = 0.025 chips.
  const CorrelationFunction boc = CorrelationFunction::boc(1, 1);
  EXPECT_NEAR(multipath_errors(boc, kChipM, kWavelengthM, 0.1, one_reflection(0.5, 0.3 * kChipM, 0.0)).code_m / kChipM,
              0.025, 1e-9);
  // Beyond 1 + d/2 chips the reflection no longer reaches the correlators.
  EXPECT_NEAR(multipath_errors(boc, kChipM, kWavelengthM, 0.1, one_reflection(0.5, 1.2 * kChipM, 0.0)).code_m, 0.0, 1e-9);
}

}  // namespace
}  // namespace skytrace::receiver
