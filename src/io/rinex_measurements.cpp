#include "skytrace/io/rinex_measurements.hpp"

#include <cmath>

namespace skytrace::io {
namespace {

// The column of type `kind` for the signal's code, else of the same band with any attribute.
std::optional<size_t> same_signal_column(const std::vector<ObservationType>& types, char kind, const Signal& signal) {
  std::optional<size_t> same_band;
  for (size_t i = 0; i < types.size(); ++i) {
    const std::string& code = types[i].code;
    if (code.size() != 3 || code[0] != kind || code[1] != signal.band) continue;
    if (code[2] == signal.attribute) return i;
    if (!same_band) same_band = i;
  }
  return same_band;
}

}  // namespace

MeasurementExtractor::MeasurementExtractor(const ObservationHeader& header) {
  for (const auto& [system, types] : header.observation_types) {
    for (size_t i = 0; i < types.size(); ++i) {
      const std::string& code = types[i].code;
      if (code.size() != 3 || code[0] != 'C') continue;
      auto signal = Signal::from_code(system, code.substr(1));
      if (!signal) continue;  // a code the catalogue does not know carries no usable range
      columns_[system].push_back(Column{*signal, i, same_signal_column(types, 'D', *signal),
                                        same_signal_column(types, 'S', *signal),
                                        same_signal_column(types, 'L', *signal)});
    }
  }
  for (const auto& slot : header.glonass_slots) glonass_channels_[slot.slot] = slot.channel;
  strength_in_dbhz_ = header.signal_strength_unit.empty() || header.signal_strength_unit == "DBHZ";
}

positioning::EpochMeasurements MeasurementExtractor::measurements(const ObservationEpoch& epoch) const {
  positioning::EpochMeasurements out;
  out.receiver_time = epoch.time;
  for (const SatelliteObservations& sat : epoch.satellites) {
    const auto columns = columns_.find(sat.satellite.system);
    if (columns == columns_.end()) continue;
    const auto value = [&](std::optional<size_t> index) -> std::optional<double> {
      if (!index || *index >= sat.values.size()) return std::nullopt;
      return sat.values[*index].value;
    };
    for (const Column& column : columns->second) {
      const std::optional<double> code = value(column.code);
      if (!code || *code == 0.0) continue;
      positioning::SignalMeasurement m;
      m.satellite = sat.satellite;
      m.signal = column.signal;
      m.pseudorange_m = *code;
      m.doppler_hz = value(column.doppler);
      if (m.doppler_hz && *m.doppler_hz == 0.0) m.doppler_hz.reset();  // blank in some writers
      if (column.phase && *column.phase < sat.values.size()) {
        const ObservationValue& phase = sat.values[*column.phase];
        if (phase.value && *phase.value != 0.0) {
          m.carrier_phase_cycles = phase.value;
          m.loss_of_lock = (phase.lli & 1U) != 0;
          m.half_cycle_unresolved = (phase.lli & 2U) != 0;
        }
      }
      if (strength_in_dbhz_) m.cn0_dbhz = value(column.strength).value_or(0.0);
      if (sat.satellite.system == GnssSystem::kGlonass) {
        const auto channel = glonass_channels_.find(sat.satellite.number);
        const SignalInfo* info = find_signal_info(column.signal);
        if (channel != glonass_channels_.end() && info != nullptr) {
          m.carrier_hz = info->carrier_frequency_hz(channel->second);
        }
      } else if (const SignalInfo* info = find_signal_info(column.signal)) {
        m.carrier_hz = info->carrier_frequency_hz();
      }
      out.signals.push_back(m);
    }
  }
  return out;
}

}  // namespace skytrace::io
