#include "skytrace/receiver/ephemeris_decoding.hpp"

#include <algorithm>

namespace skytrace::receiver {

std::optional<GnssTime> ephemeris_held_from(const orbits::BroadcastEphemerides& ephemerides,
                                            const SatelliteId& satellite, const GnssTime& acquired,
                                            const std::vector<Signal>& signals) {
  const std::vector<orbits::RecordAvailability> records = ephemerides.record_availability(satellite, signals);
  const auto carried = [&](orbits::NavMessage message) {
    return std::any_of(signals.begin(), signals.end(),
                       [&](const Signal& s) { return orbits::signal_carries(s, message); });
  };
  const bool any_carried = std::any_of(records.begin(), records.end(), [&](const orbits::RecordAvailability& r) {
    return r.valid_until >= acquired && carried(r.message);
  });
  std::optional<GnssTime> earliest;
  for (const orbits::RecordAvailability& r : records) {
    if (r.valid_until < acquired) continue;  // expired before the satellite was acquired
    if (any_carried && !carried(r.message)) continue;
    GnssTime held = acquired + orbits::ephemeris_decode_time_s(r.message);
    const bool transmission_known = any_carried && r.transmitted && *r.transmitted <= r.valid_until;
    if (transmission_known && *r.transmitted > held) held = *r.transmitted;
    if (!earliest || held < *earliest) earliest = held;
  }
  return earliest;
}

}  // namespace skytrace::receiver
