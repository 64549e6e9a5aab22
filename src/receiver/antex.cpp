#include "skytrace/receiver/antex.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>
#include <utility>

#include "skytrace/core/input_limits.hpp"
#include "skytrace/core/text_file.hpp"

namespace skytrace::receiver {
namespace {

constexpr double kMmToM = 1e-3;
// Sanity bounds: a real receiver antenna's PCO is below 0.3 m and its PCV below 0.05 m; a value
// beyond these is a broken file, not an antenna.
constexpr double kMaxOffset_mm = 10'000.0;
constexpr double kMaxVariation_mm = 1'000.0;
constexpr size_t kMaxFrequencies = 64;  // ANTEX 1.4 defines about 30 frequency codes
constexpr double kGridTolerance = 1e-6;

std::string_view trim(std::string_view text) {
  const auto begin = text.find_first_not_of(" \t");
  if (begin == std::string_view::npos) return {};
  const auto end = text.find_last_not_of(" \t");
  return text.substr(begin, end - begin + 1);
}

// Whether the record label (columns 61 on) of `line` is `label`. Data rows of a frequency block
// may run past column 60 with numbers, which never spell a label.
bool has_label(std::string_view line, std::string_view label) {
  return line.size() >= 60 + label.size() && trim(line.substr(60)) == label;
}

bool is_satellite_code(std::string_view serial) {
  static constexpr std::string_view kSystems = "GRECJSI";
  return serial.size() == 3 && kSystems.find(serial[0]) != std::string_view::npos &&
         std::isdigit(static_cast<unsigned char>(serial[1])) != 0 &&
         std::isdigit(static_cast<unsigned char>(serial[2])) != 0;
}

size_t edit_distance(std::string_view a, std::string_view b) {
  std::vector<size_t> previous(b.size() + 1), current(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) previous[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    current[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      const size_t substitute = previous[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1);
      current[j] = std::min({previous[j] + 1, current[j - 1] + 1, substitute});
    }
    std::swap(previous, current);
  }
  return previous[b.size()];
}

std::string number_text(double value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

class Parser {
 public:
  explicit Parser(const TextLines& lines) : lines_(lines) {}

  Result<AntexFile> run() {
    AntexFile out;
    out.source = lines_.name();
    if (lines_.size() == 0 || !has_label(lines_[0], "ANTEX VERSION / SYST")) {
      return lines_.error_at(0, "expected the ANTEX VERSION / SYST record first (is this an ANTEX file?)");
    }
    auto version = parse_fortran_double(field(lines_[0], 0, 8));
    if (!version || !std::isfinite(*version) || *version < 1.0 || *version >= 2.0) {
      return lines_.error_at(0, "expected an ANTEX version 1.x in columns 1-8, got '" +
                                    std::string(field(lines_[0], 0, 8)) + "'");
    }
    size_t i = 1;
    bool header_ended = false;
    for (; i < lines_.size(); ++i) {
      const std::string_view line = lines_[i];
      if (has_label(line, "END OF HEADER")) {
        header_ended = true;
        ++i;
        break;
      }
      if (has_label(line, "PCV TYPE / REFANT")) {
        const std::string_view type = field(line, 0, 1);
        if (type != "A" && type != "R") {
          return lines_.error_at(i, "expected PCV type A (absolute) or R (relative) in column 1, got '" +
                                        std::string(type) + "'");
        }
        out.pcv_type = type[0];
      }
    }
    if (!header_ended) return lines_.error_at(lines_.size() - 1, "expected END OF HEADER before the end of the file");
    for (; i < lines_.size(); ++i) {
      const std::string_view line = lines_[i];
      if (trim(line).empty()) continue;
      if (!has_label(line, "START OF ANTENNA")) {
        return lines_.error_at(i, "expected START OF ANTENNA, got '" + std::string(trim(line.substr(0, 80))) + "'");
      }
      auto antenna = parse_antenna(i);
      if (!antenna) return antenna.error();
      if (antenna->has_value()) {
        out.receiver_antennas.push_back(std::move(**antenna));
      } else {
        ++out.satellite_antennas_skipped;
      }
    }
    return out;
  }

 private:
  Result<double> number(size_t index, size_t start, size_t width, const char* what) const {
    const std::string_view text = field(lines_[index], start, width);
    auto value = parse_fortran_double(text);
    if (!value || !std::isfinite(*value)) {
      return lines_.error_at(index, std::string("expected ") + what + " in columns " + std::to_string(start + 1) + "-" +
                                        std::to_string(start + width) + ", got '" + std::string(text) + "'");
    }
    return *value;
  }

  Result<GnssTime> date(size_t index) const {
    CalendarTime c;
    int* parts[5] = {&c.year, &c.month, &c.day, &c.hour, &c.minute};
    for (size_t k = 0; k < 5; ++k) {
      auto value = parse_integer(field(lines_[index], k * 6, 6));
      if (!value) return lines_.error_at(index, "expected a date as 5I6,F13.7 (year month day hour minute second)");
      *parts[k] = static_cast<int>(*value);
    }
    auto second = number(index, 30, 13, "seconds (F13.7)");
    if (!second) return second.error();
    c.second = *second;
    if (c.year < 1980 || c.year > 2200 || c.month < 1 || c.month > 12 || c.day < 1 || c.day > 31 || c.hour < 0 ||
        c.hour > 24 || c.minute < 0 || c.minute > 59 || c.second < 0.0 || c.second > 61.0) {
      return lines_.error_at(index, "expected a calendar date between 1980 and 2200");
    }
    return GnssTime::from_calendar(c, TimeScale::kGpst);
  }

  // One antenna from its START OF ANTENNA line at `i` up to END OF ANTENNA (i left there).
  // nullopt: a satellite antenna, skipped.
  Result<std::optional<AntexAntenna>> parse_antenna(size_t& i) {
    const size_t start = i;
    AntexAntenna a;
    bool satellite = false, have_type = false, have_zenith = false, have_dazi = false;
    for (++i; i < lines_.size(); ++i) {
      const std::string_view line = lines_[i];
      if (has_label(line, "END OF ANTENNA")) {
        if (satellite) return std::optional<AntexAntenna>{};
        if (!have_type) return lines_.error_at(i, "expected TYPE / SERIAL NO in the antenna block");
        if (!have_dazi || !have_zenith) {
          return lines_.error_at(i, "expected DAZI and ZEN1 / ZEN2 / DZEN in the antenna block of " + a.name());
        }
        if (a.frequencies.empty()) return lines_.error_at(i, "expected at least one START OF FREQUENCY block in " + a.name());
        return std::optional<AntexAntenna>(std::move(a));
      }
      if (has_label(line, "START OF ANTENNA")) {
        return lines_.error_at(i, "expected END OF ANTENNA for the antenna started at line " + std::to_string(start + 1));
      }
      if (satellite) continue;  // nothing of a satellite antenna is kept
      if (has_label(line, "TYPE / SERIAL NO")) {
        const std::string_view type_radome = line.substr(0, 20);
        a.type = std::string(trim(type_radome.substr(0, 16)));
        a.radome = std::string(trim(type_radome.substr(16, 4)));
        a.serial = std::string(field(line, 20, 20));
        satellite = is_satellite_code(a.serial);
        if (!satellite && a.type.empty()) return lines_.error_at(i, "expected an antenna type in columns 1-16");
        // IGS antenna codes have no blank inside; one that had could not be named in a scenario or a
        // RINEX header (split_igs_antenna_name), so the calibration would silently never apply.
        if (!satellite && a.type.find_first_of(" \t") != std::string::npos) {
          return lines_.error_at(i, "expected an IGS antenna type without blanks in columns 1-16, got '" + a.type + "'");
        }
        if (!satellite && a.radome.empty()) a.radome = "NONE";
        have_type = true;
      } else if (has_label(line, "DAZI")) {
        auto dazi = number(i, 2, 6, "DAZI (F6.1, degrees)");
        if (!dazi) return dazi.error();
        const double rows = *dazi > 0.0 ? 360.0 / *dazi : 0.0;
        if (*dazi < 0.0 || *dazi > 360.0 || (*dazi > 0.0 && std::abs(rows - std::round(rows)) > kGridTolerance)) {
          return lines_.error_at(i, "expected DAZI 0 or a divisor of 360 degrees, got " + number_text(*dazi));
        }
        a.dazi_deg = *dazi;
        have_dazi = true;
      } else if (has_label(line, "ZEN1 / ZEN2 / DZEN")) {
        auto z1 = number(i, 2, 6, "ZEN1 (F6.1, degrees)");
        auto z2 = number(i, 8, 6, "ZEN2 (F6.1, degrees)");
        auto dz = number(i, 14, 6, "DZEN (F6.1, degrees)");
        if (!z1) return z1.error();
        if (!z2) return z2.error();
        if (!dz) return dz.error();
        const double steps = *dz > 0.0 ? (*z2 - *z1) / *dz : -1.0;
        if (*z1 < 0.0 || *z2 > 180.0 || *z2 < *z1 || *dz <= 0.0 || std::abs(steps - std::round(steps)) > kGridTolerance) {
          return lines_.error_at(i, "expected 0 <= ZEN1 <= ZEN2 <= 180 degrees with ZEN2 - ZEN1 a multiple of DZEN > 0, "
                                    "got " + number_text(*z1) + " " + number_text(*z2) + " " + number_text(*dz));
        }
        a.zen1_deg = *z1;
        a.zen2_deg = *z2;
        a.dzen_deg = *dz;
        have_zenith = true;
      } else if (has_label(line, "VALID FROM") || has_label(line, "VALID UNTIL")) {
        auto t = date(i);
        if (!t) return t.error();
        (has_label(line, "VALID FROM") ? a.valid_from : a.valid_until) = *t;
      } else if (has_label(line, "START OF FREQUENCY")) {
        if (!have_type) return lines_.error_at(i, "expected TYPE / SERIAL NO before the first frequency");
        if (!have_dazi || !have_zenith) {
          return lines_.error_at(i, "expected DAZI and ZEN1 / ZEN2 / DZEN before the first frequency");
        }
        if (a.frequencies.size() >= kMaxFrequencies) {
          return lines_.error_at(i, "expected at most " + std::to_string(kMaxFrequencies) + " frequencies per antenna");
        }
        auto f = parse_frequency(i, a);
        if (!f) return f.error();
        a.frequencies.push_back(std::move(*f));
      } else if (has_label(line, "START OF FRQ RMS")) {
        // Calibration uncertainties: not part of the model.
        for (++i; i < lines_.size() && !has_label(lines_[i], "END OF FRQ RMS"); ++i) {
          if (has_label(lines_[i], "END OF ANTENNA")) return lines_.error_at(i, "expected END OF FRQ RMS");
        }
        if (i == lines_.size()) return lines_.error_at(i - 1, "expected END OF FRQ RMS before the end of the file");
      }
      // METH / BY / # / DATE, # OF FREQUENCIES, SINEX CODE, COMMENT: not needed.
    }
    return lines_.error_at(lines_.size() - 1,
                           "expected END OF ANTENNA for the antenna started at line " + std::to_string(start + 1));
  }

  // Values of a NOAZI or azimuth row from column `from`: exactly `count`, finite and plausible.
  Result<std::vector<double>> row_values(size_t index, size_t from, size_t count) const {
    const std::string_view line = lines_[index];
    std::vector<double> out;
    out.reserve(count);
    const auto items = split_words(line.size() > from ? line.substr(from) : std::string_view{});
    if (items.size() != count) {
      return lines_.error_at(index, "expected " + std::to_string(count) + " PCV values (one per zenith node), got " +
                                        std::to_string(items.size()));
    }
    for (const std::string_view item : items) {
      auto v = parse_fortran_double(item);
      if (!v || !std::isfinite(*v) || std::abs(*v) > kMaxVariation_mm) {
        return lines_.error_at(index, "expected a PCV value in mm (|value| <= " + number_text(kMaxVariation_mm) +
                                          "), got '" + std::string(item) + "'");
      }
      out.push_back(*v * kMmToM);
    }
    return out;
  }

  Result<AntexFrequency> parse_frequency(size_t& i, const AntexAntenna& a) {
    AntexFrequency f;
    f.code = std::string(field(lines_[i], 3, 3));
    if (f.code.size() != 3 || std::isalpha(static_cast<unsigned char>(f.code[0])) == 0 ||
        std::isdigit(static_cast<unsigned char>(f.code[1])) == 0 || std::isdigit(static_cast<unsigned char>(f.code[2])) == 0) {
      return lines_.error_at(i, "expected a frequency code such as G01 in columns 4-6, got '" + f.code + "'");
    }
    if (a.frequency(f.code) != nullptr) return lines_.error_at(i, "frequency " + f.code + " given twice for " + a.name());
    const size_t nodes = a.zenith_nodes();
    const size_t rows = a.azimuth_rows();
    if (nodes * std::max<size_t>(rows, 1) > input_limits().max_grid_points) {
      return lines_.error_at(i, "the PCV grid has " + std::to_string(nodes * rows) + " points " +
                                    limit_hint(input_limits().max_grid_points, "SKYTRACE_MAX_GRID_POINTS"));
    }
    bool have_offset = false, have_noazi = false;
    size_t next_row = 0;
    const size_t start = i;
    for (++i; i < lines_.size(); ++i) {
      const std::string_view line = lines_[i];
      if (has_label(line, "END OF FREQUENCY")) {
        if (field(line, 3, 3) != f.code) {
          return lines_.error_at(i, "expected END OF FREQUENCY of " + f.code + ", got '" + std::string(field(line, 3, 3)) + "'");
        }
        if (!have_offset) return lines_.error_at(i, "expected NORTH / EAST / UP in frequency " + f.code);
        if (!have_noazi) return lines_.error_at(i, "expected the NOAZI row in frequency " + f.code);
        if (next_row != rows) {
          return lines_.error_at(i, "expected " + std::to_string(rows) + " azimuth rows (0 to 360 by DAZI " +
                                        number_text(a.dazi_deg) + ") in frequency " + f.code + ", got " +
                                        std::to_string(next_row));
        }
        return f;
      }
      for (const char* other : {"END OF ANTENNA", "START OF ANTENNA", "START OF FREQUENCY", "START OF FRQ RMS"}) {
        if (has_label(line, other)) {
          return lines_.error_at(i, "expected END OF FREQUENCY of " + f.code + " (started at line " +
                                        std::to_string(start + 1) + "), got " + other);
        }
      }
      if (has_label(line, "COMMENT")) continue;
      if (has_label(line, "NORTH / EAST / UP")) {
        for (int k = 0; k < 3; ++k) {
          auto v = number(i, static_cast<size_t>(k) * 10, 10, "a phase centre offset in mm (3F10.2)");
          if (!v) return v.error();
          if (std::abs(*v) > kMaxOffset_mm) {
            return lines_.error_at(i, "expected a phase centre offset within " + number_text(kMaxOffset_mm) +
                                          " mm, got " + number_text(*v));
          }
          f.offset_neu_m[k] = *v * kMmToM;
        }
        have_offset = true;
      } else if (field(line, 0, 8) == "NOAZI") {
        auto values = row_values(i, 8, nodes);
        if (!values) return values.error();
        f.noazi_m = std::move(*values);
        have_noazi = true;
      } else if (!trim(line).empty()) {
        // An azimuth row: F8.1 azimuth, then one value per zenith node.
        if (rows == 0) return lines_.error_at(i, "expected no azimuth rows (DAZI is 0), got '" + std::string(trim(line.substr(0, 40))) + "'");
        auto azimuth = number(i, 0, 8, "an azimuth (F8.1, degrees) or NOAZI");
        if (!azimuth) return azimuth.error();
        const double expected_deg = static_cast<double>(next_row) * a.dazi_deg;
        if (next_row >= rows || std::abs(*azimuth - expected_deg) > 1e-3) {
          return lines_.error_at(i, "expected the azimuth row " + (next_row >= rows ? std::string("END OF FREQUENCY")
                                                                                    : number_text(expected_deg)) +
                                        ", got azimuth " + number_text(*azimuth));
        }
        auto values = row_values(i, 8, nodes);
        if (!values) return values.error();
        if (f.grid_m.empty()) f.grid_m.reserve(rows * nodes);
        f.grid_m.insert(f.grid_m.end(), values->begin(), values->end());
        ++next_row;
      }
    }
    return lines_.error_at(lines_.size() - 1, "expected END OF FREQUENCY of " + f.code + " (started at line " +
                                                  std::to_string(start + 1) + ") before the end of the file");
  }

  const TextLines& lines_;
};

}  // namespace

std::string AntexAntenna::name() const {
  std::string out = type;
  out.resize(16, ' ');
  return out + radome;
}

const AntexFrequency* AntexAntenna::frequency(std::string_view code) const {
  for (const auto& f : frequencies) {
    if (f.code == code) return &f;
  }
  return nullptr;
}

size_t AntexAntenna::zenith_nodes() const {
  return static_cast<size_t>(std::lround((zen2_deg - zen1_deg) / dzen_deg)) + 1;
}

size_t AntexAntenna::azimuth_rows() const {
  return dazi_deg > 0.0 ? static_cast<size_t>(std::lround(360.0 / dazi_deg)) + 1 : 0;
}

double AntexAntenna::variation_m(const AntexFrequency& f, double zenith_deg, double azimuth_deg) const {
  const size_t nodes = zenith_nodes();
  if (f.noazi_m.size() != nodes) return 0.0;
  // Position between zenith nodes, clamped to the grid.
  const double z = std::clamp((zenith_deg - zen1_deg) / dzen_deg, 0.0, static_cast<double>(nodes - 1));
  const size_t k0 = std::min(static_cast<size_t>(z), nodes > 1 ? nodes - 2 : 0);
  const double wz = nodes > 1 ? z - static_cast<double>(k0) : 0.0;
  const size_t k1 = nodes > 1 ? k0 + 1 : 0;
  auto along_zenith = [&](const double* row) { return row[k0] + wz * (row[k1] - row[k0]); };
  const size_t rows = azimuth_rows();
  if (rows < 2 || f.grid_m.size() != rows * nodes) return along_zenith(f.noazi_m.data());
  double azimuth = std::fmod(azimuth_deg, 360.0);
  if (azimuth < 0.0) azimuth += 360.0;
  const double a = std::min(azimuth / dazi_deg, static_cast<double>(rows - 1));
  const size_t j0 = std::min(static_cast<size_t>(a), rows - 2);
  const double wa = a - static_cast<double>(j0);
  const double v0 = along_zenith(f.grid_m.data() + j0 * nodes);
  const double v1 = along_zenith(f.grid_m.data() + (j0 + 1) * nodes);
  return v0 + wa * (v1 - v0);
}

std::optional<IgsAntennaName> split_igs_antenna_name(std::string_view text) {
  IgsAntennaName out;
  const std::string_view trimmed = trim(text);
  if (trimmed.empty()) return std::nullopt;
  if (text.size() > 16 && text.size() <= 20 && !trim(text.substr(0, 16)).empty()) {
    // The fixed columns of RINEX ANT # / TYPE: type in 1-16, radome in 17-20.
    out.type = std::string(trim(text.substr(0, 16)));
    out.radome = std::string(trim(text.substr(16)));
    if (out.type.find(' ') != std::string::npos) {
      // "TYPE RADOME" written with one blank, longer than 16: split at the last blank instead.
      out = {};
    }
  }
  if (out.type.empty()) {
    const auto items = split_words(trimmed);
    if (items.size() > 2) return std::nullopt;
    out.type = std::string(items[0]);
    out.radome = items.size() == 2 ? std::string(items[1]) : std::string();
  }
  if (out.radome.empty()) out.radome = "NONE";
  if (out.type.size() > 16 || out.radome.size() > 4) return std::nullopt;
  return out;
}

Result<const AntexAntenna*> AntexFile::find(std::string_view igs_name, const std::optional<GnssTime>& at) const {
  const auto name = split_igs_antenna_name(igs_name);
  if (!name) {
    return make_error(ErrorCode::kInvalidArgument,
                      "'" + std::string(igs_name) + "' is not an IGS antenna name (type of up to 16 characters, then "
                      "the radome of up to 4, e.g. 'TRM59800.00     NONE')");
  }
  auto matching = [&](std::string_view radome) -> const AntexAntenna* {
    const AntexAntenna* found = nullptr;
    for (const auto& a : receiver_antennas) {
      if (!a.serial.empty() || a.type != name->type || a.radome != radome) continue;
      if (at && ((a.valid_from && *at < *a.valid_from) || (a.valid_until && !(*at < *a.valid_until)))) continue;
      found = &a;  // the last valid block: later calibrations follow earlier ones
    }
    return found;
  };
  if (const AntexAntenna* a = matching(name->radome)) return a;
  if (name->radome != "NONE") {
    if (const AntexAntenna* a = matching("NONE")) return a;
  }
  // Not there: the closest type-mean names of the file.
  std::string wanted = name->type;
  wanted.resize(16, ' ');
  wanted += name->radome;
  std::vector<std::pair<size_t, std::string>> ranked;
  for (const auto& a : receiver_antennas) {
    if (!a.serial.empty()) continue;
    const std::string candidate = a.name();
    const size_t distance = edit_distance(wanted, candidate);
    if (std::none_of(ranked.begin(), ranked.end(), [&](const auto& r) { return r.second == candidate; })) {
      ranked.emplace_back(distance, candidate);
    }
  }
  std::sort(ranked.begin(), ranked.end());
  std::string closest;
  for (size_t k = 0; k < ranked.size() && k < 3; ++k) closest += (k == 0 ? "" : ", ") + ("'" + ranked[k].second + "'");
  std::string message = source + ": no receiver antenna '" + wanted + "'";
  if (name->radome != "NONE") message += " (nor '" + wanted.substr(0, 16) + "NONE')";
  message += at ? " valid at the scenario's start" : "";
  message += closest.empty() ? "; the file holds no type-mean receiver antenna" : "; closest: " + closest;
  return make_error(ErrorCode::kNotFound, message);
}

Result<AntexFile> parse_antex(const std::string& name, std::string content) {
  const TextLines lines(name, std::move(content));
  return Parser(lines).run();
}

Result<AntexFile> read_antex(const std::filesystem::path& path) {
  auto lines = TextLines::read(path);
  if (!lines) return lines.error();
  return Parser(*lines).run();
}

std::string antex_frequency_code(const Signal& signal) { return {system_letter(signal.system), '0', signal.band}; }

Result<AntennaPhaseCentre> AntennaPhaseCentre::create(const AntexAntenna& antenna, std::span<const Signal> signals,
                                                      const std::string& source) {
  AntennaPhaseCentre out;
  out.antenna_ = antenna;
  auto index_of = [&](std::string_view code) -> std::optional<size_t> {
    for (size_t k = 0; k < antenna.frequencies.size(); ++k) {
      if (antenna.frequencies[k].code == code) return k;
    }
    return std::nullopt;
  };
  for (const Signal& signal : signals) {
    const std::string code = antex_frequency_code(signal);
    std::optional<size_t> k = index_of(code);
    if (!k && signal.system == GnssSystem::kQzss) k = index_of(std::string{'G', '0', signal.band});
    if (!k) {
      // A calibration without this system: the GPS frequency closest in carrier.
      const double carrier_hz = band_carrier_hz(signal.system, signal.band).value_or(0.0);
      double best_hz = std::numeric_limits<double>::infinity();
      for (const char band : {'1', '2', '5'}) {
        const auto gps_k = index_of(std::string{'G', '0', band});
        const double gps_hz = band_carrier_hz(GnssSystem::kGps, band).value_or(0.0);
        if (gps_k && std::abs(gps_hz - carrier_hz) < best_hz) {
          best_hz = std::abs(gps_hz - carrier_hz);
          k = gps_k;
        }
      }
    }
    if (!k) {
      std::string held;
      for (const auto& f : antenna.frequencies) held += (held.empty() ? "" : " ") + f.code;
      return make_error(ErrorCode::kNotFound, source + ": antenna '" + antenna.name() + "' has no frequency " + code +
                                                  " for signal " + signal.to_string() +
                                                  " and no GPS frequency to fall back on (it has " + held + ")");
    }
    out.frequency_index_[signal] = *k;
  }
  return out;
}

const AntexFrequency* AntennaPhaseCentre::frequency_of(const Signal& signal) const {
  const auto it = frequency_index_.find(signal);
  return it == frequency_index_.end() ? nullptr : &antenna_.frequencies[it->second];
}

double AntennaPhaseCentre::range_correction_m(const Signal& signal, const AzimuthElevation& direction) const {
  const AntexFrequency* f = frequency_of(signal);
  if (f == nullptr) return 0.0;
  constexpr double kDegToRad = std::numbers::pi / 180.0;
  const double el = direction.elevation_deg * kDegToRad;
  const double az = direction.azimuth_deg * kDegToRad;
  // Line of sight in north-east-up, as the offset is given.
  const Eigen::Vector3d e_neu(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
  return -e_neu.dot(f->offset_neu_m) + antenna_.variation_m(*f, 90.0 - direction.elevation_deg, direction.azimuth_deg);
}

}  // namespace skytrace::receiver
