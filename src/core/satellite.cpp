#include "skytrace/core/satellite.hpp"

#include <cctype>

namespace skytrace {

char system_letter(GnssSystem system) {
  switch (system) {
    case GnssSystem::kGps: return 'G';
    case GnssSystem::kGlonass: return 'R';
    case GnssSystem::kGalileo: return 'E';
    case GnssSystem::kBeiDou: return 'C';
    case GnssSystem::kQzss: return 'J';
    case GnssSystem::kNavic: return 'I';
    case GnssSystem::kSbas: return 'S';
  }
  return '?';
}

Result<GnssSystem> system_from_letter(char letter) {
  switch (std::toupper(static_cast<unsigned char>(letter))) {
    case 'G': return GnssSystem::kGps;
    case 'R': return GnssSystem::kGlonass;
    case 'E': return GnssSystem::kGalileo;
    case 'C': return GnssSystem::kBeiDou;
    case 'J': return GnssSystem::kQzss;
    case 'I': return GnssSystem::kNavic;
    case 'S': return GnssSystem::kSbas;
    default: break;
  }
  return make_error(ErrorCode::kInvalidArgument,
                    std::string("unknown satellite system letter '") + letter +
                        "' (expected one of G R E C J I S)");
}

std::string_view system_name(GnssSystem system) {
  switch (system) {
    case GnssSystem::kGps: return "GPS";
    case GnssSystem::kGlonass: return "GLONASS";
    case GnssSystem::kGalileo: return "Galileo";
    case GnssSystem::kBeiDou: return "BeiDou";
    case GnssSystem::kQzss: return "QZSS";
    case GnssSystem::kNavic: return "NavIC";
    case GnssSystem::kSbas: return "SBAS";
  }
  return "?";
}

TimeScale system_time_scale(GnssSystem system) {
  switch (system) {
    case GnssSystem::kGps: return TimeScale::kGpst;
    case GnssSystem::kGlonass: return TimeScale::kGlonasst;
    case GnssSystem::kGalileo: return TimeScale::kGst;
    case GnssSystem::kBeiDou: return TimeScale::kBdt;
    case GnssSystem::kQzss: return TimeScale::kQzsst;
    case GnssSystem::kNavic: return TimeScale::kIrnwt;
    case GnssSystem::kSbas: return TimeScale::kGpst;
  }
  return TimeScale::kGpst;
}

int max_satellite_number(GnssSystem system) {
  switch (system) {
    case GnssSystem::kGps: return 32;
    case GnssSystem::kGlonass: return 27;  // slots 1..24 plus spares
    case GnssSystem::kGalileo: return 36;
    case GnssSystem::kBeiDou: return 63;
    case GnssSystem::kQzss: return 10;
    case GnssSystem::kNavic: return 14;
    case GnssSystem::kSbas: return 58;     // PRN 120..158
  }
  return 0;
}

// "%c%02d" written by hand: it names every row of the truth tables.
std::string SatelliteId::to_string() const {
  std::string out(1, system_letter(system));
  if (number < 10) out.push_back('0');
  if (number >= 100) out.push_back(static_cast<char>('0' + number / 100));
  if (number >= 10) out.push_back(static_cast<char>('0' + number / 10 % 10));
  out.push_back(static_cast<char>('0' + number % 10));
  return out;
}

int SatelliteId::prn() const {
  if (system == GnssSystem::kSbas) return number + 100;
  if (system == GnssSystem::kQzss) return number + 192;
  return number;
}

Result<SatelliteId> SatelliteId::parse(std::string_view text) {
  auto fail = [&](const std::string& why) -> Result<SatelliteId> {
    return make_error(ErrorCode::kInvalidArgument, "invalid satellite '" + std::string(text) + "': " + why);
  };
  if (text.size() < 2) return fail("expected a system letter and a number, e.g. G05");
  auto system = system_from_letter(text[0]);
  if (!system) return fail(system.error().message);
  int number = 0;
  bool any_digit = false;
  for (size_t i = 1; i < text.size(); ++i) {
    const char c = text[i];
    if (c == ' ' && !any_digit) continue;
    if (!std::isdigit(static_cast<unsigned char>(c))) return fail("not a number after the system letter");
    number = number * 10 + (c - '0');
    any_digit = true;
    if (number > 999) return fail("number too large");
  }
  if (!any_digit) return fail("missing satellite number");
  if (*system == GnssSystem::kSbas && number >= 100) number -= 100;
  if (*system == GnssSystem::kQzss && number >= 193) number -= 192;
  if (number < 1 || number > max_satellite_number(*system)) {
    return fail("number out of range 1.." + std::to_string(max_satellite_number(*system)) + " for " +
                std::string(system_name(*system)));
  }
  return SatelliteId{*system, static_cast<std::uint8_t>(number)};
}

}  // namespace skytrace
