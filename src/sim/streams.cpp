#include "skytrace/sim/streams.hpp"

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

}  // namespace skytrace::sim
