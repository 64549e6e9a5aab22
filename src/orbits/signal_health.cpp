#include "skytrace/orbits/signal_health.hpp"

#include <algorithm>
#include <array>
#include <cstdio>
#include <string_view>

namespace skytrace::orbits {
namespace {

bool attribute_in(const Signal& signal, std::string_view set) {
  return set.find(signal.attribute) != std::string_view::npos;
}

// GPS signal components as IS-GPS-200 Table 20-VIII names them. "L1 C" and "L2 C" are the civil
// codes (L1 C/A; L2C and C/A on L2), "P" the P(Y) code (and the semi- and codeless tracking of it).
enum class GpsComponent { kL1Civil, kL1P, kL1Other, kL2Civil, kL2P, kL2Other, kL5 };

GpsComponent gps_component(const Signal& s) {
  if (s.band == '1') {
    if (s.attribute == 'C') return GpsComponent::kL1Civil;
    if (attribute_in(s, "PWYN")) return GpsComponent::kL1P;
    return GpsComponent::kL1Other;  // L1C, M
  }
  if (s.band == '2') {
    if (attribute_in(s, "CSLX")) return GpsComponent::kL2Civil;
    if (attribute_in(s, "PWYND")) return GpsComponent::kL2P;
    return GpsComponent::kL2Other;  // M
  }
  return GpsComponent::kL5;
}

constexpr std::array<std::string_view, 32> kGpsSignalCodes = {
    "all signals OK", "all signals weak", "all signals dead", "all signals without data modulation",
    "L1 P signal weak", "L1 P signal dead", "L1 P signal without data modulation", "L2 P signal weak",
    "L2 P signal dead", "L2 P signal without data modulation", "L1 C signal weak", "L1 C signal dead",
    "L1 C signal without data modulation", "L2 C signal weak", "L2 C signal dead",
    "L2 C signal without data modulation", "L1 & L2 P signals weak", "L1 & L2 P signals dead",
    "L1 & L2 P signals without data modulation", "L1 & L2 C signals weak", "L1 & L2 C signals dead",
    "L1 & L2 C signals without data modulation", "L1 signals weak", "L1 signals dead",
    "L1 signals without data modulation", "L2 signals weak", "L2 signals dead",
    "L2 signals without data modulation", "SV temporarily out", "SV will be temporarily out",
    "one or more signals deformed, URA valid", "more than one combination of anomalies"};

// QZSS LNAV bit (counted from the LSB) of a signal; -1 when the word does not describe it.
int qzss_lnav_bit(const Signal& s) {
  if (s.band == '1') {
    if (s.attribute == 'C') return 4;
    if (attribute_in(s, "SLX")) return 1;
    if (attribute_in(s, "EB")) return 0;  // L1C/B
    return -1;                            // L1-SAIF
  }
  if (s.band == '2') return 3;
  if (s.band == '5' && attribute_in(s, "IQX")) return 2;
  return -1;  // L5S, L6
}
constexpr int kQzssL1Bit = 5;  // health of whichever L1 C/A or L1C/B is transmitted

// Galileo health-word components: DVS bit and the 2-bit HS above it.
struct GalileoComponent {
  const char* name;
  int dvs_bit;
};
constexpr GalileoComponent kE1B{"E1-B", 0};
constexpr GalileoComponent kE5a{"E5a", 3};
constexpr GalileoComponent kE5b{"E5b", 6};

bool galileo_component_ok(int health, const GalileoComponent& c) {
  const bool dvs = ((health >> c.dvs_bit) & 1) != 0;
  const int hs = (health >> (c.dvs_bit + 1)) & 3;
  return !dvs && hs == 0;
}

// I/NAV broadcasts the health of E1-B and E5b, F/NAV that of E5a; RINEX leaves the other bits of
// the word zero, or fills them from the other message. A component the record's message does not
// describe must be clear in the word and is judged by those the message does describe too (an F/NAV
// record of a satellite whose E5a is out of service says nothing good about its E1).
bool galileo_signal_healthy(int health, NavMessage message, const Signal& s) {
  const bool fnav = message == NavMessage::kGalileoFnav;
  const auto described_ok = [&] {
    return fnav ? galileo_component_ok(health, kE5a)
                : galileo_component_ok(health, kE1B) && galileo_component_ok(health, kE5b);
  };
  const auto ok = [&](const GalileoComponent& c) {
    const bool described = fnav ? c.dvs_bit == kE5a.dvs_bit : c.dvs_bit != kE5a.dvs_bit;
    return galileo_component_ok(health, c) && (described || described_ok());
  };
  switch (s.band) {
    case '1': return ok(kE1B);
    case '5': return ok(kE5a);
    case '7': return ok(kE5b);
    case '8': return ok(kE5a) && ok(kE5b);
    default: return described_ok();  // E6: in neither message
  }
}

bool cnav_signal_healthy(int health, const Signal& s) {
  switch (s.band) {
    case '1': return (health & 0x1) == 0;
    case '2': return (health & 0x2) == 0;
    case '5': return (health & 0x4) == 0;
    default: return true;  // QZSS L6: not in the word
  }
}

bool sbas_ranging_healthy(int health) {
  const bool mt17_unavailable = (health & 0x10) != 0;
  return mt17_unavailable || (health & 0x01) == 0;
}

constexpr int kGlonassLnFlag = 1 << 2;  // RINEX 3.05 health flags: l_n

// A word that declares every signal healthy (the common case: no search through the signals).
bool all_clear(const KeplerEphemeris& eph) { return eph.health == 0; }
bool all_clear(const GlonassEphemeris& eph) { return eph.health == 0 && (eph.health_flags & kGlonassLnFlag) == 0; }
bool all_clear(const SbasEphemeris& eph) { return sbas_ranging_healthy(eph.health); }

template <typename Record>
bool any_usable(const Record& eph, std::span<const Signal> wanted) {
  if (all_clear(eph)) return true;
  const GnssSystem system = eph.satellite.system;
  const bool any_of_system =
      std::any_of(wanted.begin(), wanted.end(), [&](const Signal& s) { return s.system == system; });
  if (any_of_system) {
    return std::any_of(wanted.begin(), wanted.end(),
                       [&](const Signal& s) { return s.system == system && signal_healthy(eph, s); });
  }
  for (const SignalInfo& info : all_signals()) {
    if (info.signal.system == system && signal_healthy(eph, info.signal)) return true;
  }
  return false;
}

std::string hex(int value) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "0x%X", static_cast<unsigned>(value));
  return buf;
}

}  // namespace

