#include "skytrace/sim/streams.hpp"

#include "skytrace/io/fix_csv.hpp"

#include <algorithm>
#include <set>
#include <tuple>

#include "skytrace/core/text_file.hpp"
#include "skytrace/receiver/profile.hpp"
#include "skytrace/sim/setup.hpp"

namespace skytrace::sim {

io::RtcmEpoch to_rtcm_epoch(const receiver::EpochObservations& epoch) {
  io::RtcmEpoch out;
  out.time = epoch.receiver_time;
  for (const auto& sat : epoch.satellites) {
    if (sat.status != receiver::SatelliteStatus::kTracked || sat.signals.empty()) continue;
    io::RtcmSatelliteObservation s;
    s.satellite = sat.satellite;
    s.glonass_channel = sat.glonass_channel;
    for (const auto& m : sat.signals) {
      io::RtcmSignalObservation o;
      o.signal = m.signal;
      o.pseudorange_m = m.pseudorange_m;
      o.phase_cycles = m.carrier_phase_cycles;
      o.doppler_hz = m.doppler_hz;
      o.cn0_dbhz = m.cn0_dbhz;
      o.lock_time_s = m.lock_time_s;
      o.half_cycle = m.half_cycle_unresolved;
      s.signals.push_back(o);
    }
    out.satellites.push_back(std::move(s));
  }
  return out;
}

io::RtcmStation rtcm_station(const Eigen::Vector3d& marker_m, const ReceiverSettings& receiver, int station_id) {
  io::RtcmStation station;
  station.station_id = station_id;
  station.arp_ecef_m = antenna_point(marker_m, receiver);
  station.antenna_height_m = receiver.antenna_height_m;
  return station;
}

RecordsInUse records_in_use(const orbits::BroadcastEphemerides& ephemerides,
                            const receiver::EpochObservations& epoch) {
  std::set<const orbits::KeplerEphemeris*> kepler;
  std::set<const orbits::GlonassEphemeris*> glonass;
  for (const auto& sat : epoch.satellites) {
    if (sat.status != receiver::SatelliteStatus::kTracked) continue;
    if (sat.satellite.system == GnssSystem::kGlonass) {
      if (const auto* g = ephemerides.find_glonass(sat.satellite, epoch.true_time)) glonass.insert(g);
      continue;
    }
    for (const auto& m : sat.signals) {
      const auto* e = ephemerides.find_kepler(sat.satellite, epoch.true_time, orbits::preferred_message(m.signal));
      if (e == nullptr) e = ephemerides.find_kepler(sat.satellite, epoch.true_time);
      if (e != nullptr) kepler.insert(e);
    }
  }
  RecordsInUse out;
  out.kepler.assign(kepler.begin(), kepler.end());
  out.glonass.assign(glonass.begin(), glonass.end());
  // Transmission order independent of addresses: by satellite, then reference time.
  std::sort(out.kepler.begin(), out.kepler.end(), [](const auto* a, const auto* b) {
    return std::tie(a->satellite, a->toe, a->message) < std::tie(b->satellite, b->toe, b->message);
  });
  std::sort(out.glonass.begin(), out.glonass.end(),
            [](const auto* a, const auto* b) { return std::tie(a->satellite, a->toe) < std::tie(b->satellite, b->toe); });
  return out;
}

Result<std::vector<std::uint8_t>> rtcm3_epoch_bytes(io::Rtcm3Stream& stream, const receiver::EpochObservations& epoch,
                                                    const RecordsInUse& records) {
  return stream.epoch(to_rtcm_epoch(epoch), records.kepler, records.glonass);
}

positioning::SolverSettings default_solver_settings(const ReceiverSettings& receiver,
                                                    const orbits::BroadcastEphemerides& ephemerides) {
  positioning::SolverSettings settings;
  settings.elevation_mask_deg = std::max(receiver.elevation_mask_deg, 5.0);
  settings.ionosphere_klobuchar = ephemerides.data().ionosphere.gps.has_value();
  settings.troposphere_saastamoinen = true;
  return settings;
}

namespace {
positioning::RtkSettings rtk_settings_of(const ReceiverSettings& rover, const receiver::ReceiverProfile& profile,
                                         const orbits::BroadcastEphemerides& ephemerides) {
  const receiver::RtkProfile& p = profile.rtk;
  positioning::RtkSettings out;
  out.single_point = default_solver_settings(rover, ephemerides);
  out.elevation_mask_deg = std::max(p.elevation_mask_deg, rover.elevation_mask_deg);
  out.min_cn0_dbhz = p.min_cn0_dbhz;
  out.ratio_threshold = p.ratio_threshold;
  out.ambiguity_mode = p.ambiguity_mode == "float"        ? positioning::AmbiguityMode::kFloat
                       : p.ambiguity_mode == "continuous" ? positioning::AmbiguityMode::kContinuous
                                                          : positioning::AmbiguityMode::kFixAndHold;
  out.dynamics = p.dynamics == "static" ? positioning::RtkDynamics::kStatic : positioning::RtkDynamics::kKinematic;
  out.estimate_velocity = p.estimate_velocity;
  out.sigma_phase_zenith_m = out.sigma_phase_elevation_m = p.sigma_phase_m;
  out.code_phase_ratio = p.code_phase_ratio;
  out.acceleration_noise_mps2 = p.acceleration_noise_mps2;
  out.ambiguity_noise_cycles = p.ambiguity_noise_cycles;
  out.cn0_weighting_dbhz = p.cn0_weighting_dbhz;
  return out;
}
}  // namespace

Result<positioning::RtkSettings> rtk_settings(const Scenario& s, size_t rover_index,
                                              const orbits::BroadcastEphemerides& ephemerides) {
  const ReceiverSettings& rover = s.receivers.at(rover_index);
  if (!rover.rtk) return make_error(ErrorCode::kInvalidArgument, "receiver '" + rover.name + "' has no rtk key");
  const auto base = std::find_if(s.receivers.begin(), s.receivers.end(),
                                 [&](const ReceiverSettings& r) { return r.name == rover.rtk->base; });
  if (base == s.receivers.end()) {
    return make_error(ErrorCode::kInvalidArgument, "receiver '" + rover.name + "': no base '" + rover.rtk->base + "'");
  }
  auto profile = receiver::load_profile(rover.profile, s.source.parent_path());
  if (!profile) return profile.error().with_context(s.source.string() + ": receiver.profile");
  auto base_profile = receiver::load_profile(base->profile, s.source.parent_path());
  if (!base_profile) return base_profile.error().with_context(s.source.string() + ": receiver.profile");
  positioning::RtkSettings out = rtk_settings_of(rover, *profile, ephemerides);
  // GLONASS inter-frequency biases differ between receiver designs: integers only within one.
  out.fix_glonass = profile->name == base_profile->name;
  return out;
}

Result<positioning::RtkSettings> rtk_settings_without_base(const ReceiverSettings& rover, const Scenario& s,
                                                           const orbits::BroadcastEphemerides& ephemerides) {
  auto profile = receiver::load_profile(rover.profile, s.source.parent_path());
  if (!profile) return profile.error().with_context(s.source.string() + ": receiver.profile");
  positioning::RtkSettings out = rtk_settings_of(rover, *profile, ephemerides);
  out.fix_glonass = false;
  return out;
}

FixStage::FixStage(const orbits::BroadcastEphemerides& ephemerides, const ReceiverSettings& receiver,
                   std::optional<positioning::RtkSettings> rtk) {
  if (rtk) {
    rtk_.emplace(ephemerides, std::move(*rtk), ephemerides.data().ionosphere.gps);
  } else {
    solver_.emplace(ephemerides, default_solver_settings(receiver, ephemerides), ephemerides.data().ionosphere.gps);
  }
}

Result<positioning::PositionFix> FixStage::solve(const receiver::EpochObservations& epoch,
                                                 const positioning::BaseEpoch* base) {
  return solve(to_measurements(epoch), base);
}

Result<positioning::PositionFix> FixStage::solve(const positioning::EpochMeasurements& measurements,
                                                 const positioning::BaseEpoch* base) {
  if (rtk_) return rtk_->solve(measurements, base);
  return solver_->solve(measurements);
}

}  // namespace skytrace::sim
