#include "skytrace/receiver/antenna.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <set>
#include <sstream>

#include "pattern_table.hpp"
#include "skytrace/core/text_file.hpp"
#include "skytrace/core/yaml_field.hpp"

namespace skytrace::receiver {
namespace {

using detail::check_increasing;
using detail::looks_like_path;
using detail::parse_gain_rows;

// The reference temperature of noise figures and of a passive loss (IEEE).
constexpr double kReferenceTemperature_k = 290.0;
// The gains a band table may hold (dBic): beyond them a table is a typo, not an antenna.
constexpr double kMinGain_dbic = -40.0;
constexpr double kMaxGain_dbic = 20.0;

double from_db(double db) { return std::pow(10.0, db / 10.0); }

std::string trim(const std::string& text) {
  const auto first = text.find_first_not_of(" \t");
  if (first == std::string::npos) return "";
  return text.substr(first, text.find_last_not_of(" \t") - first + 1);
}

bool valid_band_key(const std::string& key) {
  if (key.size() == 1) return key[0] >= '1' && key[0] <= '9';
  return key.size() == 2 && std::string_view("GRECJIS").find(key[0]) != std::string_view::npos && key[1] >= '1' &&
         key[1] <= '9';
}

// "1, 2, R1" -> {"1", "2", "R1"}.
std::vector<std::string> band_keys(const YamlField& node, const std::string& text) {
  std::vector<std::string> keys;
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, ',');) {
    const std::string key = trim(item);
    if (!valid_band_key(key)) {
      node.fail("band '" + key + "': expected a RINEX band digit (1-9) or a system letter and a digit (R1 for GLONASS G1), "
                "several separated by commas");
    }
    keys.push_back(key);
  }
  return keys;
}

std::string joined(const std::vector<std::string>& items) {
  std::string out;
  for (const auto& item : items) out += (out.empty() ? "" : ", ") + item;
  return out;
}

AntennaProfile parse_root(const YamlField& root, const std::string& source) {
  root.expect_keys({"name", "description", "igs_names", "elevation_deg", "azimuth_deg", "gain_dbic",
                    "band_response_db", "lhcp_gain_dbic", "lhcp_rejection_db", "front_end"});
  AntennaProfile a;
  a.source = source;
  a.name = root.required("name").as_string();
  if (auto c = root.child("description")) a.description = c->as_string();
  if (auto c = root.child("igs_names")) {
    for (const YamlField& item : c->as_list_or_single()) {
      auto name = normalize_igs_name(item.as_string());
      if (!name) item.fail("'" + item.as_string() + "' is no IGS antenna name (TYPE RADOME, type up to 16 characters)");
      a.igs_names.push_back(*name);
    }
  }
  const YamlField elevation = root.required("elevation_deg");
  std::vector<double> elevations = elevation.as_doubles_in(-90.0, 90.0);
  check_increasing(elevation, elevations);
  std::vector<double> azimuths;
  if (auto c = root.child("azimuth_deg")) {
    azimuths = c->as_doubles_in(0.0, 359.999999);
    check_increasing(*c, azimuths);
  }
  const auto lhcp_gain = root.child("lhcp_gain_dbic");
  const auto lhcp_rejection = root.child("lhcp_rejection_db");
  if (lhcp_gain.has_value() == lhcp_rejection.has_value()) {
    root.fail("give one of lhcp_gain_dbic (LHCP gain per elevation) or lhcp_rejection_db (RHCP minus LHCP gain)");
  }
  const auto lhcp_rows = lhcp_gain ? parse_gain_rows(*lhcp_gain, elevations.size(), azimuths.size(), -60.0, kMaxGain_dbic)
                                   : parse_gain_rows(*lhcp_rejection, elevations.size(), azimuths.size(), -10.0, 60.0);

  const YamlField gains = root.required("gain_dbic");
  for (const auto& [key_text, rows_node] : gains.entries()) {
    auto pattern = std::make_shared<AntennaPattern>();
    pattern->elevation_deg = elevations;
    pattern->azimuth_deg = azimuths;
    pattern->rhcp_gain_dbic = parse_gain_rows(rows_node, elevations.size(), azimuths.size(), kMinGain_dbic, kMaxGain_dbic);
    if (lhcp_gain) {
      pattern->lhcp_gain_dbic = lhcp_rows;
    } else {
      pattern->lhcp_gain_dbic = pattern->rhcp_gain_dbic;
      for (size_t row = 0; row < lhcp_rows.size(); ++row) {
        for (size_t i = 0; i < lhcp_rows[row].size(); ++i) pattern->lhcp_gain_dbic[row][i] -= lhcp_rows[row][i];
      }
    }
    for (const std::string& key : band_keys(rows_node, key_text)) {
      if (!a.bands.emplace(key, AntennaBand{pattern, 0.0}).second) rows_node.fail("band " + key + " given twice");
    }
  }
  if (a.bands.empty()) gains.fail("give the gain of at least one band");
  if (auto responses = root.child("band_response_db")) {
    for (const auto& [key_text, value] : responses->entries()) {
      const double db = value.as_double_in(kMinGain_dbic, kMaxGain_dbic);
      for (const std::string& key : band_keys(value, key_text)) {
        const auto band = a.bands.find(key);
        if (band == a.bands.end()) value.fail("band " + key + " has no gain_dbic table");
        band->second.response_db = db;
      }
    }
  }
  if (auto c = root.child("front_end")) {
    c->expect_keys({"antenna_temperature_k", "lna_gain_db", "lna_noise_figure_db", "cable_loss_db"});
    AntennaFrontEnd f;
    f.antenna_temperature_k = c->required("antenna_temperature_k").as_double_in(0.0, 1000.0);
    f.lna_gain_db = c->required("lna_gain_db").as_double_in(0.0, 60.0);
    f.lna_noise_figure_db = c->required("lna_noise_figure_db").as_double_in(0.0, 20.0);
    f.cable_loss_db = c->required("cable_loss_db").as_double_in(0.0, 40.0);
    a.front_end = f;
  }
  a.rinex_type = a.igs_names.empty() ? "" : a.igs_names.front();
  return a;
}

