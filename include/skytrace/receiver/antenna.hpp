// Antenna profiles: the antenna as a model of its own (profiles/antennas/*.yaml, format in
// docs/profiles.md). A scenario's receiver.antenna names one (by profile name, by path or by its IGS
// name as in the RINEX header ANT # / TYPE); without it the receiver profile's default_antenna.
#pragma once

#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "skytrace/core/error.hpp"
#include "skytrace/core/signal.hpp"
#include "skytrace/receiver/profile.hpp"

namespace skytrace::receiver {

// The active antenna's chain up to the receiver's connector: the element's noise temperature (sky
// and ground it sees), the LNA and the cable. Its noise temperature referred to the element's port
// (Friis, the cable a passive loss at 290 K):
//   T = T_antenna + 290 (F_lna - 1) + 290 (L_cable - 1) / G_lna
struct AntennaFrontEnd {
  double antenna_temperature_k = 130.0;
  double lna_gain_db = 30.0;
  double lna_noise_figure_db = 2.0;
  double cable_loss_db = 0.0;
  [[nodiscard]] double noise_temperature_k() const;
};

// One band's right-hand gain table with the LHCP (reflection) gain table of the same grid.
// `response_db` is the band's gain relative to its table at every elevation (a filter or element
// roll-off): kept apart from the table so that bands can share one.
struct AntennaBand {
  std::shared_ptr<const AntennaPattern> pattern;
  double response_db = 0.0;
};

struct AntennaProfile {
  std::string name;
  std::string description;
  std::string source;                  // the file it was read from ("" for a profile's inline antenna)
  std::vector<std::string> igs_names;  // normalised, "TYPE" padded to 16 then the radome ("NONE")
  // By band key: a RINEX band digit ("5") or a system letter and a digit ("R1"), which wins for
  // that system's signals of the band.
  std::map<std::string, AntennaBand> bands;
  std::optional<AntennaFrontEnd> front_end;
  // The IGS name the antenna was asked for by (normalised), else its first IGS name, else "":
  // what the RINEX header's ANT # / TYPE says.
  std::string rinex_type;

  // The band a signal is received in, or nullptr.
  [[nodiscard]] const AntennaBand* band_for(const Signal& signal) const;
};

// "ASH701945E_M SCIS" -> "ASH701945E_M    SCIS" (type padded to 16 columns, radome NONE when absent);
// nullopt for text that is no IGS name (empty, more than two words, type over 16 characters).
[[nodiscard]] std::optional<std::string> normalize_igs_name(const std::string& text);

// Parses an antenna profile from YAML text; `source` names the file in messages.
[[nodiscard]] Result<AntennaProfile> parse_antenna_profile(const std::string& yaml_text, const std::string& source);

// Folders searched for an antenna by name: the `antennas` folder of each receiver-profile folder
// (profile_search_path: beside the scenario, SKYTRACE_PROFILE_PATH, the project's profiles).
[[nodiscard]] std::vector<std::filesystem::path> antenna_search_path(const std::filesystem::path& scenario_dir);

// An antenna by path (contains '/' or ends in .yaml; relative to `scenario_dir`), by profile name
// or by IGS name (exact with its radome first; a radome no profile lists is ignored).
[[nodiscard]] Result<AntennaProfile> load_antenna(const std::string& name, const std::filesystem::path& scenario_dir = {});

// Names of the antenna profiles on the search path (sorted, without duplicates).
[[nodiscard]] std::vector<std::string> available_antenna_names(const std::filesystem::path& scenario_dir = {});

// A receiver profile's inline `antenna:` (the older profile form) as an antenna for every band.
[[nodiscard]] AntennaProfile inline_antenna(const ReceiverProfile& profile);

// Puts `antenna` in front of the receiver for `signals`: each signal's band table and response,
// and the system noise temperature with the antenna's chain in place of the default antenna's
// (both with a front_end; else the profile's temperature as it is). Errors: a band the antenna
// lacks (naming the antenna's file and the band), a system temperature that would not stay positive.
[[nodiscard]] Status attach_antenna(ReceiverProfile& profile, const AntennaProfile& antenna,
                                    const AntennaProfile* default_antenna, const std::vector<Signal>& signals);

// Resolves and attaches the receiver's antenna: `antenna` when not empty (scenario key
// receiver.antenna), else the profile's default_antenna, else its inline antenna. Messages name
// the scenario key or the profile field.
[[nodiscard]] Status attach_antenna(ReceiverProfile& profile, const std::string& antenna,
                                    const std::vector<Signal>& signals, const std::filesystem::path& scenario_dir);

// The profile (by name or path) with its antenna: `antenna` when not empty (scenario key
// receiver.antenna), else the profile's default_antenna, else its inline antenna; attached for
// `signals`. Messages name the scenario key or the profile field.
[[nodiscard]] Result<ReceiverProfile> load_profile_with_antenna(const std::string& profile_name,
                                                                const std::string& antenna,
                                                                const std::vector<Signal>& signals,
                                                                const std::filesystem::path& scenario_dir = {});

}  // namespace skytrace::receiver
