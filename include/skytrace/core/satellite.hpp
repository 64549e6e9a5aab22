// Satellite systems and satellite identifiers (RINEX 3 style: G05, R24, E11, C59, J02, I03, S27).
#pragma once

#include <array>
#include <compare>
#include <cstdint>
#include <functional>
#include <string>
#include <string_view>

#include "skytrace/core/error.hpp"
#include "skytrace/core/time.hpp"

namespace skytrace {

enum class GnssSystem : std::uint8_t { kGps, kGlonass, kGalileo, kBeiDou, kQzss, kNavic, kSbas };

inline constexpr std::array<GnssSystem, 7> kAllSystems = {
    GnssSystem::kGps,  GnssSystem::kGlonass, GnssSystem::kGalileo, GnssSystem::kBeiDou,
    GnssSystem::kQzss, GnssSystem::kNavic,   GnssSystem::kSbas};

// RINEX system letter: G R E C J I S.
[[nodiscard]] char system_letter(GnssSystem system);
[[nodiscard]] Result<GnssSystem> system_from_letter(char letter);
[[nodiscard]] std::string_view system_name(GnssSystem system);  // "GPS", "GLONASS", ...
// The time scale the system's navigation message is expressed in.
[[nodiscard]] TimeScale system_time_scale(GnssSystem system);

// A satellite. `number` is the RINEX satellite number: PRN for G/E/C/I, slot for R, PRN-192 for
// J (J01 = PRN 193), PRN-100 for S (S27 = PRN 127).
struct SatelliteId {
  GnssSystem system = GnssSystem::kGps;
  std::uint8_t number = 0;

  // "G05", "S27".
  [[nodiscard]] std::string to_string() const;
  // Accepts "G05", "G5", "G 5" and, for SBAS and QZSS, the full PRN ("S127", "J193").
  [[nodiscard]] static Result<SatelliteId> parse(std::string_view text);
  // The ranging-code PRN (S27 -> 127, J01 -> 193); equal to number for other systems.
  [[nodiscard]] int prn() const;

  friend auto operator<=>(const SatelliteId&, const SatelliteId&) = default;
  friend bool operator==(const SatelliteId&, const SatelliteId&) = default;
};

// Largest satellite number per system accepted by the parser.
[[nodiscard]] int max_satellite_number(GnssSystem system);

}  // namespace skytrace

template <>
struct std::hash<skytrace::SatelliteId> {
  size_t operator()(const skytrace::SatelliteId& id) const noexcept {
    return (static_cast<size_t>(id.system) << 8) | id.number;
  }
};
