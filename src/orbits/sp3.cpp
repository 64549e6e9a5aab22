// SP3-a/b/c/d reader (NGS/IGS "Extended Standard Product 3 Orbit Format", SP3-c 2010 and SP3-d
// 2016 documents by S. Hilla). Fixed columns as in those documents; 0-based offsets below.
#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <string>
#include <utility>

#include "skytrace/core/text_file.hpp"
#include "skytrace/orbits/precise.hpp"

namespace skytrace::orbits {
namespace {

constexpr double kKm_m = 1000.0;
constexpr double kMicrosecond_s = 1e-6;
constexpr double kDecimetre_m = 0.1;
constexpr double kClockRateUnit_s_per_s = 1e-10;  // 1e-4 microseconds per second
// SP3 "bad or absent" markers.
constexpr double kMissingMarker = 999999.0;   // 999999.999999 (any value at or beyond)
// Two epochs closer than this are the same epoch (files carry 8 decimals of the second).
constexpr double kSameEpoch_s = 1e-6;

bool is_missing_value(double value) { return std::abs(value) >= kMissingMarker; }

std::string trimmed(std::string_view text) { return std::string(field(text, 0, text.size())); }

// Time system names of the "%c" line. GLO time tags in IGS formats (SP3, RINEX) are UTC(SU),
// i.e. UTC without the 3 h of GLONASS system time: read them as UTC.
Result<TimeScale> sp3_time_scale(std::string_view name) {
  if (name.empty() || name == "ccc") return TimeScale::kGpst;  // SP3-a/b placeholders
  if (name == "GLO") return TimeScale::kUtc;
  return parse_time_scale(name);
}

// Satellite identifier of SP3 (A1,I2; a blank letter means GPS as in SP3-a). nullopt for an
// unused slot ("  0", " 00") and for LEOs ("L"), which skytrace does not model.
Result<std::optional<SatelliteId>> parse_sp3_satellite(std::string_view text) {
  if (text.size() < 3) return make_error(ErrorCode::kParse, "satellite identifier '" + std::string(text) + "' too short");
  const char letter = text[0] == ' ' ? 'G' : text[0];
  auto number = parse_integer(text.substr(1, 2));
  if (!number) return make_error(ErrorCode::kParse, "bad satellite identifier '" + std::string(text) + "'");
  if (*number == 0 && (text[0] == ' ' || text[0] == '0')) return std::optional<SatelliteId>{};
  if (letter == 'L') return std::optional<SatelliteId>{};
  auto system = system_from_letter(letter);
  if (!system) return make_error(ErrorCode::kParse, "bad satellite identifier '" + std::string(text) + "'");
  if (*number < 1 || *number > max_satellite_number(*system)) {
    return make_error(ErrorCode::kParse, "satellite number out of range in '" + std::string(text) + "'");
  }
  return std::optional<SatelliteId>{SatelliteId{*system, static_cast<std::uint8_t>(*number)}};
}

// "YYYY MM DD hh mm ss.ssssssss" starting at `start` (epoch lines and the first header line).
Result<CalendarTime> parse_calendar(const TextLines& lines, size_t index, size_t start) {
  const std::string_view line = lines[index];
  CalendarTime c;
  const std::pair<const char*, std::pair<size_t, size_t>> int_fields[] = {
      {"year", {start, 4}}, {"month", {start + 5, 2}}, {"day", {start + 8, 2}},
      {"hour", {start + 11, 2}}, {"minute", {start + 14, 2}}};
  int* targets[] = {&c.year, &c.month, &c.day, &c.hour, &c.minute};
  for (size_t i = 0; i < 5; ++i) {
    auto value = parse_integer(field(line, int_fields[i].second.first, int_fields[i].second.second));
    if (!value) return lines.error_at(index, std::string("epoch ") + int_fields[i].first + ": " + value.error().message);
    *targets[i] = static_cast<int>(*value);
  }
  auto second = parse_fortran_double(field(line, start + 17, 11));
  if (!second) return lines.error_at(index, "epoch second: " + second.error().message);
  c.second = *second;
  if (c.month < 1 || c.month > 12 || c.day < 1 || c.day > 31 || c.hour < 0 || c.hour > 24 || c.minute < 0 ||
      c.minute > 59 || c.second < 0.0 || c.second >= 61.0) {
    return lines.error_at(index, "epoch out of range: '" + trimmed(line.substr(start)) + "'");
  }
  return c;
}

struct Sp3Parser {
  explicit Sp3Parser(const TextLines& text) : lines(text) {}

