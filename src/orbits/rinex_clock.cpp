// RINEX clock reader ("RINEX Extensions to Handle Clock Information", J. Ray, W. Gurtner,
// versions 2.00, 3.00, 3.02 and 3.04). Data records: A2,1X,A4,1X,I4,4I3,F10.6,I3,3X,D19.12,1X,
// D19.12 then continuation lines of up to four more values. Version 3.04 widens the name to A9
// (everything after it shifts by 5 columns) and the header labels move from column 61 to 66.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <string>
#include <utility>

#include "skytrace/core/text_file.hpp"
#include "skytrace/orbits/precise.hpp"

namespace skytrace::orbits {
namespace {

constexpr double kSameTime_s = 1e-6;
constexpr size_t kValuesOnFirstLine = 2;
constexpr size_t kValuesPerContinuationLine = 4;

std::string trimmed(std::string_view text) { return std::string(field(text, 0, text.size())); }

// Whitespace-separated tokens of a line.
std::vector<std::string_view> tokens(std::string_view text) {
  std::vector<std::string_view> out;
  size_t k = 0;
  while (k < text.size()) {
    while (k < text.size() && std::isspace(static_cast<unsigned char>(text[k]))) ++k;
    const size_t start = k;
    while (k < text.size() && !std::isspace(static_cast<unsigned char>(text[k]))) ++k;
    if (k > start) out.push_back(text.substr(start, k - start));
  }
  return out;
}

bool is_year_field(std::string_view line, size_t start) {
  if (line.size() < start + 4) return false;
  for (size_t k = start; k < start + 4; ++k) {
    if (!std::isdigit(static_cast<unsigned char>(line[k]))) return false;
  }
  return start == 0 || line[start - 1] == ' ';
}

Result<TimeScale> clock_time_scale(std::string_view name) {
  if (name.empty()) return TimeScale::kGpst;
  if (name == "GLO") return TimeScale::kUtc;  // RINEX GLO time tags are UTC(SU), without +3 h
  return parse_time_scale(name);
}

class ClockParser {
 public:
  explicit ClockParser(const TextLines& lines) : lines_(lines) {}

  Result<RinexClockData> run() {
    if (lines_.size() == 0) return make_error(ErrorCode::kParse, lines_.name() + ": empty file");
    auto end = parse_header();
    if (!end) return end.error();
    for (size_t i = *end + 1; i < lines_.size(); ++i) {
      const std::string_view line = lines_[i];
      if (field(line, 0, line.size()).empty()) continue;
      auto consumed = parse_record(i);
      if (!consumed) return consumed.error();
      i += *consumed;  // continuation lines
    }
    // Files are written epoch by epoch; sort per satellite and keep the first of equal times.
    for (auto& [satellite, samples] : data_.satellite_clocks) {
      std::stable_sort(samples.begin(), samples.end(),
                       [](const ClockSample& a, const ClockSample& b) { return a.time < b.time; });
      samples.erase(std::unique(samples.begin(), samples.end(),
                                [](const ClockSample& a, const ClockSample& b) {
                                  return std::abs(b.time - a.time) < kSameTime_s;
                                }),
                    samples.end());
    }
    data_.sources.push_back(lines_.name());
    return std::move(data_);
  }

 private:
  // The header label (columns 61-80, or 66-85 from version 3.04).
  std::string_view label(std::string_view line) const {
    const size_t column = wide_ ? 65 : 60;
    return field(line, column, 20);
  }

