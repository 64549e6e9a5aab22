// ANTEX 1.3/1.4 antenna calibrations (receiver::parse_antex), then what a run does with an accepted
// file: the scenario's antenna looked up by its IGS name (receiver.antenna_type) and its phase
// centre resolved for a run's signals and evaluated over the sky. An accepted calibration must give
// finite range corrections everywhere, and the lookup of a type mean the file holds must find it.
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "fuzz_support.hpp"
#include "skytrace/receiver/antex.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace skytrace;
  auto file = receiver::parse_antex("fuzz.atx", fuzz::as_string(data, size));
  if (!file) return 0;
  static const std::vector<Signal> kSignals = {
      Signal::parse("G1C").value(), Signal::parse("G2W").value(), Signal::parse("G5Q").value(),
      Signal::parse("R1C").value(), Signal::parse("E1C").value(), Signal::parse("E5Q").value(),
      Signal::parse("C2I").value(), Signal::parse("J1C").value()};
  constexpr std::array<double, 7> kElevations_deg = {-5.0, 0.0, 0.001, 10.0, 45.0, 89.999, 90.0};
  constexpr std::array<double, 5> kAzimuths_deg = {0.0, 0.001, 137.5, 359.999, 360.0};
  for (const receiver::AntexAntenna& antenna : file->receiver_antennas) {
    // A type mean the reader accepted is found under the name RINEX headers give it.
    if (antenna.serial.empty() && !file->find(antenna.name())) __builtin_trap();
    auto centre = receiver::AntennaPhaseCentre::create(antenna, kSignals, "fuzz.atx");
    if (!centre) continue;
    for (const Signal& signal : kSignals) {
      for (double elevation_deg : kElevations_deg) {
        for (double azimuth_deg : kAzimuths_deg) {
          const double correction_m = centre->range_correction_m(signal, AzimuthElevation{azimuth_deg, elevation_deg});
          if (!std::isfinite(correction_m)) __builtin_trap();
        }
      }
    }
  }
  return 0;
}