  const TextLines& lines;
  Sp3Data data;
  // Index of each satellite in data.satellites during parsing.
  std::map<SatelliteId, size_t> index;

  size_t satellite_slot(const SatelliteId& satellite) {
    auto [it, inserted] = index.try_emplace(satellite, data.satellites.size());
    if (inserted) {
      data.satellites.push_back(satellite);
      data.records.emplace_back(data.epochs.size());
    }
    return it->second;
  }

  Status parse_first_line(size_t i) {
    const std::string_view line = lines[i];
    if (line.size() < 3 || line[0] != '#' || std::string_view("abcd").find(line[1]) == std::string_view::npos) {
      return lines.error_at(i, "not an SP3 file: the first line must start with #a, #b, #c or #d");
    }
    auto& h = data.header;
    h.version = line[1];
    if (line[2] != 'P' && line[2] != 'V') return lines.error_at(i, "position/velocity flag must be P or V");
    h.has_velocities = line[2] == 'V';
    auto start = parse_calendar(lines, i, 3);
    if (!start) return start.error();
    // The scale is known only from the "%c" line: keep the calendar and convert later.
    first_calendar = *start;
    if (auto count = parse_integer(field(line, 32, 7)); count) {
      h.declared_epoch_count = static_cast<int>(*count);
    } else {
      return lines.error_at(i, "number of epochs: " + count.error().message);
    }
    h.data_used = std::string(field(line, 40, 5));
    h.coordinate_system = std::string(field(line, 46, 5));
    h.orbit_type = std::string(field(line, 52, 3));
    h.agency = std::string(field(line, 56, 4));
    return Ok{};
  }

  Status parse_second_line(size_t i) {
    const std::string_view line = lines[i];
    auto interval = parse_fortran_double(field(line, 24, 14));
    if (!interval) return lines.error_at(i, "epoch interval: " + interval.error().message);
    if (!(*interval > 0.0)) return lines.error_at(i, "epoch interval must be positive");
    data.header.interval_s = *interval;
    return Ok{};
  }

  Status parse_satellite_line(size_t i, bool first) {
    const std::string_view line = lines[i];
    if (first) {
      auto count = parse_integer(field(line, 3, 3));
      if (!count) return lines.error_at(i, "number of satellites: " + count.error().message);
      declared_satellites = static_cast<int>(*count);
    }
    for (size_t column = 9; column + 3 <= line.size(); column += 3) {
      const std::string_view text = line.substr(column, 3);
      if (field(text, 0, 3).empty()) continue;
      auto satellite = parse_sp3_satellite(text);
      if (!satellite) return lines.error_at(i, "satellite list: " + satellite.error().message);
      ++listed_slots;
      if (*satellite) data.header.satellites.push_back(**satellite);
      if (listed_slots >= declared_satellites) break;
    }
    return Ok{};
  }

  Status parse_accuracy_line(size_t i) {
    const std::string_view line = lines[i];
    for (size_t column = 9; column + 3 <= line.size(); column += 3) {
      const std::string_view text = field(line, column, 3);
      if (text.empty()) continue;
      auto exponent = parse_integer(text);
      if (!exponent) return lines.error_at(i, "accuracy exponent: " + exponent.error().message);
      accuracy.push_back(static_cast<int>(*exponent));
    }
    return Ok{};
  }

