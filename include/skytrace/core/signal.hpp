// Signal identities keyed by RINEX 3 observation codes (band digit + tracking attribute), and the
// catalogue of carrier frequencies, chipping rates and modulations for every system.
#pragma once

#include <compare>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "skytrace/core/error.hpp"
#include "skytrace/core/satellite.hpp"

namespace skytrace {

// One signal of one system, e.g. G1C (GPS L1 C/A), E5Q (Galileo E5a pilot), R1C (GLONASS G1 C/A).
struct Signal {
  GnssSystem system = GnssSystem::kGps;
  char band = '1';       // RINEX band digit
  char attribute = 'C';  // RINEX tracking mode / channel letter

  [[nodiscard]] std::string code() const { return {band, attribute}; }  // "1C"
  [[nodiscard]] std::string to_string() const { return {system_letter(system), band, attribute}; }
  // Parses "G1C"; the signal must exist in the catalogue.
  [[nodiscard]] static Result<Signal> parse(std::string_view text);
  // Parses a two-letter code ("1C") of a given system; the signal must exist in the catalogue.
  [[nodiscard]] static Result<Signal> from_code(GnssSystem system, std::string_view code);

  friend auto operator<=>(const Signal&, const Signal&) = default;
  friend bool operator==(const Signal&, const Signal&) = default;
};

// Spreading modulation; m and n in units of 1.023 MHz (BOC(m,n): subcarrier m, chips n).
struct Modulation {
  enum class Kind { kBpsk, kBoc, kCboc, kTmboc, kAltBoc };
  Kind kind = Kind::kBpsk;
  double subcarrier_factor = 0.0;  // m (0 for BPSK)
  double chip_factor = 1.0;        // n
};

struct SignalInfo {
  Signal signal;
  std::string_view band_name;    // "L1", "E5a", "B1I", "G1"
  std::string_view description;  // "C/A", "pilot", ...
  double carrier_hz = 0.0;       // for GLONASS FDMA: the channel-0 frequency
  double fdma_channel_step_hz = 0.0;  // GLONASS FDMA: frequency step per channel number k, else 0
  double chip_rate_hz = 0.0;
  Modulation modulation;

  [[nodiscard]] bool is_fdma() const { return fdma_channel_step_hz != 0.0; }
  // Carrier frequency for GLONASS channel k (-7..+6); k is ignored for CDMA signals.
  [[nodiscard]] double carrier_frequency_hz(int glonass_channel = 0) const {
    return carrier_hz + fdma_channel_step_hz * glonass_channel;
  }
};

// The whole catalogue, ordered by system, band, attribute.
[[nodiscard]] std::span<const SignalInfo> all_signals();
// The catalogue entry of a signal, or nullptr if the system has no such signal.
[[nodiscard]] const SignalInfo* find_signal_info(const Signal& signal);
// Carrier frequency of a band of a system (any attribute), e.g. for ionosphere scaling.
[[nodiscard]] std::optional<double> band_carrier_hz(GnssSystem system, char band, int glonass_channel = 0);

// Common frequencies (Hz).
inline constexpr double kFrequencyL1_Hz = 1575.42e6;
inline constexpr double kFrequencyL2_Hz = 1227.60e6;
inline constexpr double kFrequencyL5_Hz = 1176.45e6;
inline constexpr double kFrequencyE5b_Hz = 1207.14e6;
inline constexpr double kFrequencyE5_Hz = 1191.795e6;
inline constexpr double kFrequencyE6_Hz = 1278.75e6;
inline constexpr double kFrequencyB1I_Hz = 1561.098e6;
inline constexpr double kFrequencyB3I_Hz = 1268.52e6;
inline constexpr double kFrequencyNavicS_Hz = 2492.028e6;
inline constexpr double kFrequencyG1Base_Hz = 1602.0e6;
inline constexpr double kFrequencyG1Step_Hz = 0.5625e6;
inline constexpr double kFrequencyG2Base_Hz = 1246.0e6;
inline constexpr double kFrequencyG2Step_Hz = 0.4375e6;
inline constexpr double kFrequencyG1a_Hz = 1600.995e6;
inline constexpr double kFrequencyG2a_Hz = 1248.06e6;
inline constexpr double kFrequencyG3_Hz = 1202.025e6;

}  // namespace skytrace
