// The navigation records of a satellite as a receiver holds them: which record it uses (by default,
// for each signal, and the satellite's reference record that carries its one clock), the
// satellite state a record gives, the signals' health and their code group delays. Shared by the
// stages: geometry evaluates the reference record, tracking reads health, errors the group delays.
#pragma once

#include <optional>
#include <span>
#include <string>

#include "skytrace/core/signal.hpp"
#include "skytrace/core/time.hpp"
#include "skytrace/orbits/broadcast.hpp"

namespace skytrace::receiver::stages {

// The ephemeris record a receiver uses, and the satellite state it gives at some instant.
struct RecordState {
  orbits::SatelliteState state;
  const orbits::KeplerEphemeris* kepler = nullptr;
  const orbits::GlonassEphemeris* glonass = nullptr;
  const orbits::SbasEphemeris* sbas = nullptr;
};

// The record a receiver holds at its own time `t_receiver` (the epoch tag, as RTKLIB selects with
// the observation time), with a Galileo message preference falling back to the other message.
// nullopt when it holds none (the broadcast layer's select_* explain why, at a cost per call).
// Only records usable for one of the `wanted` signals qualify (orbits::record_usable).
[[nodiscard]] std::optional<RecordState> select_record(const orbits::BroadcastEphemerides& ephemerides,
                                                       const SatelliteId& sat, const GnssTime& t_receiver,
                                                       std::optional<orbits::NavMessage> message,
                                                       std::span<const Signal> wanted);

// The receiver's default record of a satellite: Galileo I/NAV first, other systems any message.
[[nodiscard]] std::optional<RecordState> select_default_record(const orbits::BroadcastEphemerides& ephemerides,
                                                        const SatelliteId& sat, const GnssTime& t_receiver,
                                                        std::span<const Signal> wanted);

// The record whose orbit and clock are a satellite's truth with broadcast truth: one record per
// satellite and epoch, as a real satellite has one clock, whichever messages the navigation data
// holds. It is the record of the satellite's reference message as a receiver selects it: Galileo
// I/NAV, else F/NAV; GPS and QZSS LNAV, else CNAV, else CNAV-2; BeiDou D1 (D2 on GEOs), else
// CNAV1/2/3; the other systems have one message. `default_record` is the receiver's default selection
// (Galileo I/NAV first, other systems any message), reused when it is of the first rank.
[[nodiscard]] RecordState reference_record(const orbits::BroadcastEphemerides& ephemerides, const SatelliteId& sat,
                                           const GnssTime& t_receiver, const RecordState& default_record,
                                           std::span<const Signal> wanted);

// The record a receiver uses for a signal: the one of the message that belongs to it (Galileo E5a:
// F/NAV; GPS L2C and L5: CNAV), when it holds one usable for its signals, else the satellite's
// default record. The signal's health is read from it.
[[nodiscard]] RecordState record_for_signal(const orbits::BroadcastEphemerides& ephemerides, const SatelliteId& sat,
                                            const GnssTime& t_receiver, const RecordState& default_record,
                                            const Signal& signal, std::span<const Signal> receiver_signals);

// Evaluates the record's orbit and clock at instant t (on the GPST timeline).
void evaluate_record(RecordState& record, const GnssTime& t, orbits::GlonassOrbitCache& glonass_orbits);

// The signal's health as the record declares it, and why not when unhealthy.
[[nodiscard]] bool signal_healthy(const RecordState& record, const Signal& signal);
[[nodiscard]] std::string health_description(const RecordState& record);

// The code group delay (s) of a signal relative to the record's clock (orbits::group_delay_s).
[[nodiscard]] double group_delay_of(const RecordState& record, const Signal& signal);

// The record whose group delay parameters give a signal's code delay relative to the satellite's
// one clock (the reference record, `truth`): the reference record itself when its message
// broadcasts the signal's group delay (Galileo I/NAV carries BGD(E1,E5a) as well as BGD(E1,E5b), so
// E1, E5a and E5b all take theirs from it; GPS LNAV serves L1 C/A and P(Y), BeiDou D1/D2 B1I, B2I
// and B3I). Otherwise the record of the message that does, when the receiver holds one (GPS/QZSS
// L2C and L5: CNAV ISCs, L1C: CNAV-2; BeiDou B1C/B2a/B2b: CNAV1/2/3 TGDs): those delays refer to the
// same clock reference as the reference message's clock (GPS L1/L2 P(Y), BeiDou B3I), so no second
// clock enters. Failing both, the reference record (group_delay_s derives what it can, e.g. LNAV's
// gamma T_GD for L2C). `signal_record` is the receiver's record for the signal, which is the
// signal's own message's when the receiver holds one.
[[nodiscard]] const RecordState& group_delay_record(const RecordState& truth, const RecordState& signal_record,
                                                    const Signal& signal);

// Code group delay of a signal relative to the clock of precise products, which refer to the
// ionosphere-free combination of the IGS reference signals: GPS/QZSS L1/L2 P(Y) like the broadcast
// clock; Galileo E1/E5a like F/NAV; BeiDou B1I/B3I where the broadcast clock refers to B3I alone.
// `delays` is the record of the signal's group delay (group_delay_record), `reference` the
// satellite's reference record (BeiDou: its TGD1 converts B3I to B1I/B3I).
[[nodiscard]] double precise_clock_group_delay_s(const RecordState& reference, const RecordState& delays,
                                                 const Signal& signal);

}  // namespace skytrace::receiver::stages
