// Reading antenna tables, shared by receiver profiles (their inline antenna) and antenna profiles.
#pragma once

#include <string>
#include <vector>

#include "skytrace/core/yaml_field.hpp"

namespace skytrace::receiver::detail {

// Gain rows: one list (no azimuth) or one list per azimuth, each as long as the elevations, every
// value within [low_db, high_db].
[[nodiscard]] std::vector<std::vector<double>> parse_gain_rows(const YamlField& node, size_t elevations,
                                                               size_t azimuths, double low_db, double high_db);
// At least two values, strictly increasing.
void check_increasing(const YamlField& node, const std::vector<double>& values);
// A name that is a file: contains '/' or ends in .yaml.
[[nodiscard]] bool looks_like_path(const std::string& text);

}  // namespace skytrace::receiver::detail