  Result<size_t> parse_header() {
    const std::string_view first = lines_[0];
    if (first.find("RINEX VERSION / TYPE") == std::string_view::npos) {
      return lines_.error_at(0, "not a RINEX file: the first line must be RINEX VERSION / TYPE");
    }
    const auto words = tokens(first.substr(0, std::min<size_t>(first.size(), 60)));
    if (words.size() < 2) return lines_.error_at(0, "RINEX VERSION / TYPE: missing version or file type");
    auto version = parse_fortran_double(words[0]);
    if (!version) return lines_.error_at(0, "format version: " + version.error().message);
    data_.version = *version;
    if (words[1].front() != 'C') {
      return lines_.error_at(0, "not a RINEX clock file (file type '" + std::string(words[1]) + "', expected C)");
    }
    wide_ = data_.version >= 3.035;
    name_offset_ = wide_ ? 5 : 0;

    for (size_t i = 1; i < lines_.size(); ++i) {
      const std::string_view line = lines_[i];
      const std::string_view name = label(line);
      const std::string_view content = line.substr(0, std::min<size_t>(line.size(), wide_ ? 65 : 60));
      if (name == "END OF HEADER") return i;
      if (name == "TIME SYSTEM ID") {
        const auto words_here = tokens(content);
        data_.time_system = words_here.empty() ? "GPS" : std::string(words_here[0]);
        auto scale = clock_time_scale(words_here.empty() ? std::string_view{} : words_here[0]);
        if (!scale) return lines_.error_at(i, "TIME SYSTEM ID: " + scale.error().message);
        data_.time_scale = *scale;
      } else if (name == "ANALYSIS CENTER") {
        data_.analysis_center = trimmed(content);
      } else if (name == "PRN LIST") {
        for (size_t column = 0; column + 3 <= content.size(); column += 4) {
          const std::string_view text = field(content, column, 3);
          if (text.empty()) continue;
          auto satellite = SatelliteId::parse(text);
          if (!satellite) return lines_.error_at(i, "PRN LIST: " + satellite.error().message);
          data_.listed_satellites.push_back(*satellite);
        }
      }
    }
    return make_error(ErrorCode::kParse, lines_.name() + ": no END OF HEADER line");
  }

  // One data record; returns the number of continuation lines it used.
  Result<size_t> parse_record(size_t i) {
    const std::string_view line = lines_[i];
    const std::string_view type = field(line, 0, 2);
    if (type.size() != 2 || !std::isupper(static_cast<unsigned char>(type[0]))) {
      return lines_.error_at(i, "unexpected data line '" + trimmed(line.substr(0, std::min<size_t>(line.size(), 20))) + "'");
    }
    // Some 3.04 writers keep 4-character names and some older files carry long names: take the
    // layout whose year field is numeric, preferring the one of the version.
    size_t offset = name_offset_;
    if (!is_year_field(line, 8 + offset)) {
      const size_t other = offset == 0 ? 5 : 0;
      if (!is_year_field(line, 8 + other)) return lines_.error_at(i, type == "AS" || type == "AR" ? std::string(type) + " record: no year at column " + std::to_string(9 + offset) : "bad data record");
      offset = other;
    }
    const std::string_view name = field(line, 3, 4 + offset);
    // Every record of an epoch repeats its time: parsed once per epoch.
    const std::string_view epoch_text = line.substr(8 + offset, std::min<size_t>(line.size() - (8 + offset), 29));
    if (epoch_text != last_epoch_text_) {
      CalendarTime c;
      const std::pair<const char*, std::pair<size_t, size_t>> int_fields[] = {
          {"year", {8, 4}}, {"month", {12, 3}}, {"day", {15, 3}}, {"hour", {18, 3}}, {"minute", {21, 3}}};
      int* targets[] = {&c.year, &c.month, &c.day, &c.hour, &c.minute};
      for (size_t k = 0; k < 5; ++k) {
        auto value = parse_integer(field(line, int_fields[k].second.first + offset, int_fields[k].second.second));
        if (!value) return lines_.error_at(i, std::string(type) + " " + std::string(name) + " epoch " + int_fields[k].first + ": " + value.error().message);
        *targets[k] = static_cast<int>(*value);
      }
      auto second = parse_fortran_double(field(line, 24 + offset, 10));
      if (!second) return lines_.error_at(i, std::string(type) + " " + std::string(name) + " epoch second: " + second.error().message);
      c.second = *second;
      if (c.month < 1 || c.month > 12 || c.day < 1 || c.day > 31 || c.hour < 0 || c.hour > 24 || c.minute < 0 ||
          c.minute > 59 || c.second < 0.0 || c.second >= 61.0) {
        return lines_.error_at(i, std::string(type) + " " + std::string(name) + ": epoch out of range");
      }
      last_epoch_text_ = epoch_text;
      last_epoch_ = GnssTime::from_calendar(c, data_.time_scale);
    }
    auto count = parse_integer(field(line, 34 + offset, 3));
    if (!count || *count < 1 || *count > 6) {
      return lines_.error_at(i, std::string(type) + " " + std::string(name) + ": number of values must be 1 to 6");
    }
    const size_t continuation =
        static_cast<size_t>(*count) > kValuesOnFirstLine
            ? (static_cast<size_t>(*count) - kValuesOnFirstLine + kValuesPerContinuationLine - 1) / kValuesPerContinuationLine
            : 0;
    if (i + continuation >= lines_.size()) return lines_.error_at(i, "record truncated: continuation line missing");
    if (type != "AS") return continuation;

    auto satellite = SatelliteId::parse(name);
    if (!satellite) return lines_.error_at(i, "AS satellite: " + satellite.error().message);
    // Values are separated by at least one blank (D19.12 with 1X), so blank-separated words are
    // safe; the first two are the bias and its sigma.
    std::string_view rest = line.size() > 37 + offset ? line.substr(37 + offset) : std::string_view{};
    const auto next_word = [&rest] {
      const size_t start = rest.find_first_not_of(' ');
      if (start == std::string_view::npos) return std::string_view{};
      const size_t end = std::min(rest.find(' ', start), rest.size());
      const std::string_view word = rest.substr(start, end - start);
      rest.remove_prefix(end);
      return word;
    };
    const std::string_view bias_text = next_word();
    if (bias_text.empty()) return lines_.error_at(i, "AS " + satellite->to_string() + ": clock bias missing");
    auto bias = parse_fortran_double(bias_text);
    if (!bias) return lines_.error_at(i, "AS " + satellite->to_string() + " clock bias: " + bias.error().message);
    ClockSample sample;
    sample.time = last_epoch_;
    sample.bias_s = *bias;
    const std::string_view sigma_text = *count >= 2 ? next_word() : std::string_view{};
    if (!sigma_text.empty()) {
      auto sigma = parse_fortran_double(sigma_text);
      if (!sigma) return lines_.error_at(i, "AS " + satellite->to_string() + " clock sigma: " + sigma.error().message);
      sample.sigma_s = *sigma;
    }
    data_.satellite_clocks[*satellite].push_back(sample);
    return continuation;
  }

