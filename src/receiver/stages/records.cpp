#include "skytrace/receiver/stages/records.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "skytrace/orbits/signal_health.hpp"

namespace skytrace::receiver::stages {

std::optional<RecordState> select_record(const orbits::BroadcastEphemerides& ephemerides, const SatelliteId& sat,
                                         const GnssTime& t_receiver, std::optional<orbits::NavMessage> message,
                                         std::span<const Signal> wanted) {
  RecordState out;
  switch (sat.system) {
    case GnssSystem::kGlonass: out.glonass = ephemerides.find_glonass(sat, t_receiver, wanted); break;
    case GnssSystem::kSbas: out.sbas = ephemerides.find_sbas(sat, t_receiver, wanted); break;
    default:
      out.kepler = ephemerides.find_kepler(sat, t_receiver, message, wanted);
      if (out.kepler == nullptr && message) out.kepler = ephemerides.find_kepler(sat, t_receiver, std::nullopt, wanted);
      break;
  }
  if (out.kepler == nullptr && out.glonass == nullptr && out.sbas == nullptr) return std::nullopt;
  return out;
}

RecordState reference_record(const orbits::BroadcastEphemerides& ephemerides, const SatelliteId& sat,
                             const GnssTime& t_receiver, const RecordState& default_record,
                             std::span<const Signal> wanted) {
  using M = orbits::NavMessage;
  if (default_record.kepler == nullptr) return default_record;
  static constexpr std::array<M, 2> kGalileo{M::kGalileoInav, M::kGalileoFnav};
  static constexpr std::array<M, 3> kGps{M::kGpsLnav, M::kGpsCnav, M::kGpsCnav2};
  static constexpr std::array<M, 3> kQzss{M::kQzssLnav, M::kQzssCnav, M::kQzssCnav2};
  static constexpr std::array<M, 5> kBeiDou{M::kBeiDouD1, M::kBeiDouD2, M::kBeiDouCnav1, M::kBeiDouCnav2,
                                            M::kBeiDouCnav3};
  std::span<const M> order;
  size_t first_rank = 1;  // how many messages of `order` rank first (BeiDou: D1 and D2)
  switch (sat.system) {
    case GnssSystem::kGalileo: order = kGalileo; break;
    case GnssSystem::kGps: order = kGps; break;
    case GnssSystem::kQzss: order = kQzss; break;
    case GnssSystem::kBeiDou:
      order = kBeiDou;
      first_rank = 2;
      break;
    default: return default_record;
  }
  const M message = default_record.kepler->message;
  if (std::find(order.begin(), order.begin() + static_cast<long>(first_rank), message) !=
      order.begin() + static_cast<long>(first_rank)) {
    return default_record;  // the closest record of any message is of the reference message
  }
  for (const M message_wanted : order) {
    if (const orbits::KeplerEphemeris* eph = ephemerides.find_kepler(sat, t_receiver, message_wanted, wanted)) {
      RecordState out;
      out.kepler = eph;
      return out;
    }
  }
  return default_record;
}

RecordState record_for_signal(const orbits::BroadcastEphemerides& ephemerides, const SatelliteId& sat,
                              const GnssTime& t_receiver, const RecordState& default_record, const Signal& signal,
                              std::span<const Signal> receiver_signals) {
  if (default_record.kepler != nullptr) {
    const auto message = orbits::preferred_message(signal);
    if (message && *message != default_record.kepler->message) {
      if (auto r = select_record(ephemerides, sat, t_receiver, message, receiver_signals)) return *r;
    }
  }
  return default_record;
}

void evaluate_record(RecordState& record, const GnssTime& t, orbits::GlonassOrbitCache& glonass_orbits) {
  if (record.kepler != nullptr) {
    record.state = orbits::evaluate_kepler(*record.kepler, t);
  } else if (record.glonass != nullptr) {
    record.state = glonass_orbits.evaluate(*record.glonass, t);
  } else {
    record.state = orbits::evaluate_sbas(*record.sbas, t);
  }
}

bool signal_healthy(const RecordState& record, const Signal& signal) {
  if (record.kepler != nullptr) return orbits::signal_healthy(*record.kepler, signal);
  if (record.glonass != nullptr) return orbits::signal_healthy(*record.glonass, signal);
  return orbits::signal_healthy(*record.sbas, signal);
}
std::string health_description(const RecordState& record) {
  if (record.kepler != nullptr) return orbits::health_description(*record.kepler);
  if (record.glonass != nullptr) return orbits::health_description(*record.glonass);
  return orbits::health_description(*record.sbas);
}

double group_delay_of(const RecordState& record, const Signal& signal) {
  if (record.kepler != nullptr) return orbits::group_delay_s(*record.kepler, signal);
  if (record.glonass != nullptr) return orbits::group_delay_s(*record.glonass, signal);
  return 0.0;  // SBAS clocks refer to L1 directly
}

const RecordState& group_delay_record(const RecordState& truth, const RecordState& signal_record,
                                      const Signal& signal) {
  if (truth.kepler == nullptr) return truth;
  const auto wanted = orbits::preferred_message(signal);
  const orbits::NavMessage message = truth.kepler->message;
  if (!wanted || *wanted == message || message == orbits::NavMessage::kGalileoInav) return truth;
  if (signal_record.kepler != nullptr && signal_record.kepler->message == *wanted) return signal_record;
  return truth;
}

double precise_clock_group_delay_s(const RecordState& reference, const RecordState& delays, const Signal& signal) {
  if (delays.kepler == nullptr) return group_delay_of(delays, signal);
  const orbits::KeplerEphemeris& eph = *delays.kepler;
  switch (eph.satellite.system) {
    case GnssSystem::kGalileo:  // I/NAV records carry BGD(E1,E5a) too
      return orbits::group_delay_s(eph, signal, orbits::NavMessage::kGalileoFnav);
    case GnssSystem::kBeiDou: {
      // The B1I/B3I ionosphere-free code is late by gamma/(gamma-1) TGD1 against B3I.
      const double gamma = std::pow(kFrequencyB1I_Hz / kFrequencyB3I_Hz, 2);
      const double tgd1_s = (reference.kepler != nullptr ? *reference.kepler : eph).group_delays.tgd1_s;
      return orbits::group_delay_s(eph, signal) - gamma / (gamma - 1.0) * tgd1_s;
    }
    default: return orbits::group_delay_s(eph, signal);
  }
}

std::optional<RecordState> select_default_record(const orbits::BroadcastEphemerides& ephemerides, const SatelliteId& sat,
                                          const GnssTime& t_receiver, std::span<const Signal> wanted) {
  const std::optional<orbits::NavMessage> message =
      sat.system == GnssSystem::kGalileo ? std::optional(orbits::NavMessage::kGalileoInav) : std::nullopt;
  return select_record(ephemerides, sat, t_receiver, message, wanted);
}

}  // namespace skytrace::receiver::stages
