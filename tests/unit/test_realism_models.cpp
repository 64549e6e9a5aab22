// Receiver realism models against independent numbers: the squaring loss of semi-codeless
// tracking, time-correlated loop noise (first-order Gauss-Markov) and the flicker term of the clock.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "skytrace/core/random.hpp"
#include "skytrace/receiver/clock.hpp"
#include "skytrace/receiver/link_budget.hpp"
#include "skytrace/receiver/profile.hpp"

namespace skytrace::receiver {
namespace {

TEST(SquaringLoss, SemicodelessPyAgainstHandNumbers) {
  // T_w = 20 / 10.23 MHz = 1.955034 us. At 45 dB-Hz: 2 * 31622.78 * 1.955034e-6 = 0.123646,
  // 10 log10(1 + 1 / 0.123646) = 9.5845 dB (computed by hand with Python).
  EXPECT_NEAR(kWBitDuration_s, 1.955034e-6, 1e-12);
  EXPECT_NEAR(squaring_loss_db(45.0, kWBitDuration_s), 9.5845, 1e-3);
  // Strong signals lose little (60 dB-Hz: 0.989 dB); weak ones lose dB for dB: from 40 to 30
  // dB-Hz the loss grows by 9.85 dB.
  EXPECT_NEAR(squaring_loss_db(60.0, kWBitDuration_s), 0.9890, 1e-3);
  EXPECT_NEAR(squaring_loss_db(30.0, kWBitDuration_s) - squaring_loss_db(40.0, kWBitDuration_s), 9.8504, 1e-3);
}

TEST(SquaringLoss, OnlySemicodelessSignalsPayIt) {
  EXPECT_TRUE(is_semicodeless(Signal::parse("G2W").value()));
  EXPECT_TRUE(is_semicodeless(Signal::parse("G1W").value()));
  EXPECT_TRUE(is_semicodeless(Signal::parse("G2D").value()));
  EXPECT_FALSE(is_semicodeless(Signal::parse("G2L").value()));
  EXPECT_FALSE(is_semicodeless(Signal::parse("G1C").value()));
  EXPECT_FALSE(is_semicodeless(Signal::parse("R2P").value()));

  ReceiverProfile profile;
  profile.antenna.elevation_deg = {-90.0, 90.0};
  profile.antenna.rhcp_gain_dbic = {{3.0, 3.0}};
  profile.antenna.lhcp_gain_dbic = {{-20.0, -20.0}};
  profile.implementation_loss_db = 1.0;
  profile.system_noise_temperature_k = 290.0;
  const Eigen::Vector3d receiver(kEarthRadiusMean_m, 0.0, 0.0);
  const Eigen::Vector3d satellite(26560e3, 0.0, 0.0);  // overhead
  const TrackedSignal w{Signal::parse("G2W").value(), 0.0};
  const TrackedSignal y{Signal::parse("G2L").value(), 0.0};
  const LinkBudget bw = link_budget(profile, w, satellite, receiver, 90.0, 0.0, 0.0);
  const LinkBudget by = link_budget(profile, y, satellite, receiver, 90.0, 0.0, 0.0);
  EXPECT_DOUBLE_EQ(by.squaring_loss_db, 0.0);
  // The loss is that of the pre-squaring C/N0 (everything but the squaring loss).
  const double before_dbhz = bw.cn0_dbhz() + bw.squaring_loss_db;
  EXPECT_NEAR(bw.squaring_loss_db, squaring_loss_db(before_dbhz, kWBitDuration_s), 1e-12);
  EXPECT_GT(bw.squaring_loss_db, 3.0);
  // The signal's extra loss (a receiver's reporting offset) does not change the squaring loss.
  const TrackedSignal w_offset{Signal::parse("G2W").value(), -9.75};
  const LinkBudget bo = link_budget(profile, w_offset, satellite, receiver, 90.0, 0.0, 0.0);
  EXPECT_DOUBLE_EQ(bo.squaring_loss_db, bw.squaring_loss_db);
  EXPECT_NEAR(bo.cn0_dbhz() - bw.cn0_dbhz(), 9.75, 1e-12);
}

// Sample variance and lag-1 autocorrelation of a sequence.
std::pair<double, double> variance_and_lag1(const std::vector<double>& x) {
  double mean = 0.0;
  for (double v : x) mean += v;
  mean /= static_cast<double>(x.size());
  double var = 0.0, cov = 0.0;
  for (size_t i = 0; i < x.size(); ++i) {
    var += (x[i] - mean) * (x[i] - mean);
    if (i > 0) cov += (x[i] - mean) * (x[i - 1] - mean);
  }
  return {var / static_cast<double>(x.size()), cov / var};
}

TEST(LoopNoise, GaussMarkovKeepsTheSigmaAndCorrelatesOverTheLoopTimeConstant) {
  // A 0.25 Hz DLL: time constant 1 s. At 10 Hz the outputs are correlated exp(-0.1) = 0.9048
  // from one epoch to the next; at 30 s they are independent.
  EXPECT_DOUBLE_EQ(loop_time_constant_s(0.25), 1.0);
  EXPECT_TRUE(std::isinf(loop_time_constant_s(0.0)));
  RandomStream random(12345);
  for (const auto& [dt_s, expected_lag1] : {std::pair{0.1, std::exp(-0.1)}, std::pair{30.0, 0.0}}) {
    std::vector<double> x;
    double value = 0.0;
    for (int k = 0; k < 200000; ++k) {
      value = gauss_markov_step(value, k == 0 ? INFINITY : dt_s, 1.0, random.gaussian());
      x.push_back(value);
    }
    const auto [variance, lag1] = variance_and_lag1(x);
    EXPECT_NEAR(variance, 1.0, 0.03) << dt_s;
    EXPECT_NEAR(lag1, expected_lag1, 0.01) << dt_s;
  }
  // A new arc (infinite step) or no loop (tau infinite) draws white noise.
  EXPECT_DOUBLE_EQ(gauss_markov_step(5.0, INFINITY, 1.0, 0.3), 0.3);
  EXPECT_DOUBLE_EQ(gauss_markov_step(5.0, 1.0, INFINITY, 0.3), 0.3);
}

TEST(ReceiverClockModel, FlickerTermGivesTheBiasItsVariance) {
  // Free running, flicker only: the bias changes by 2 h-1 dt^2 in variance per step.
  OscillatorSettings oscillator;
  oscillator.h_minus1 = 7e-21;  // TCXO preset
  oscillator.steered = false;
  for (double dt_s : {1.0, 30.0}) {
    ReceiverClock clock(oscillator, false, 99);
    std::vector<double> steps;
    double last = clock.state().bias_s;
    for (int k = 0; k < 20000; ++k) {
      clock.advance(dt_s);
      steps.push_back(clock.state().bias_s - last);
      last = clock.state().bias_s;
    }
    double sum_squares = 0.0;
    for (double s : steps) sum_squares += s * s;
    const double expected = 2.0 * 7e-21 * dt_s * dt_s;
    EXPECT_NEAR(sum_squares / static_cast<double>(steps.size()) / expected, 1.0, 0.05) << dt_s;
  }
  // Without h-1 the same clock changes less (white frequency only).
  OscillatorSettings white = oscillator;
  white.h_minus1 = 0.0;
  white.h0 = 2e-19;
  ReceiverClock clock(white, false, 99);
  double sum_squares = 0.0, last = clock.state().bias_s;
  for (int k = 0; k < 20000; ++k) {
    clock.advance(1.0);
    sum_squares += (clock.state().bias_s - last) * (clock.state().bias_s - last);
    last = clock.state().bias_s;
  }
  EXPECT_NEAR(sum_squares / 20000.0 / (2e-19 / 2.0), 1.0, 0.05);
}

}  // namespace
}  // namespace skytrace::receiver