  const TextLines& lines_;
  RinexClockData data_;
  std::string_view last_epoch_text_;  // columns of the last record's epoch, and its time
  GnssTime last_epoch_;
  bool wide_ = false;
  size_t name_offset_ = 0;
};

}  // namespace

const std::vector<ClockSample>* RinexClockData::series(const SatelliteId& satellite) const {
  const auto it = satellite_clocks.find(satellite);
  return it == satellite_clocks.end() ? nullptr : &it->second;
}

void RinexClockData::merge(const RinexClockData& other) {
  if (sources.empty()) {
    version = other.version;
    time_system = other.time_system;
    time_scale = other.time_scale;
    analysis_center = other.analysis_center;
  }
  for (const auto& satellite : other.listed_satellites) {
    if (std::find(listed_satellites.begin(), listed_satellites.end(), satellite) == listed_satellites.end()) {
      listed_satellites.push_back(satellite);
    }
  }
  for (const auto& [satellite, theirs] : other.satellite_clocks) {
    auto& mine = satellite_clocks[satellite];
    std::vector<ClockSample> merged;
    merged.reserve(mine.size() + theirs.size());
    size_t a = 0, b = 0;
    while (a < mine.size() || b < theirs.size()) {
      if (b == theirs.size() || (a < mine.size() && mine[a].time - theirs[b].time < -kSameTime_s)) {
        merged.push_back(mine[a++]);
      } else if (a == mine.size() || theirs[b].time - mine[a].time < -kSameTime_s) {
        merged.push_back(theirs[b++]);
      } else {  // same time: keep ours
        merged.push_back(mine[a++]);
        ++b;
      }
    }
    mine = std::move(merged);
  }
  sources.insert(sources.end(), other.sources.begin(), other.sources.end());
}

Result<RinexClockData> parse_rinex_clock(const std::string& name, std::string content) {
  const TextLines lines(name, std::move(content));
  return ClockParser(lines).run();
}

Result<RinexClockData> read_rinex_clock(const std::filesystem::path& path) {
  auto lines = TextLines::read(path);
  if (!lines) return lines.error();
  return ClockParser(*lines).run();
}

Result<RinexClockData> read_rinex_clock(const std::vector<std::filesystem::path>& paths) {
  if (paths.empty()) return make_error(ErrorCode::kInvalidArgument, "no clock file given");
  RinexClockData all;
  for (const auto& path : paths) {
    auto data = read_rinex_clock(path);
    if (!data) return data.error();
    all.merge(*data);
  }
  return all;
}

}  // namespace skytrace::orbits