GpsLnavHealth decode_gps_lnav_health(int health) {
  return GpsLnavHealth{(health & 0x20) != 0, health & 0x1F};
}

bool gps_lnav_signal_usable(int signal_code, const Signal& signal) {
  using C = GpsComponent;
  const C c = gps_component(signal);
  const bool l1 = c == C::kL1Civil || c == C::kL1P || c == C::kL1Other;
  const bool l2 = c == C::kL2Civil || c == C::kL2P || c == C::kL2Other;
  switch (signal_code) {
    case 2:   // all signals dead
    case 28:  // SV temporarily out
    case 31:  // more than one combination: which signals is not said
      return false;
    case 5: return c != C::kL1P;
    case 8: return c != C::kL2P;
    case 11: return c != C::kL1Civil;
    case 14: return c != C::kL2Civil;
    case 17: return c != C::kL1P && c != C::kL2P;
    case 20: return c != C::kL1Civil && c != C::kL2Civil;
    case 23: return !l1;
    case 26: return !l2;
    default: return true;  // OK, weak, without data modulation, will be out, deformed
  }
}

bool signal_healthy(const KeplerEphemeris& eph, const Signal& signal) {
  const int h = eph.health;
  switch (eph.message) {
    case NavMessage::kGpsLnav: {
      const GpsLnavHealth decoded = decode_gps_lnav_health(h);
      return !decoded.nav_data_bad && gps_lnav_signal_usable(decoded.signal_code, signal);
    }
    case NavMessage::kQzssLnav: {
      const int bit = qzss_lnav_bit(signal);
      if (bit < 0) return true;
      const bool l1_transmitted = signal.band == '1' && (bit == 4 || bit == 0);
      if (l1_transmitted && ((h >> kQzssL1Bit) & 1) != 0) return false;
      return ((h >> bit) & 1) == 0;
    }
    case NavMessage::kGpsCnav:
    case NavMessage::kGpsCnav2:
    case NavMessage::kQzssCnav:
    case NavMessage::kQzssCnav2: return cnav_signal_healthy(h, signal);
    case NavMessage::kGalileoInav:
    case NavMessage::kGalileoFnav: return galileo_signal_healthy(h, eph.message, signal);
    default: return h == 0;  // BeiDou, NavIC: one flag for the satellite
  }
}