  // Epoch line "*  YYYY MM DD hh mm ss.ssssssss".
  Status parse_epoch(size_t i) {
    auto calendar = parse_calendar(lines, i, 3);
    if (!calendar) return calendar.error();
    const GnssTime t = GnssTime::from_calendar(*calendar, data.header.time_scale);
    if (!data.epochs.empty() && !(t - data.epochs.back() > kSameEpoch_s)) {
      return lines.error_at(i, "epoch " + t.to_iso8601(TimeScale::kGpst, 3) +
                                   " GPST does not follow the previous epoch");
    }
    data.epochs.push_back(t);
    for (auto& series : data.records) series.emplace_back();
    return Ok{};
  }

  // P or V record: satellite, three coordinates, clock, then (P only) flags.
  Status parse_record(size_t i, bool velocity) {
    const std::string_view line = lines[i];
    const char* kind = velocity ? "V record" : "P record";
    if (data.epochs.empty()) return lines.error_at(i, std::string(kind) + " before the first epoch line");
    auto satellite = parse_sp3_satellite(line.substr(1, std::min<size_t>(3, line.size() - 1)));
    if (!satellite) return lines.error_at(i, std::string(kind) + " satellite: " + satellite.error().message);
    if (!*satellite) return Ok{};  // LEO: not modelled
    double values[4] = {};
    static constexpr const char* kNames[4] = {"x", "y", "z", "clock"};
    for (size_t k = 0; k < 4; ++k) {
      const std::string_view text = field(line, 4 + 14 * k, 14);
      if (text.empty() && k == 3) {  // SP3-a writers may leave the clock blank
        values[k] = kMissingMarker + 1.0;
        continue;
      }
      auto value = parse_fortran_double(text);
      if (!value) return lines.error_at(i, std::string(kind) + " " + satellite->value().to_string() + " " + kNames[k] + ": " + value.error().message);
      values[k] = *value;
    }
    Sp3Record& record = data.records[satellite_slot(**satellite)].back();
    const bool missing_position = (values[0] == 0.0 && values[1] == 0.0 && values[2] == 0.0) ||
                                  is_missing_value(values[0]) || is_missing_value(values[1]) ||
                                  is_missing_value(values[2]);
    const bool missing_clock = is_missing_value(values[3]);
    if (!velocity) {
      if (!p_seen.insert({**satellite, data.epochs.size()}).second) {
        return lines.error_at(i, "second P record of " + satellite->value().to_string() + " in one epoch");
      }
      record.has_position = !missing_position;
      if (record.has_position) record.position_m = Eigen::Vector3d(values[0], values[1], values[2]) * kKm_m;
      record.has_clock = !missing_clock;
      if (record.has_clock) record.clock_s = values[3] * kMicrosecond_s;
      record.clock_event = line.size() > 74 && line[74] == 'E';
      record.clock_predicted = line.size() > 75 && line[75] == 'P';
      record.maneuver = line.size() > 78 && line[78] == 'M';
      record.orbit_predicted = line.size() > 79 && line[79] == 'P';
    } else {
      record.has_velocity = !missing_position;
      if (record.has_velocity) record.velocity_mps = Eigen::Vector3d(values[0], values[1], values[2]) * kDecimetre_m;
      record.has_clock_rate = !missing_clock;
      if (record.has_clock_rate) record.clock_rate_s_per_s = values[3] * kClockRateUnit_s_per_s;
    }
    return Ok{};
  }

