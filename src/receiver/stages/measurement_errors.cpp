#include "skytrace/receiver/stages/measurement_errors.hpp"

#include <limits>
#include <numbers>

#include "skytrace/core/constants.hpp"

namespace skytrace::receiver::stages {

namespace {
constexpr double kC = constants::kSpeedOfLight_mps;
}  // namespace

Result<AtmosphereTerms> atmosphere_terms(atmosphere::TroposphereModel troposphere,
                                         const atmosphere::IonosphereModel* ionosphere, const GnssTime& true_time,
                                         const Geodetic& receiver, const AzimuthElevation& direction,
                                         const atmosphere::ResidualField* troposphere_residual) {
  AtmosphereTerms out;
  if (troposphere == atmosphere::TroposphereModel::kSaastamoinen) {
    out.troposphere_m = atmosphere::saastamoinen_delay_m(receiver, direction.elevation_deg).value_or(0.0);
  } else if (troposphere == atmosphere::TroposphereModel::kUnb3m) {
    const double day_of_year = true_time.day_of_year(TimeScale::kGpst);
    const auto delay = atmosphere::unb3m_delay(receiver, direction.elevation_deg, day_of_year);
    out.troposphere_m = delay ? delay->slant_m() : 0.0;
  }
  if (troposphere_residual != nullptr) {
    out.troposphere_m += atmosphere::troposphere_residual_m(*troposphere_residual, true_time, receiver, direction);
  }
  if (ionosphere != nullptr) {
    auto delay = ionosphere->delay_l1_m(true_time, receiver, direction);
    if (!delay) return delay.error();
    out.ionosphere_l1_m = delay->value_or(0.0);
  }
  return out;
}

double signal_group_delay_s(const RecordState& truth, const RecordState& signal_record, const Signal& signal,
                            bool precise_truth, double block_code_bias_m) {
  const RecordState& delays = group_delay_record(truth, signal_record, signal);
  double delay_s = precise_truth ? precise_clock_group_delay_s(truth, delays, signal) : group_delay_of(delays, signal);
  const bool broadcast_has_it = delays.kepler != nullptr && orbits::is_cnav(delays.kepler->message);
  if (block_code_bias_m != 0.0 && !broadcast_has_it) delay_s += block_code_bias_m / kC;
  return delay_s;
}

double block_code_bias_m(SatelliteBlock block, const Signal& signal) {
  // GPS L5 (I5, Q5 and both): least squares of real minus simulated code over ESBC 2020-177's first
  // hour (PolaRx5, el >= 10 deg, each epoch's median removed), one term per block: III - IIF = 4.06 m.
  if (signal.system == GnssSystem::kGps && signal.band == '5' && block == SatelliteBlock::kGpsIIIA) return 4.1;
  return 0.0;
}

MultipathErrors signal_multipath_errors(const SignalInfo& info, int glonass_channel, double spacing_chips,
                                        const std::vector<ReceivedPath>& paths) {
  if (paths.empty()) return {};
  return multipath_errors(CorrelationFunction::of(info.modulation), kC / info.chip_rate_hz,
                          kC / info.carrier_frequency_hz(glonass_channel), spacing_chips, paths);
}

LoopErrors LoopNoise::draw(const SatelliteId& sat, const Signal& signal, const ReceiverProfile& profile,
                           const SignalInfo& info, double carrier_hz, double cn0_dbhz,
                           std::optional<AidingLoop> aiding, bool continuing, const GnssTime& tag) {
  const SignalKey key{sat, signal};
  auto it = streams_.find(key);
  if (it == streams_.end()) {
    const auto rx = static_cast<std::uint64_t>(receiver_index_);
    it = streams_
             .emplace(key, Streams(stream_key(seed_, {hash_name("tracking-noise"), rx, satellite_key(sat),
                                                      signal_key(signal)})))
             .first;
  }
  Streams& streams = it->second;
  const bool aided = aiding.has_value() && profile.semicodeless_aiding_bandwidth_hz > 0.0;
  const TrackingNoise sigma = tracking_noise(profile, info, carrier_hz, cn0_dbhz);
  const double phase_bandwidth_hz = aided ? profile.semicodeless_aiding_bandwidth_hz : profile.pll_bandwidth_hz;
  // Loop outputs, correlated over each loop's time constant (profile.hpp); a new arc starts afresh.
  LoopNoiseState& loops = streams.loops;
  const double now_s = tag.gpst_seconds_approx();
  const double dt_s = loops.started && continuing ? now_s - loops.last_s : std::numeric_limits<double>::infinity();
  loops.code = gauss_markov_step(loops.code, dt_s, loop_time_constant_s(profile.dll_bandwidth_hz),
                                 streams.noise.gaussian());
  loops.phase = gauss_markov_step(loops.phase, dt_s, loop_time_constant_s(phase_bandwidth_hz), streams.noise.gaussian());
  loops.doppler = gauss_markov_step(loops.doppler, dt_s, loop_time_constant_s(profile.fll_bandwidth_hz),
                                    streams.noise.gaussian());
  loops.started = true;
  loops.last_s = now_s;
  LoopErrors out;
  out.code_m = sigma.code_m * loops.code;
  out.phase_m = sigma.phase_m * loops.phase;
  if (aided) {
    // The aided loop's phase is the C/A loop's (in metres) plus what its narrow loop adds.
    const double wavelength_m = kC / carrier_hz;
    const double residual_m =
        pll_jitter_rad(profile, cn0_dbhz, phase_bandwidth_hz) * wavelength_m / (2.0 * std::numbers::pi);
    out.phase_m = aiding->phase_m + residual_m * loops.phase;
  }
  out.doppler_mps = aiding ? aiding->doppler_mps : sigma.doppler_mps * loops.doppler;
  return out;
}

}  // namespace skytrace::receiver::stages