bool signal_healthy(const GlonassEphemeris& eph, const Signal&) {
  return eph.health == 0 && (eph.health_flags & kGlonassLnFlag) == 0;
}

bool signal_healthy(const SbasEphemeris& eph, const Signal&) { return sbas_ranging_healthy(eph.health); }

bool record_usable(const KeplerEphemeris& eph, std::span<const Signal> wanted) { return any_usable(eph, wanted); }
bool record_usable(const GlonassEphemeris& eph, std::span<const Signal> wanted) { return any_usable(eph, wanted); }
bool record_usable(const SbasEphemeris& eph, std::span<const Signal> wanted) { return any_usable(eph, wanted); }

std::string health_description(const KeplerEphemeris& eph) {
  const int h = eph.health;
  const std::string prefix = std::string(system_name(eph.satellite.system)) + " " +
                             std::string(to_string(eph.message)) + " health " + std::to_string(h);
  switch (eph.message) {
    case NavMessage::kGpsLnav: {
      const GpsLnavHealth d = decode_gps_lnav_health(h);
      std::string text = prefix + " (";
      if (d.nav_data_bad) text += "NAV data bad, ";
      return text + std::string(kGpsSignalCodes[static_cast<size_t>(d.signal_code)]) + ")";
    }
    case NavMessage::kQzssLnav: {
      static constexpr std::array<const char*, 6> kBits = {"L1C/B", "L1C", "L5", "L2C", "L1C/A", "L1"};
      std::string bad;
      for (size_t b = 0; b < kBits.size(); ++b) {
        if (((h >> b) & 1) != 0) bad += (bad.empty() ? "" : ", ") + std::string(kBits[b]);
      }
      return prefix + " (unhealthy: " + (bad.empty() ? "none" : bad) + ")";
    }
    case NavMessage::kGpsCnav:
    case NavMessage::kGpsCnav2:
    case NavMessage::kQzssCnav:
    case NavMessage::kQzssCnav2: {
      std::string bad;
      if ((h & 1) != 0) bad += "L1";
      if ((h & 2) != 0) bad += std::string(bad.empty() ? "" : ", ") + "L2";
      if ((h & 4) != 0) bad += std::string(bad.empty() ? "" : ", ") + "L5";
      return prefix + " (bad: " + (bad.empty() ? "none" : bad) + ")";
    }
    case NavMessage::kGalileoInav:
    case NavMessage::kGalileoFnav: {
      std::string text = prefix.substr(0, prefix.rfind(' ')) + " " + hex(h) + " (";
      bool first = true;
      for (const GalileoComponent& c : {kE1B, kE5a, kE5b}) {
        text += std::string(first ? "" : ", ") + c.name + " HS " + std::to_string((h >> (c.dvs_bit + 1)) & 3) +
                " DVS " + std::to_string((h >> c.dvs_bit) & 1);
        first = false;
      }
      return text + ")";
    }
    default: return prefix;
  }
}

std::string health_description(const GlonassEphemeris& eph) {
  return "GLONASS health B_n " + std::to_string(eph.health) + ", l_n " +
         std::to_string((eph.health_flags & kGlonassLnFlag) != 0 ? 1 : 0);
}

std::string health_description(const SbasEphemeris& eph) { return "SBAS health " + hex(eph.health); }

}  // namespace skytrace::orbits