  Result<Sp3Data> run() {
    if (lines.size() == 0) return make_error(ErrorCode::kParse, lines.name() + ": empty file");
    if (auto s = parse_first_line(0); !s) return s.error();
    if (lines.size() < 2 || !lines[1].starts_with("##")) return lines.error_at(std::min<size_t>(1, lines.size() - 1), "second line must start with ##");
    if (auto s = parse_second_line(1); !s) return s.error();

    // Header: "+", "++", "%c", "%f", "%i", "/*" lines in any number up to the first epoch.
    size_t i = 2;
    bool first_plus = true;
    bool seen_percent_c = false;
    for (; i < lines.size(); ++i) {
      const std::string_view line = lines[i];
      if (line.starts_with("* ") || line == "*") break;
      if (line.starts_with("++")) {
        if (auto s = parse_accuracy_line(i); !s) return s.error();
      } else if (line.starts_with("+")) {
        if (auto s = parse_satellite_line(i, first_plus); !s) return s.error();
        first_plus = false;
      } else if (line.starts_with("%c")) {
        if (!seen_percent_c) {  // only the first %c line carries file type and time system
          seen_percent_c = true;
          data.header.file_type = std::string(field(line, 3, 2));
          data.header.time_system = std::string(field(line, 9, 3));
          auto scale = sp3_time_scale(data.header.time_system);
          if (!scale) return lines.error_at(i, "time system: " + scale.error().message);
          data.header.time_scale = *scale;
        }
      } else if (line.starts_with("%f") || line.starts_with("%i") || line.starts_with("%/")) {
        // Floating-point and integer bases: only needed for the standard deviations.
      } else if (line.starts_with("/*")) {
        data.header.comments.push_back(trimmed(line.substr(2)));
      } else if (field(line, 0, line.size()).empty()) {
        // Tolerate blank lines.
      } else if (line.starts_with("EOF")) {
        break;
      } else {
        return lines.error_at(i, "unexpected header line '" + trimmed(line.substr(0, 20)) + "'");
      }
    }
    if (first_plus) return lines.error_at(std::min(i, lines.size() - 1), "header has no satellite list (+ lines)");
    if (static_cast<int>(data.header.satellites.size()) > declared_satellites) {
      return lines.error_at(2, "more satellites listed than the declared " + std::to_string(declared_satellites));
    }
    if (!accuracy.empty()) {
      // Exponents are listed in the order of the satellite slots; LEO slots were dropped above,
      // so only assign them when the counts match.
      if (accuracy.size() >= data.header.satellites.size()) {
        data.header.accuracy_exponents.assign(accuracy.begin(),
                                              accuracy.begin() + static_cast<long>(data.header.satellites.size()));
      }
    }
    data.header.first_epoch = GnssTime::from_calendar(first_calendar, data.header.time_scale);
    data.interval_s = data.header.interval_s;
    for (const auto& satellite : data.header.satellites) satellite_slot(satellite);

    bool seen_eof = false;
    for (; i < lines.size(); ++i) {
      const std::string_view line = lines[i];
      if (line.starts_with("EOF")) {
        seen_eof = true;
        break;
      }
      if (line.starts_with("*")) {
        if (auto s = parse_epoch(i); !s) return s.error();
      } else if (line.starts_with("P")) {
        if (auto s = parse_record(i, false); !s) return s.error();
      } else if (line.starts_with("EP") || line.starts_with("EV")) {
        // Correlation records: not used.
      } else if (line.starts_with("V")) {
        if (auto s = parse_record(i, true); !s) return s.error();
      } else if (field(line, 0, line.size()).empty()) {
        // Tolerate blank lines.
      } else if (line.starts_with("/*")) {
        // Some writers put comments between epochs.
      } else {
        return lines.error_at(i, "unexpected record '" + trimmed(line.substr(0, std::min<size_t>(20, line.size()))) + "'");
      }
    }
    (void)seen_eof;  // a missing EOF line (truncated download) is tolerated: the epochs read are valid
    if (data.epochs.empty()) return make_error(ErrorCode::kParse, lines.name() + ": no epochs");
    data.sources.push_back(lines.name());
    sort_satellites();
    return std::move(data);
  }

  void sort_satellites() {
    std::vector<size_t> order(data.satellites.size());
    for (size_t k = 0; k < order.size(); ++k) order[k] = k;
    std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return data.satellites[a] < data.satellites[b]; });
    std::vector<SatelliteId> satellites;
    std::vector<std::vector<Sp3Record>> records;
    for (size_t k : order) {
      satellites.push_back(data.satellites[k]);
      records.push_back(std::move(data.records[k]));
    }
    data.satellites = std::move(satellites);
    data.records = std::move(records);
  }