struct IgsName {
  std::string type;
  std::string radome;
};
IgsName split_igs(const std::string& normalized) {
  return {trim(normalized.substr(0, std::min<size_t>(16, normalized.size()))),
          normalized.size() > 16 ? trim(normalized.substr(16)) : std::string("NONE")};
}

Result<AntennaProfile> read_antenna_file(const std::filesystem::path& file) {
  auto text = read_text_file(file);
  if (!text) return text.error();
  return parse_antenna_profile(*text, file.string());
}

std::vector<std::filesystem::path> antenna_files(const std::filesystem::path& scenario_dir) {
  // First of each name along the search path, as a lookup by name finds it.
  std::vector<std::filesystem::path> files;
  std::set<std::string> seen;
  std::error_code ec;
  for (const auto& dir : antenna_search_path(scenario_dir)) {
    if (!std::filesystem::is_directory(dir, ec)) continue;
    std::vector<std::filesystem::path> here;
    for (const auto& entry : std::filesystem::directory_iterator(dir, ec)) {
      if (entry.path().extension() == ".yaml") here.push_back(entry.path());
    }
    std::sort(here.begin(), here.end());
    for (auto& file : here) {
      if (seen.insert(file.stem().string()).second) files.push_back(std::move(file));
    }
  }
  return files;
}

// The antenna whose igs_names hold `wanted` (normalised): with its radome first, then the type
// alone when no profile lists that radome.
std::optional<Result<AntennaProfile>> find_by_igs_name(const std::string& wanted, const std::filesystem::path& scenario_dir) {
  const IgsName w = split_igs(wanted);
  std::optional<std::filesystem::path> by_type;
  for (const auto& file : antenna_files(scenario_dir)) {
    auto antenna = read_antenna_file(file);
    if (!antenna) continue;  // a broken file is reported when asked for by its name
    for (const auto& name : antenna->igs_names) {
      const IgsName n = split_igs(name);
      if (n.type != w.type) continue;
      if (n.radome == w.radome) return antenna;
      if (!by_type) by_type = file;
    }
  }
  if (by_type) return read_antenna_file(*by_type);
  return std::nullopt;
}

}  // namespace

double AntennaFrontEnd::noise_temperature_k() const {
  return antenna_temperature_k + kReferenceTemperature_k * (from_db(lna_noise_figure_db) - 1.0) +
         kReferenceTemperature_k * (from_db(cable_loss_db) - 1.0) / from_db(lna_gain_db);
}

const AntennaBand* AntennaProfile::band_for(const Signal& signal) const {
  const std::string digit(1, signal.band);
  if (auto it = bands.find(std::string(1, system_letter(signal.system)) + digit); it != bands.end()) return &it->second;
  if (auto it = bands.find(digit); it != bands.end()) return &it->second;
  return nullptr;
}

