// The code, Doppler and C/N0 of RINEX observation epochs as measurements for the positioning
// engine (`skytrace position`), for RINEX 2.11, 3.0x and 4.0x files alike.
#pragma once

#include <map>
#include <vector>

#include "skytrace/io/rinex_obs.hpp"
#include "skytrace/positioning/spp.hpp"

namespace skytrace::io {

class MeasurementExtractor {
 public:
  // Maps the header's observation types once: per pseudorange type of a catalogue signal, the
  // Doppler and signal strength of the same code (else of the same band).
  explicit MeasurementExtractor(const ObservationHeader& header);

  // Every signal with a non-zero pseudorange, with the carrier phase and its LLI flags. GLONASS carriers come from the header's SLOT / FRQ #
  // (else 0: the solver takes the channel from the ephemerides). C/N0 only when the signal
  // strength unit is DBHZ or not given.
  [[nodiscard]] positioning::EpochMeasurements measurements(const ObservationEpoch& epoch) const;

 private:
  struct Column {
    Signal signal;
    size_t code = 0;
    std::optional<size_t> doppler;
    std::optional<size_t> strength;
    std::optional<size_t> phase;  // carrier phase of the same code, else of the same band
  };
  std::map<GnssSystem, std::vector<Column>> columns_;
  std::map<int, int> glonass_channels_;  // slot -> channel
  bool strength_in_dbhz_ = true;
};

}  // namespace skytrace::io
