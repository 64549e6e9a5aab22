#include "skytrace/core/signal.hpp"

#include <algorithm>
#include <array>

namespace skytrace {
namespace {

using K = Modulation::Kind;
constexpr double kMcps = 1.023e6;
constexpr GnssSystem G = GnssSystem::kGps, R = GnssSystem::kGlonass, E = GnssSystem::kGalileo,
                     C = GnssSystem::kBeiDou, J = GnssSystem::kQzss, I = GnssSystem::kNavic,
                     S = GnssSystem::kSbas;

constexpr SignalInfo cdma(GnssSystem sys, char band, char attr, std::string_view band_name,
                          std::string_view description, double carrier_hz, double chip_rate_hz,
                          Modulation modulation) {
  return SignalInfo{{sys, band, attr}, band_name, description, carrier_hz, 0.0, chip_rate_hz, modulation};
}
constexpr SignalInfo fdma(char band, char attr, std::string_view band_name, std::string_view description,
                          double base_hz, double step_hz, double chip_rate_hz) {
  return SignalInfo{{R, band, attr}, band_name, description, base_hz, step_hz, chip_rate_hz, {K::kBpsk, 0, chip_rate_hz / kMcps}};
}

constexpr Modulation kBpsk1{K::kBpsk, 0, 1};
constexpr Modulation kBpsk2{K::kBpsk, 0, 2};
constexpr Modulation kBpsk5{K::kBpsk, 0, 5};
constexpr Modulation kBpsk10{K::kBpsk, 0, 10};
constexpr Modulation kBoc11{K::kBoc, 1, 1};
constexpr Modulation kTmboc{K::kTmboc, 1, 1};
constexpr Modulation kCboc{K::kCboc, 1, 1};
constexpr Modulation kBoc152{K::kBoc, 15, 2.5};
constexpr Modulation kBoc105{K::kBoc, 10, 5};
constexpr Modulation kAltBoc{K::kAltBoc, 15, 10};
constexpr Modulation kBoc52{K::kBoc, 5, 2};

// RINEX 3.05 / 4.00 observation-code table (section 5.1 and tables A2-A9).
constexpr auto kCatalogue = std::to_array<SignalInfo>({
    // GPS
    cdma(G, '1', 'C', "L1", "C/A", kFrequencyL1_Hz, 1 * kMcps, kBpsk1),
    cdma(G, '1', 'S', "L1", "L1C-D (data)", kFrequencyL1_Hz, 1 * kMcps, kBoc11),
    cdma(G, '1', 'L', "L1", "L1C-P (pilot)", kFrequencyL1_Hz, 1 * kMcps, kTmboc),
    cdma(G, '1', 'X', "L1", "L1C-(D+P)", kFrequencyL1_Hz, 1 * kMcps, kTmboc),
    cdma(G, '1', 'P', "L1", "P (AS off)", kFrequencyL1_Hz, 10 * kMcps, kBpsk10),
    cdma(G, '1', 'W', "L1", "Z-tracking (P(Y) semi-codeless)", kFrequencyL1_Hz, 10 * kMcps, kBpsk10),
    cdma(G, '1', 'Y', "L1", "Y", kFrequencyL1_Hz, 10 * kMcps, kBpsk10),
    cdma(G, '1', 'M', "L1", "M", kFrequencyL1_Hz, 5 * kMcps, kBoc105),
    cdma(G, '1', 'N', "L1", "codeless", kFrequencyL1_Hz, 10 * kMcps, kBpsk10),
    cdma(G, '2', 'C', "L2", "C/A", kFrequencyL2_Hz, 1 * kMcps, kBpsk1),
    cdma(G, '2', 'D', "L2", "L1(C/A)+(P2-P1) semi-codeless", kFrequencyL2_Hz, 10 * kMcps, kBpsk10),
    cdma(G, '2', 'S', "L2", "L2C (M)", kFrequencyL2_Hz, 0.5 * kMcps, kBpsk1),
    cdma(G, '2', 'L', "L2", "L2C (L)", kFrequencyL2_Hz, 0.5 * kMcps, kBpsk1),
    cdma(G, '2', 'X', "L2", "L2C (M+L)", kFrequencyL2_Hz, 1 * kMcps, kBpsk1),
    cdma(G, '2', 'P', "L2", "P (AS off)", kFrequencyL2_Hz, 10 * kMcps, kBpsk10),
    cdma(G, '2', 'W', "L2", "Z-tracking (P(Y) semi-codeless)", kFrequencyL2_Hz, 10 * kMcps, kBpsk10),
    cdma(G, '2', 'Y', "L2", "Y", kFrequencyL2_Hz, 10 * kMcps, kBpsk10),
    cdma(G, '2', 'M', "L2", "M", kFrequencyL2_Hz, 5 * kMcps, kBoc105),
    cdma(G, '2', 'N', "L2", "codeless", kFrequencyL2_Hz, 10 * kMcps, kBpsk10),
    cdma(G, '5', 'I', "L5", "I (data)", kFrequencyL5_Hz, 10 * kMcps, kBpsk10),
    cdma(G, '5', 'Q', "L5", "Q (pilot)", kFrequencyL5_Hz, 10 * kMcps, kBpsk10),
    cdma(G, '5', 'X', "L5", "I+Q", kFrequencyL5_Hz, 10 * kMcps, kBpsk10),
    // GLONASS FDMA (carrier from the channel number k of each satellite) and CDMA
    fdma('1', 'C', "G1", "C/A", kFrequencyG1Base_Hz, kFrequencyG1Step_Hz, 0.511e6),
    fdma('1', 'P', "G1", "P", kFrequencyG1Base_Hz, kFrequencyG1Step_Hz, 5.11e6),
    fdma('2', 'C', "G2", "C/A", kFrequencyG2Base_Hz, kFrequencyG2Step_Hz, 0.511e6),
    fdma('2', 'P', "G2", "P", kFrequencyG2Base_Hz, kFrequencyG2Step_Hz, 5.11e6),
    cdma(R, '4', 'A', "G1a", "L1OCd", kFrequencyG1a_Hz, 0.5115e6, kBpsk1),
    cdma(R, '4', 'B', "G1a", "L1OCp", kFrequencyG1a_Hz, 0.5115e6, kBoc11),
    cdma(R, '4', 'X', "G1a", "L1OCd+L1OCp", kFrequencyG1a_Hz, 0.5115e6, kBoc11),
    cdma(R, '6', 'A', "G2a", "L2CSI", kFrequencyG2a_Hz, 0.5115e6, kBpsk1),
    cdma(R, '6', 'B', "G2a", "L2OCp", kFrequencyG2a_Hz, 0.5115e6, kBoc11),
    cdma(R, '6', 'X', "G2a", "L2CSI+L2OCp", kFrequencyG2a_Hz, 0.5115e6, kBoc11),
    cdma(R, '3', 'I', "G3", "I (data)", kFrequencyG3_Hz, 10.23e6, kBpsk10),
    cdma(R, '3', 'Q', "G3", "Q (pilot)", kFrequencyG3_Hz, 10.23e6, kBpsk10),
    cdma(R, '3', 'X', "G3", "I+Q", kFrequencyG3_Hz, 10.23e6, kBpsk10),
    // Galileo
    cdma(E, '1', 'A', "E1", "A (PRS)", kFrequencyL1_Hz, 2.5 * kMcps, kBoc152),
    cdma(E, '1', 'B', "E1", "B (I/NAV OS data)", kFrequencyL1_Hz, 1 * kMcps, kCboc),
    cdma(E, '1', 'C', "E1", "C (no data, pilot)", kFrequencyL1_Hz, 1 * kMcps, kCboc),
    cdma(E, '1', 'X', "E1", "B+C", kFrequencyL1_Hz, 1 * kMcps, kCboc),
    cdma(E, '1', 'Z', "E1", "A+B+C", kFrequencyL1_Hz, 1 * kMcps, kCboc),
    cdma(E, '5', 'I', "E5a", "I (F/NAV OS data)", kFrequencyL5_Hz, 10 * kMcps, kBpsk10),
    cdma(E, '5', 'Q', "E5a", "Q (pilot)", kFrequencyL5_Hz, 10 * kMcps, kBpsk10),
    cdma(E, '5', 'X', "E5a", "I+Q", kFrequencyL5_Hz, 10 * kMcps, kBpsk10),
    cdma(E, '7', 'I', "E5b", "I (I/NAV OS data)", kFrequencyE5b_Hz, 10 * kMcps, kBpsk10),
    cdma(E, '7', 'Q', "E5b", "Q (pilot)", kFrequencyE5b_Hz, 10 * kMcps, kBpsk10),
    cdma(E, '7', 'X', "E5b", "I+Q", kFrequencyE5b_Hz, 10 * kMcps, kBpsk10),
    cdma(E, '8', 'I', "E5", "E5 AltBOC I", kFrequencyE5_Hz, 10 * kMcps, kAltBoc),
    cdma(E, '8', 'Q', "E5", "E5 AltBOC Q", kFrequencyE5_Hz, 10 * kMcps, kAltBoc),
    cdma(E, '8', 'X', "E5", "E5 AltBOC I+Q", kFrequencyE5_Hz, 10 * kMcps, kAltBoc),
    cdma(E, '6', 'A', "E6", "A (PRS)", kFrequencyE6_Hz, 5 * kMcps, kBoc105),
    cdma(E, '6', 'B', "E6", "B (C/NAV data)", kFrequencyE6_Hz, 5 * kMcps, kBpsk5),
    cdma(E, '6', 'C', "E6", "C (pilot)", kFrequencyE6_Hz, 5 * kMcps, kBpsk5),
    cdma(E, '6', 'X', "E6", "B+C", kFrequencyE6_Hz, 5 * kMcps, kBpsk5),
    cdma(E, '6', 'Z', "E6", "A+B+C", kFrequencyE6_Hz, 5 * kMcps, kBpsk5),
    // BeiDou (B1I/B3I on BDS-2 and BDS-3; B1C, B2a, B2b only on BDS-3)
    cdma(C, '2', 'I', "B1I", "I", kFrequencyB1I_Hz, 2 * kMcps, kBpsk2),
    cdma(C, '2', 'Q', "B1I", "Q", kFrequencyB1I_Hz, 2 * kMcps, kBpsk2),
    cdma(C, '2', 'X', "B1I", "I+Q", kFrequencyB1I_Hz, 2 * kMcps, kBpsk2),
    cdma(C, '1', 'D', "B1C", "data", kFrequencyL1_Hz, 1 * kMcps, kBoc11),
    cdma(C, '1', 'P', "B1C", "pilot", kFrequencyL1_Hz, 1 * kMcps, kTmboc),
    cdma(C, '1', 'X', "B1C", "data+pilot", kFrequencyL1_Hz, 1 * kMcps, kTmboc),
    cdma(C, '1', 'A', "B1A", "B1A", kFrequencyL1_Hz, 2 * kMcps, kBoc11),
    cdma(C, '1', 'N', "B1", "codeless", kFrequencyL1_Hz, 2 * kMcps, kBoc11),
    cdma(C, '5', 'D', "B2a", "data", kFrequencyL5_Hz, 10 * kMcps, kBpsk10),
    cdma(C, '5', 'P', "B2a", "pilot", kFrequencyL5_Hz, 10 * kMcps, kBpsk10),
    cdma(C, '5', 'X', "B2a", "data+pilot", kFrequencyL5_Hz, 10 * kMcps, kBpsk10),
    cdma(C, '7', 'I', "B2I", "I (BDS-2)", kFrequencyE5b_Hz, 2 * kMcps, kBpsk2),
    cdma(C, '7', 'Q', "B2I", "Q (BDS-2)", kFrequencyE5b_Hz, 2 * kMcps, kBpsk2),
    cdma(C, '7', 'X', "B2I", "I+Q (BDS-2)", kFrequencyE5b_Hz, 2 * kMcps, kBpsk2),
    cdma(C, '7', 'D', "B2b", "data (BDS-3)", kFrequencyE5b_Hz, 10 * kMcps, kBpsk10),
    cdma(C, '7', 'P', "B2b", "pilot (BDS-3)", kFrequencyE5b_Hz, 10 * kMcps, kBpsk10),
    cdma(C, '7', 'Z', "B2b", "data+pilot (BDS-3)", kFrequencyE5b_Hz, 10 * kMcps, kBpsk10),
    cdma(C, '8', 'D', "B2", "B2a+B2b data", kFrequencyE5_Hz, 10 * kMcps, kAltBoc),
    cdma(C, '8', 'P', "B2", "B2a+B2b pilot", kFrequencyE5_Hz, 10 * kMcps, kAltBoc),
    cdma(C, '8', 'X', "B2", "B2a+B2b data+pilot", kFrequencyE5_Hz, 10 * kMcps, kAltBoc),
    cdma(C, '6', 'I', "B3I", "I", kFrequencyB3I_Hz, 10 * kMcps, kBpsk10),
    cdma(C, '6', 'Q', "B3I", "Q", kFrequencyB3I_Hz, 10 * kMcps, kBpsk10),
    cdma(C, '6', 'X', "B3I", "I+Q", kFrequencyB3I_Hz, 10 * kMcps, kBpsk10),
    cdma(C, '6', 'A', "B3A", "B3A", kFrequencyB3I_Hz, 10 * kMcps, kBpsk10),
    // QZSS
    cdma(J, '1', 'C', "L1", "C/A", kFrequencyL1_Hz, 1 * kMcps, kBpsk1),
    cdma(J, '1', 'E', "L1", "L1C/B", kFrequencyL1_Hz, 1 * kMcps, kBpsk1),
    cdma(J, '1', 'S', "L1", "L1C (D)", kFrequencyL1_Hz, 1 * kMcps, kBoc11),
    cdma(J, '1', 'L', "L1", "L1C (P)", kFrequencyL1_Hz, 1 * kMcps, kTmboc),
    cdma(J, '1', 'X', "L1", "L1C (D+P)", kFrequencyL1_Hz, 1 * kMcps, kTmboc),
    cdma(J, '1', 'Z', "L1", "L1-SAIF", kFrequencyL1_Hz, 1 * kMcps, kBpsk1),
    cdma(J, '1', 'B', "L1", "L1C/B", kFrequencyL1_Hz, 1 * kMcps, kBpsk1),
    cdma(J, '2', 'S', "L2", "L2C (M)", kFrequencyL2_Hz, 0.5 * kMcps, kBpsk1),
    cdma(J, '2', 'L', "L2", "L2C (L)", kFrequencyL2_Hz, 0.5 * kMcps, kBpsk1),
    cdma(J, '2', 'X', "L2", "L2C (M+L)", kFrequencyL2_Hz, 1 * kMcps, kBpsk1),
    cdma(J, '5', 'I', "L5", "I", kFrequencyL5_Hz, 10 * kMcps, kBpsk10),
    cdma(J, '5', 'Q', "L5", "Q", kFrequencyL5_Hz, 10 * kMcps, kBpsk10),
    cdma(J, '5', 'X', "L5", "I+Q", kFrequencyL5_Hz, 10 * kMcps, kBpsk10),
    cdma(J, '5', 'D', "L5", "L5S I", kFrequencyL5_Hz, 10 * kMcps, kBpsk10),
    cdma(J, '5', 'P', "L5", "L5S Q", kFrequencyL5_Hz, 10 * kMcps, kBpsk10),
    cdma(J, '5', 'Z', "L5", "L5S I+Q", kFrequencyL5_Hz, 10 * kMcps, kBpsk10),
    cdma(J, '6', 'S', "L6", "L6D", kFrequencyE6_Hz, 5 * kMcps, kBpsk5),
    cdma(J, '6', 'L', "L6", "L6P", kFrequencyE6_Hz, 5 * kMcps, kBpsk5),
    cdma(J, '6', 'X', "L6", "L6D+L6P", kFrequencyE6_Hz, 5 * kMcps, kBpsk5),
    cdma(J, '6', 'E', "L6", "L6E", kFrequencyE6_Hz, 5 * kMcps, kBpsk5),
    cdma(J, '6', 'Z', "L6", "L6D+L6E", kFrequencyE6_Hz, 5 * kMcps, kBpsk5),
    // NavIC
    cdma(I, '1', 'D', "L1", "L1 SPS data", kFrequencyL1_Hz, 1 * kMcps, kBoc11),
    cdma(I, '1', 'P', "L1", "L1 SPS pilot", kFrequencyL1_Hz, 1 * kMcps, kBoc11),
    cdma(I, '1', 'X', "L1", "L1 SPS data+pilot", kFrequencyL1_Hz, 1 * kMcps, kBoc11),
    cdma(I, '5', 'A', "L5", "SPS", kFrequencyL5_Hz, 1 * kMcps, kBpsk1),
    cdma(I, '5', 'B', "L5", "RS (data)", kFrequencyL5_Hz, 2 * kMcps, kBoc52),
    cdma(I, '5', 'C', "L5", "RS (pilot)", kFrequencyL5_Hz, 2 * kMcps, kBoc52),
    cdma(I, '5', 'X', "L5", "RS (data+pilot)", kFrequencyL5_Hz, 2 * kMcps, kBoc52),
    cdma(I, '9', 'A', "S", "SPS", kFrequencyNavicS_Hz, 1 * kMcps, kBpsk1),
    cdma(I, '9', 'B', "S", "RS (data)", kFrequencyNavicS_Hz, 2 * kMcps, kBoc52),
    cdma(I, '9', 'C', "S", "RS (pilot)", kFrequencyNavicS_Hz, 2 * kMcps, kBoc52),
    cdma(I, '9', 'X', "S", "RS (data+pilot)", kFrequencyNavicS_Hz, 2 * kMcps, kBoc52),
    // SBAS
    cdma(S, '1', 'C', "L1", "C/A", kFrequencyL1_Hz, 1 * kMcps, kBpsk1),
    cdma(S, '5', 'I', "L5", "I", kFrequencyL5_Hz, 10 * kMcps, kBpsk10),
    cdma(S, '5', 'Q', "L5", "Q", kFrequencyL5_Hz, 10 * kMcps, kBpsk10),
    cdma(S, '5', 'X', "L5", "I+Q", kFrequencyL5_Hz, 10 * kMcps, kBpsk10),
});

}  // namespace

std::span<const SignalInfo> all_signals() { return kCatalogue; }

const SignalInfo* find_signal_info(const Signal& signal) {
  for (const auto& info : kCatalogue) {
    if (info.signal == signal) return &info;
  }
  return nullptr;
}

std::optional<double> band_carrier_hz(GnssSystem system, char band, int glonass_channel) {
  for (const auto& info : kCatalogue) {
    if (info.signal.system == system && info.signal.band == band) {
      return info.carrier_frequency_hz(glonass_channel);
    }
  }
  return std::nullopt;
}

Result<Signal> Signal::from_code(GnssSystem system, std::string_view code) {
  if (code.size() != 2) {
    return make_error(ErrorCode::kInvalidArgument,
                      "invalid signal code '" + std::string(code) + "' (expected band digit and attribute, e.g. 1C)");
  }
  const Signal signal{system, code[0], code[1]};
  if (find_signal_info(signal) == nullptr) {
    std::string known;
    for (const auto& info : kCatalogue) {
      if (info.signal.system != system) continue;
      if (!known.empty()) known.push_back(' ');
      known.append({info.signal.band, info.signal.attribute});
    }
    return make_error(ErrorCode::kInvalidArgument,
                      "signal '" + signal.to_string() + "' does not exist for " +
                          std::string(system_name(system)) + " (known: " + known + ")");
  }
  return signal;
}

Result<Signal> Signal::parse(std::string_view text) {
  if (text.size() != 3) {
    return make_error(ErrorCode::kInvalidArgument,
                      "invalid signal '" + std::string(text) + "' (expected system letter, band, attribute, e.g. G1C)");
  }
  auto system = system_from_letter(text[0]);
  if (!system) return system.error().with_context("invalid signal '" + std::string(text) + "'");
  return from_code(*system, text.substr(1));
}

}  // namespace skytrace