std::optional<std::string> normalize_igs_name(const std::string& text) {
  std::istringstream in(text);
  std::vector<std::string> words;
  for (std::string word; in >> word;) words.push_back(word);
  if (words.empty() || words.size() > 2 || words[0].size() > 16 || (words.size() == 2 && words[1].size() > 4)) {
    return std::nullopt;
  }
  std::string type = words[0];
  std::transform(type.begin(), type.end(), type.begin(), [](unsigned char c) { return std::toupper(c); });
  std::string radome = words.size() == 2 ? words[1] : "NONE";
  std::transform(radome.begin(), radome.end(), radome.begin(), [](unsigned char c) { return std::toupper(c); });
  type.resize(16, ' ');
  return type + radome;
}

Result<AntennaProfile> parse_antenna_profile(const std::string& yaml_text, const std::string& source) {
  try {
    const YAML::Node root = YAML::Load(yaml_text);
    if (!root || root.IsNull()) return make_error(ErrorCode::kParse, source + ": empty antenna profile");
    if (auto duplicate = find_duplicate_key(root, source)) return make_error(ErrorCode::kParse, *duplicate);
    return parse_root(YamlField(root, "", &source, "antenna profile"), source);
  } catch (const YamlFieldError& e) {
    return make_error(ErrorCode::kParse, e.message);
  } catch (const YAML::Exception& e) {
    return make_error(ErrorCode::kParse, source + ":" + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
}

std::vector<std::filesystem::path> antenna_search_path(const std::filesystem::path& scenario_dir) {
  std::vector<std::filesystem::path> dirs;
  for (const auto& dir : profile_search_path(scenario_dir)) dirs.push_back(dir / "antennas");
  return dirs;
}

Result<AntennaProfile> load_antenna(const std::string& name, const std::filesystem::path& scenario_dir) {
  std::error_code ec;
  const auto igs = normalize_igs_name(name);
  if (looks_like_path(name)) {
    std::filesystem::path file = name;
    if (file.is_relative() && !scenario_dir.empty()) file = scenario_dir / file;
    if (std::filesystem::is_regular_file(file, ec)) return read_antenna_file(file);
    // IGS types may hold a '/' (AOAD/M_T): a name before a missing file.
    if (igs) {
      if (auto found = find_by_igs_name(*igs, scenario_dir)) {
        if (*found) (*found)->rinex_type = *igs;
        return std::move(*found);
      }
    }
    return make_error(ErrorCode::kNotFound, "antenna profile file not found: " + file.string());
  }
  std::string searched;
  for (const auto& dir : antenna_search_path(scenario_dir)) {
    const auto candidate = dir / (name + ".yaml");
    if (std::filesystem::is_regular_file(candidate, ec)) return read_antenna_file(candidate);
    searched += (searched.empty() ? "" : ", ") + dir.string();
  }
  if (igs) {
    if (auto found = find_by_igs_name(*igs, scenario_dir)) {
      if (*found) (*found)->rinex_type = *igs;
      return std::move(*found);
    }
  }
  return make_error(ErrorCode::kNotFound, "unknown antenna '" + name + "' (no antenna profile of that name or IGS name; known: " +
                                              joined(available_antenna_names(scenario_dir)) + "; searched " + searched + ")");
}

std::vector<std::string> available_antenna_names(const std::filesystem::path& scenario_dir) {
  std::set<std::string> names;
  for (const auto& file : antenna_files(scenario_dir)) names.insert(file.stem().string());
  return {names.begin(), names.end()};
}

AntennaProfile inline_antenna(const ReceiverProfile& profile) {
  AntennaProfile a;
  a.name = profile.name + " (inline antenna)";
  a.source = profile.source;
  const auto pattern = std::make_shared<AntennaPattern>(profile.antenna);
  for (char digit = '1'; digit <= '9'; ++digit) a.bands.emplace(std::string(1, digit), AntennaBand{pattern, 0.0});
  return a;
}

Status attach_antenna(ReceiverProfile& profile, const AntennaProfile& antenna, const AntennaProfile* default_antenna,
                      const std::vector<Signal>& signals) {
  const std::string where = antenna.source.empty() ? antenna.name : antenna.source;
  for (const Signal& signal : signals) {
    const TrackedSignal* tracked = profile.tracked(signal);
    if (tracked == nullptr) continue;  // the caller says which signals the receiver cannot track
    const AntennaBand* band = antenna.band_for(signal);
    if (band == nullptr) {
      std::vector<std::string> keys;
      for (const auto& [key, b] : antenna.bands) keys.push_back(key);
      return make_error(ErrorCode::kNotFound,
                        where + ": gain_dbic: no band " + std::string(1, signal.band) + " for " + signal.to_string() +
                            " (antenna '" + antenna.name + "' gives bands " + joined(keys) + ")");
    }
    TrackedSignal entry = *tracked;
    entry.antenna = band->pattern;
    entry.antenna_band_response_db = band->response_db;
    auto existing = std::find_if(profile.signals.begin(), profile.signals.end(),
                                 [&](const TrackedSignal& t) { return t.signal == signal; });
    if (existing != profile.signals.end()) {
      *existing = std::move(entry);
    } else {
      profile.signals.push_back(std::move(entry));  // a profile tracking every signal
    }
  }
  // The profile's temperature holds its default antenna's chain: the antenna in use replaces it.
  // The same chain gives a difference of exactly zero, so the default keeps today's C/N0.
  if (default_antenna != nullptr && default_antenna->front_end && antenna.front_end) {
    const double chain_change_k =
        antenna.front_end->noise_temperature_k() - default_antenna->front_end->noise_temperature_k();
    const double system_k = profile.system_noise_temperature_k + chain_change_k;
    if (!(system_k >= 10.0)) {
      return make_error(ErrorCode::kParse,
                        profile.source + ": front_end.system_noise_temperature_k: " +
                            std::to_string(profile.system_noise_temperature_k) + " K less the default antenna's chain (" +
                            std::to_string(default_antenna->front_end->noise_temperature_k()) + " K) plus " + where +
                            "'s (" + std::to_string(antenna.front_end->noise_temperature_k()) + " K) leaves no receiver");
    }
    profile.system_noise_temperature_k = system_k;
  }
  // Signals without a table of their own (none once attached) and callers reading the profile's
  // table get the L1 band's.
  if (const auto l1 = antenna.bands.find("1"); l1 != antenna.bands.end()) profile.antenna = *l1->second.pattern;
  profile.antenna_name = antenna.name;
  profile.antenna_rinex_type = antenna.rinex_type;
  return Ok{};
}

Status attach_antenna(ReceiverProfile& profile, const std::string& antenna, const std::vector<Signal>& signals,
                      const std::filesystem::path& scenario_dir) {
  std::optional<AntennaProfile> default_antenna;
  if (!profile.default_antenna.empty()) {
    auto loaded = load_antenna(profile.default_antenna, scenario_dir);
    if (!loaded) return loaded.error().with_context(profile.source + ": default_antenna");
    default_antenna = std::move(*loaded);
  }
  AntennaProfile used;
  if (!antenna.empty()) {
    auto loaded = load_antenna(antenna, scenario_dir);
    if (!loaded) return loaded.error().with_context("receiver.antenna");
    used = std::move(*loaded);
  } else if (default_antenna) {
    used = *default_antenna;
  } else if (profile.inline_antenna) {
    used = inline_antenna(profile);
  } else {
    return make_error(ErrorCode::kNotFound, "receiver.antenna: receiver profile " + profile.source +
                                                " names no default_antenna: give receiver.antenna (known: " +
                                                joined(available_antenna_names(scenario_dir)) + ")");
  }
  if (auto st = attach_antenna(profile, used, default_antenna ? &*default_antenna : nullptr, signals); !st) {
    return st.error().with_context(antenna.empty() ? "receiver profile " + profile.name + "'s default antenna"
                                                   : "receiver.antenna");
  }
  return Ok{};
}

Result<ReceiverProfile> builtin_profile(const std::string& name) {
  auto profile = load_profile(name);
  if (!profile) return profile;
  std::vector<Signal> signals;
  if (profile->all_signals) {
    for (const SignalInfo& info : skytrace::all_signals()) signals.push_back(info.signal);
  } else {
    for (const TrackedSignal& t : profile->signals) signals.push_back(t.signal);
  }
  if (auto st = attach_antenna(*profile, std::string(), signals, {}); !st) return st.error();
  return profile;
}

Result<ReceiverProfile> load_profile_with_antenna(const std::string& profile_name, const std::string& antenna,
                                                  const std::vector<Signal>& signals,
                                                  const std::filesystem::path& scenario_dir) {
  auto profile = load_profile(profile_name, scenario_dir);
  if (!profile) return profile.error().with_context("receiver.profile");
  if (auto st = attach_antenna(*profile, antenna, signals, scenario_dir); !st) return st.error();
  return profile;
}

}  // namespace skytrace::receiver