  CalendarTime first_calendar;
  int declared_satellites = 0;
  int listed_slots = 0;
  std::vector<int> accuracy;
  // (satellite, epoch count) of every P record read, to reject duplicates.
  std::set<std::pair<SatelliteId, size_t>> p_seen;
};

}  // namespace

const std::vector<Sp3Record>* Sp3Data::series(const SatelliteId& satellite) const {
  const auto it = std::lower_bound(satellites.begin(), satellites.end(), satellite);
  if (it == satellites.end() || *it != satellite) return nullptr;
  return &records[static_cast<size_t>(it - satellites.begin())];
}

size_t Sp3Data::satellite_count(GnssSystem system) const {
  size_t count = 0;
  for (size_t k = 0; k < satellites.size(); ++k) {
    if (satellites[k].system != system) continue;
    if (std::any_of(records[k].begin(), records[k].end(), [](const Sp3Record& r) { return r.has_position; })) ++count;
  }
  return count;
}

void Sp3Data::merge(const Sp3Data& other) {
  if (other.epochs.empty()) return;
  if (epochs.empty()) {
    auto sources_before = std::move(sources);
    *this = other;
    sources_before.insert(sources_before.end(), other.sources.begin(), other.sources.end());
    sources = std::move(sources_before);
    return;
  }
  // Union of the epoch grids, remembering where each old epoch goes.
  std::vector<GnssTime> merged;
  std::vector<size_t> from_this(epochs.size()), from_other(other.epochs.size());
  size_t a = 0, b = 0;
  while (a < epochs.size() || b < other.epochs.size()) {
    const bool take_a = b == other.epochs.size() || (a < epochs.size() && epochs[a] - other.epochs[b] < kSameEpoch_s);
    const bool take_b = a == epochs.size() || (b < other.epochs.size() && other.epochs[b] - epochs[a] < kSameEpoch_s);
    if (take_a) from_this[a] = merged.size();
    if (take_b) from_other[b] = merged.size();
    merged.push_back(take_a ? epochs[a] : other.epochs[b]);
    if (take_a) ++a;
    if (take_b) ++b;
  }
  std::vector<SatelliteId> all = satellites;
  all.insert(all.end(), other.satellites.begin(), other.satellites.end());
  std::sort(all.begin(), all.end());
  all.erase(std::unique(all.begin(), all.end()), all.end());
  std::vector<std::vector<Sp3Record>> out(all.size(), std::vector<Sp3Record>(merged.size()));
  for (size_t s = 0; s < all.size(); ++s) {
    if (const auto* mine = series(all[s])) {
      for (size_t e = 0; e < epochs.size(); ++e) out[s][from_this[e]] = (*mine)[e];
    }
    if (const auto* theirs = other.series(all[s])) {
      for (size_t e = 0; e < other.epochs.size(); ++e) {
        Sp3Record& target = out[s][from_other[e]];
        if (!target.has_position) target = (*theirs)[e];
      }
    }
  }
  epochs = std::move(merged);
  satellites = std::move(all);
  records = std::move(out);
  interval_s = std::max(interval_s, other.interval_s);
  sources.insert(sources.end(), other.sources.begin(), other.sources.end());
}

Result<Sp3Data> parse_sp3(const std::string& name, std::string content) {
  const TextLines lines(name, std::move(content));
  Sp3Parser parser(lines);
  return parser.run();
}

Result<Sp3Data> read_sp3(const std::filesystem::path& path) {
  auto lines = TextLines::read(path);
  if (!lines) return lines.error();
  Sp3Parser parser(*lines);
  return parser.run();
}

Result<Sp3Data> read_sp3(const std::vector<std::filesystem::path>& paths) {
  if (paths.empty()) return make_error(ErrorCode::kInvalidArgument, "no SP3 file given");
  Sp3Data all;
  for (const auto& path : paths) {
    auto data = read_sp3(path);
    if (!data) return data.error();
    all.merge(*data);
  }
  return all;
}

}  // namespace skytrace::orbits
