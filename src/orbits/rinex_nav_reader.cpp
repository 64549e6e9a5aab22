// Reader of RINEX navigation files: 2.x (GPS "N", GLONASS "G", GEO/SBAS "H"), 3.0x (mixed and
// single-system) and 4.0x (EPH, ION, STO records; EOP and unknown records skipped).
//
// Layout facts this reader relies on (RINEX 2.11, 3.05 and 4.00 specifications):
// - Epoch lines: RINEX 2 "I2,5(1X,I2),F5.1" then three D19.12 from column 22; RINEX 3/4 "A1,I2,1X,
//   I4,5(1X,I2)" then three D19.12 from column 23. Broadcast-orbit lines: four D19.12 from column 3
//   (RINEX 2) or 4 (RINEX 3/4).
// - Epochs are in the system's own time scale: GPS/QZSS/SBAS GPST, Galileo GST, BeiDou BDT, NavIC
//   IRNWT and GLONASS UTC.
// - Week fields: GPS/QZSS GPS week, Galileo "GAL week" aligned to the GPS week, BeiDou BDT week,
//   NavIC "IRN week" (RTKLIB and the 3.03+ files treat it as GPS-aligned; a week counted from the
//   NavIC epoch is 1024 weeks off and is corrected by the nearest-to-toc rule below).
#include "skytrace/orbits/rinex_nav.hpp"

#include <array>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <utility>

#include "skytrace/core/text_file.hpp"

namespace skytrace::orbits {
namespace {

constexpr double kWeek_s = 604800.0;
constexpr double kDay_s = 86400.0;
constexpr double kKm_m = 1000.0;
constexpr int kBdtMinusUtcToGps_s = 14;  // GPS - UTC = (BDT - UTC) + 14 s
// RINEX 3.05 marks an unknown value of the GLONASS fourth line with .999999999999E+09.
constexpr double kUnknownMarker = 0.999999999e9;
constexpr size_t kFieldWidth = 19;
constexpr double kGlonassTbStep_s = 900.0;       // GLONASS t_b is counted in 15-minute steps
constexpr double kGlonassTbSnapLimit_s = 30.0;  // larger offsets are left as written

bool is_blank(std::string_view line) {
  for (const char c : line) {
    if (c != ' ' && c != '\t') return false;
  }
  return true;
}

// A broadcast-orbit line starts with `indent` blanks (3 in RINEX 2, 4 later) and holds data.
bool is_orbit_line(std::string_view line, size_t indent) {
  if (line.size() <= indent || is_blank(line)) return false;
  for (size_t i = 0; i < indent; ++i) {
    if (line[i] != ' ') return false;
  }
  return true;
}

std::string_view header_label(std::string_view line) { return field(line, 60, 20); }

std::string quoted(std::string_view text) {
  std::string out;  // built by appending: GCC 12 warns falsely (-Wrestrict) on "'" + std::string
  out.reserve(text.size() + 2);
  out.push_back('\'');
  out.append(text);
  out.push_back('\'');
  return out;
}

// Nominal URA in metres of a GPS/QZSS CNAV URA index (IS-GPS-200 20.3.3.3.1.3 / 30.3.3.1.1.4);
// used for BeiDou SISAI too, which follows the same scale.
double ura_index_to_m(int index) {
  if (index <= 6) return std::pow(2.0, 1.0 + index / 2.0);
  if (index < 15) return std::pow(2.0, index - 2.0);
  return 6144.0;  // 15: no accuracy prediction; the largest bound
}

// The instance of `t` (shifted by whole weeks) nearest to `reference`: toe near a week boundary,
// or a week field counted from another epoch (NavIC, Galileo) resolves to the week of toc.
GnssTime nearest_instance(const GnssTime& t, const GnssTime& reference) {
  const double weeks = std::round((t - reference) / kWeek_s);
  return weeks == 0.0 ? t : t - weeks * kWeek_s;
}

// The lines of one record: row 0 is the epoch line, rows 1.. the broadcast-orbit lines.
struct RecordLines {
  std::array<size_t, 12> index{};
  size_t count = 0;
};

// Reads fixed-width numeric fields of one record and keeps the first error, so a decoder can read
// every field in sequence and check once. Slot 1..3 of row 0 are the epoch line's values; slots
// 0..3 of the other rows are the four values of a broadcast-orbit line.
class FieldReader {
 public:
  FieldReader(const TextLines& text, const RecordLines& rows, size_t epoch_col, size_t orbit_col)
      : text_(text), rows_(rows), epoch_col_(epoch_col), orbit_col_(orbit_col) {}

  double required(size_t row, int slot, std::string_view name) {
    return read(row, slot, name, false).value_or(0.0);
  }
  // A blank field (allowed by RINEX for spare or unknown values) gives `fallback`.
  double optional(size_t row, int slot, std::string_view name, double fallback = 0.0) {
    return read(row, slot, name, true).value_or(fallback);
  }
  std::optional<double> maybe(size_t row, int slot, std::string_view name) { return read(row, slot, name, true); }
  // A required value that must lie in [low, high] to describe a real satellite.
  double required_in(size_t row, int slot, std::string_view name, double low, double high, std::string_view what) {
    const double value = required(row, slot, name);
    if (!error_ && !(value >= low && value <= high)) {
      fail(row, name, "value " + std::to_string(value) + " outside [" + std::to_string(low) + ", " +
                          std::to_string(high) + "] (" + std::string(what) + ")");
    }
    return value;
  }
  // Seconds of week: more than a week outside [0, 604800) is corruption, not a time (1e40 has no
  // whole seconds in an int64).
  double seconds_of_week(size_t row, int slot, std::string_view name) {
    const double value_s = required(row, slot, name);
    if (!error_ && !(value_s >= -kWeek_s && value_s <= 2.0 * kWeek_s)) {
      fail(row, name, "out of range: " + std::to_string(value_s) + " s (expected seconds of week, 0 to 604800)");
    }
    return value_s;
  }

  [[nodiscard]] const std::optional<Error>& error() const { return error_; }

 private:
  std::optional<double> read(size_t row, int slot, std::string_view name, bool blank_ok) {
    if (error_) return std::nullopt;
    const std::string_view line = text_[rows_.index[row]];
    const size_t column = row == 0 ? epoch_col_ + static_cast<size_t>(slot - 1) * kFieldWidth
                                   : orbit_col_ + static_cast<size_t>(slot) * kFieldWidth;
    const std::string_view raw = field(line, column, kFieldWidth);
    if (raw.empty()) {
      if (!blank_ok) fail(row, name, "missing (blank)");
      return std::nullopt;
    }
    auto value = parse_fortran_double(raw);
    if (!value || !std::isfinite(*value)) {
      fail(row, name, "not a number " + quoted(raw));
      return std::nullopt;
    }
    return *value;
  }
  void fail(size_t row, std::string_view name, const std::string& why) {
    error_ = text_.error_at(rows_.index[row], "field '" + std::string(name) + "': " + why);
  }

  const TextLines& text_;
  const RecordLines& rows_;
  size_t epoch_col_;
  size_t orbit_col_;
  std::optional<Error> error_;
};

// Klobuchar coefficients arrive as two header lines (alpha, beta); both are needed.
struct PendingKlobuchar {
  std::optional<std::array<double, 4>> alpha;
  std::optional<std::array<double, 4>> beta;

  void commit_to(std::optional<KlobucharCoefficients>& target) const {
    if (target || !alpha || !beta) return;
    target = KlobucharCoefficients{*alpha, *beta};
  }
};

class NavReader {
 public:
  explicit NavReader(const TextLines& text)
      : text_(text), file_name_(std::filesystem::path(text.name()).filename().string()) {}

  Result<NavigationData> run() {
    if (auto status = parse_header(); !status) return status.error();
    Status body = major_ == 2 ? parse_body_v2() : major_ == 3 ? parse_body_v3() : parse_body_v4();
    if (!body) return body.error();
    resolve_leap_seconds();
    if (!skipped_.empty()) {
      std::string list;
      for (const auto& [what, count] : skipped_) {
        list += std::string(list.empty() ? "" : ", ") + what + " (" + std::to_string(count) + ")";
      }
      data_.warnings.push_back(text_.name() + ": records defined by RINEX but not used, skipped: " + list);
    }
    data_.source_files.push_back(text_.name());
    return std::move(data_);
  }

 private:
  // ---------------------------------------------------------------------------------------- header
  Status parse_header() {
    if (text_.size() == 0 || header_label(text_[0]) != "RINEX VERSION / TYPE") {
      return text_.error_at(0, "not a RINEX file: the first line lacks 'RINEX VERSION / TYPE'");
    }
    const std::string_view first = text_[0];
    auto version = parse_fortran_double(field(first, 0, 9));
    if (!version) return text_.error_at(0, "field 'format version': not a number " + quoted(field(first, 0, 9)));
    // Range first: a version such as 2E11 has no int (the cast would be undefined).
    major_ = *version >= 2.0 && *version < 5.0 ? static_cast<int>(std::floor(*version)) : 0;
    const char type = first.size() > 20 ? static_cast<char>(std::toupper(static_cast<unsigned char>(first[20]))) : ' ';
    file_system_ = first.size() > 40 ? static_cast<char>(std::toupper(static_cast<unsigned char>(first[40]))) : ' ';
    if (major_ == 2) {
      if (type == 'N') v2_system_ = GnssSystem::kGps;
      else if (type == 'G') v2_system_ = GnssSystem::kGlonass;
      else if (type == 'H') v2_system_ = GnssSystem::kSbas;
      else return not_navigation(type);
    } else if (major_ == 3 || major_ == 4) {
      // 'N' by the specification; 'G' and 'H' of RINEX 2 habits are accepted since records name
      // their system.
      if (type != 'N' && type != 'G' && type != 'H') return not_navigation(type);
    } else {
      Error error = text_.error_at(0, "unsupported RINEX version " + std::string(field(first, 0, 9)) +
                                          " (2.x, 3.x and 4.x are read)");
      error.code = ErrorCode::kUnsupported;
      return error;
    }

    PendingKlobuchar gps, qzss, beidou, navic;
    for (size_t i = 1; i < text_.size(); ++i) {
      const std::string_view line = text_[i];
      const std::string_view label = header_label(line);
      if (label == "END OF HEADER") {
        gps.commit_to(data_.ionosphere.gps);
        qzss.commit_to(data_.ionosphere.qzss);
        beidou.commit_to(data_.ionosphere.beidou);
        navic.commit_to(data_.ionosphere.navic);
        body_start_ = i + 1;
        return Ok{};
      }
      Status status = Ok{};
      if (label == "IONOSPHERIC CORR") {
        status = header_ionospheric_corr(i, gps, qzss, beidou, navic);
      } else if (label == "ION ALPHA" || label == "ION BETA") {
        auto values = four_header_values(i, 2, 12, label);
        if (!values) return values.error();
        (label == "ION ALPHA" ? gps.alpha : gps.beta) = *values;
      } else if (label == "TIME SYSTEM CORR") {
        status = header_time_system_corr(i);
      } else if (label == "DELTA-UTC: A0,A1,T,W") {
        status = header_delta_utc(i, "GPUT");
      } else if (label == "D-UTC A0,A1,T,W,S,U") {  // RINEX 2.1x GEO files
        status = header_delta_utc(i, "SBUT");
      } else if (label == "CORR TO SYSTEM TIME") {
        status = header_corr_to_system_time(i);
      } else if (label == "LEAP SECONDS") {
        status = header_leap_seconds(i);
      }
      if (!status) return status;
    }
    return text_.error_at(text_.size() - 1, "header has no 'END OF HEADER' line");
  }

  Status not_navigation(char type) const {
    return text_.error_at(0, std::string("not a RINEX navigation file (file type '") + type +
                                 "' in RINEX VERSION / TYPE)");
  }

  Result<std::array<double, 4>> four_header_values(size_t i, size_t start, size_t width, std::string_view label,
                                                    bool fourth_optional = false) const {
    std::array<double, 4> values{};
    for (size_t k = 0; k < 4; ++k) {
      const std::string_view raw = field(text_[i], start + k * width, width);
      if (raw.empty() && k == 3 && fourth_optional) continue;
      auto value = parse_fortran_double(raw);
      if (!value || !std::isfinite(*value)) {
        return text_.error_at(i, std::string(label) + " value " + std::to_string(k + 1) + ": not a number " + quoted(raw));
      }
      values[k] = *value;
    }
    return values;
  }

  Status header_ionospheric_corr(size_t i, PendingKlobuchar& gps, PendingKlobuchar& qzss, PendingKlobuchar& beidou,
                                 PendingKlobuchar& navic) {
    // A4,1X,4D12.4 then (3.03+) a time mark and a satellite in columns 54-58, which are not needed.
    const std::string_view type = field(text_[i], 0, 4);
    // GAL lines may leave the unused fourth value blank.
    auto values = four_header_values(i, 5, 12, "IONOSPHERIC CORR " + std::string(type), type == "GAL");
    if (!values) return values.error();
    if (type == "GAL") {
      if (!data_.ionosphere.galileo) data_.ionosphere.galileo = NequickGCoefficients{(*values)[0], (*values)[1], (*values)[2]};
      return Ok{};
    }
    PendingKlobuchar* target = nullptr;
    if (type.substr(0, 3) == "GPS") target = &gps;
    else if (type.substr(0, 3) == "QZS") target = &qzss;
    else if (type.substr(0, 3) == "BDS") target = &beidou;
    else if (type.substr(0, 3) == "IRN") target = &navic;
    if (target == nullptr || type.size() != 4) return Ok{};  // unknown models are not needed here
    // BDS and QZS lines may repeat with other time marks; the first set is kept.
    auto& slot = type[3] == 'A' ? target->alpha : target->beta;
    if (!slot && (type[3] == 'A' || type[3] == 'B')) slot = *values;
    return Ok{};
  }

  Status header_time_system_corr(size_t i) {
    // A4,1X,D17.10,D16.9,1X,I6,1X,I4: type, a0, a1, reference seconds of week, week.
    const std::string_view line = text_[i];
    TimeSystemCorrection correction;
    correction.type = std::string(field(line, 0, 4));
    auto a0 = parse_fortran_double(field(line, 5, 17));
    auto a1 = parse_fortran_double(field(line, 22, 16));
    if (!a0) return text_.error_at(i, "TIME SYSTEM CORR field 'a0': not a number " + quoted(field(line, 5, 17)));
    if (!a1) return text_.error_at(i, "TIME SYSTEM CORR field 'a1': not a number " + quoted(field(line, 22, 16)));
    auto tow = parse_integer(field(line, 38, 7));
    auto week = parse_integer(field(line, 45, 5));
    if (!tow) return text_.error_at(i, "TIME SYSTEM CORR field 'T': not an integer " + quoted(field(line, 38, 7)));
    if (!week) return text_.error_at(i, "TIME SYSTEM CORR field 'W': not an integer " + quoted(field(line, 45, 5)));
    correction.a0_s = *a0;
    correction.a1_s_per_s = *a1;
    // BeiDou gives BDT weeks; the others a GPS-aligned week. GLONASS (GLUT, GLGP) writes zero:
    // those corrections have no reference time and keep the default.
    if (*week != 0 || *tow != 0) {
      const TimeScale scale = correction.type.substr(0, 2) == "BD" ? TimeScale::kBdt : TimeScale::kGpst;
      correction.reference_time = GnssTime::from_week_tow(scale, static_cast<int>(*week), static_cast<double>(*tow));
    }
    correction.source = where(i);
    add_time_correction(std::move(correction));
    return Ok{};
  }

  Status header_delta_utc(size_t i, const char* type) {
    // RINEX 2: 3X,2D19.12,2I9 (GEO files: 3X,2D19.12,2I7): A0, A1, T (s of week), W (GPS week).
    const std::string_view line = text_[i];
    const bool geo = std::string_view(type) == "SBUT";
    auto a0 = parse_fortran_double(field(line, 3, 19));
    auto a1 = parse_fortran_double(field(line, 22, 19));
    auto tow = parse_integer(field(line, 41, geo ? 7 : 9));
    auto week = parse_integer(field(line, geo ? 48 : 50, geo ? 7 : 9));
    if (!a0) return text_.error_at(i, "DELTA-UTC field 'A0': not a number " + quoted(field(line, 3, 19)));
    if (!a1) return text_.error_at(i, "DELTA-UTC field 'A1': not a number " + quoted(field(line, 22, 19)));
    if (!tow || !week) return text_.error_at(i, "DELTA-UTC fields 'T,W': not integers");
    TimeSystemCorrection correction{type, *a0, *a1,
                                    GnssTime::from_week_tow(TimeScale::kGpst, static_cast<int>(*week),
                                                            static_cast<double>(*tow)),
                                    where(i)};
    add_time_correction(std::move(correction));
    return Ok{};
  }

  Status header_corr_to_system_time(size_t i) {
    // GLONASS RINEX 2: 3I6 (reference date), 3X, D19.12: the correction GLONASS time -> UTC(SU)
    // (written "-TauC"), kept as written under the RINEX 3 name GLUT.
    const std::string_view line = text_[i];
    auto year = parse_integer(field(line, 0, 6));
    auto month = parse_integer(field(line, 6, 6));
    auto day = parse_integer(field(line, 12, 6));
    auto value = parse_fortran_double(field(line, 21, 19));
    if (!year || !month || !day || *month < 1 || *month > 12 || *day < 1 || *day > 31) {
      return text_.error_at(i, "CORR TO SYSTEM TIME: invalid reference date");
    }
    if (!value) return text_.error_at(i, "CORR TO SYSTEM TIME field '-TauC': not a number " + quoted(field(line, 21, 19)));
    const CalendarTime date{static_cast<int>(*year), static_cast<int>(*month), static_cast<int>(*day), 0, 0, 0.0};
    add_time_correction(TimeSystemCorrection{"GLUT", *value, 0.0, GnssTime::from_calendar(date, TimeScale::kUtc), where(i)});
    return Ok{};
  }

  Status header_leap_seconds(size_t i) {
    const std::string_view line = text_[i];
    auto leap = parse_integer(field(line, 0, 6));
    if (!leap) return text_.error_at(i, "LEAP SECONDS field 'current leap seconds': not an integer " + quoted(field(line, 0, 6)));
    leap_value_ = static_cast<int>(*leap);
    // 3.04+ names the time system in columns 24-26; BDS counts BDT - UTC.
    const std::string_view system = field(line, 24, 3);
    leap_is_bdt_ = system == "BDS";
    leap_system_blank_ = system.empty();
    return Ok{};
  }

  // NavigationData keeps GPS - UTC. A BeiDou-only file without a time-system mark (3.02 writers)
  // may count BDT - UTC: the records' epochs decide which reading is consistent.
  void resolve_leap_seconds() {
    if (!leap_value_) return;
    int value = *leap_value_ + (leap_is_bdt_ ? kBdtMinusUtcToGps_s : 0);
    if (!leap_is_bdt_ && leap_system_blank_ && file_system_ == 'C') {
      value = *leap_value_ + kBdtMinusUtcToGps_s;
      if (!data_.kepler.empty() && gps_minus_utc_s(data_.kepler.front().toc) == *leap_value_) value = *leap_value_;
    }
    data_.leap_seconds = value;
  }

  void add_time_correction(TimeSystemCorrection correction) {
    for (const auto& known : data_.time_corrections) {
      if (known.type == correction.type) return;  // the first one of each type is kept
    }
    data_.time_corrections.push_back(std::move(correction));
  }

  // -------------------------------------------------------------------------------- record framing
  std::string where(size_t index) const { return file_name_ + ":" + std::to_string(index + 1); }

  // Gathers the epoch line `first` and up to `max_rows - 1` broadcast-orbit lines after it.
  RecordLines gather(size_t first, size_t max_rows, size_t indent) const {
    RecordLines rows;
    rows.index[rows.count++] = first;
    for (size_t j = first + 1; j < text_.size() && rows.count < max_rows; ++j) {
      if (!is_orbit_line(text_[j], indent)) break;
      rows.index[rows.count++] = j;
    }
    return rows;
  }

  Error truncated(size_t first, const SatelliteId& sat, size_t got, size_t expected) const {
    return text_.error_at(first, "record of " + sat.to_string() + " ends after " + std::to_string(got) + " of " +
                                     std::to_string(expected) + " lines");
  }

  Result<SatelliteId> satellite_at(size_t index, std::string_view text) const {
    if (!text.empty()) {
      auto system = system_from_letter(text[0]);
      if (!system) return text_.error_at(index, "unknown satellite system letter '" + std::string(1, text[0]) + "'");
    }
    auto sat = SatelliteId::parse(text);
    if (!sat) return text_.error_at(index, "field 'satellite': " + sat.error().message);
    return *sat;
  }

  Status parse_body_v2() {
    const size_t n = text_.size();
    size_t i = body_start_;
    while (i < n) {
      const std::string_view line = text_[i];
      if (is_blank(line)) { ++i; continue; }
      if (is_orbit_line(line, 3)) return text_.error_at(i, "broadcast-orbit line outside a record");
      auto prn = parse_integer(field(line, 0, 2));
      if (!prn) return text_.error_at(i, "field 'satellite number': not an integer " + quoted(field(line, 0, 2)));
      long number = *prn;
      if (v2_system_ == GnssSystem::kSbas && number >= 100) number -= 100;  // GEO files write PRN - 100
      auto sat = satellite_at(i, std::string(1, system_letter(v2_system_)) + std::to_string(number));
      if (!sat) return sat.error();
      const size_t expected = v2_system_ == GnssSystem::kGps ? 8 : 4;
      const RecordLines rows = gather(i, expected, 3);
      if (rows.count < expected) return truncated(i, *sat, rows.count, expected);
      Status status = Ok{};
      if (v2_system_ == GnssSystem::kGps) status = decode_legacy_kepler(rows, *sat, std::nullopt, 22, 3);
      else if (v2_system_ == GnssSystem::kGlonass) status = decode_glonass(rows, *sat, 22, 3);
      else status = decode_sbas(rows, *sat, 22, 3);
      if (!status) return status;
      i = rows.index[rows.count - 1] + 1;
    }
    return Ok{};
  }

  Status parse_body_v3() {
    const size_t n = text_.size();
    size_t i = body_start_;
    while (i < n) {
      const std::string_view line = text_[i];
      if (is_blank(line)) { ++i; continue; }
      if (is_orbit_line(line, 4)) return text_.error_at(i, "broadcast-orbit line outside a record");
      auto sat = satellite_at(i, line.substr(0, 3));
      if (!sat) return sat.error();
      size_t min_rows = 8, max_rows = 8;
      if (sat->system == GnssSystem::kGlonass) {
        min_rows = 4;
        max_rows = 5;  // RINEX 3.05 adds a fourth broadcast-orbit line
      } else if (sat->system == GnssSystem::kSbas) {
        min_rows = max_rows = 4;
      }
      const RecordLines rows = gather(i, max_rows, 4);
      if (rows.count < min_rows) return truncated(i, *sat, rows.count, min_rows);
      Status status = Ok{};
      if (sat->system == GnssSystem::kGlonass) status = decode_glonass(rows, *sat, 23, 4);
      else if (sat->system == GnssSystem::kSbas) status = decode_sbas(rows, *sat, 23, 4);
      else status = decode_legacy_kepler(rows, *sat, std::nullopt, 23, 4);
      if (!status) return status;
      i = rows.index[rows.count - 1] + 1;
    }
    return Ok{};
  }

  // RINEX 4: every record starts with "> TYPE SAT MESSAGE"; its lines run to the next '>'.
  Status parse_body_v4() {
    const size_t n = text_.size();
    size_t i = body_start_;
    while (i < n) {
      const std::string_view line = text_[i];
      if (is_blank(line)) { ++i; continue; }
      if (line[0] != '>') return text_.error_at(i, "expected a record start '>' (RINEX 4), found " + quoted(line.substr(0, 20)));
      size_t end = i + 1;
      while (end < n && (text_[end].empty() || text_[end][0] != '>')) ++end;
      size_t last = end;  // trailing blank lines do not belong to the record
      while (last > i + 1 && is_blank(text_[last - 1])) --last;
      RecordLines rows;
      for (size_t j = i + 1; j < last; ++j) {
        if (rows.count == rows.index.size()) return text_.error_at(i, "record has more lines than any RINEX 4 record");
        rows.index[rows.count++] = j;
      }
      if (auto status = decode_v4_record(i, rows); !status) return status;
      i = end;
    }
    return Ok{};
  }

  Status decode_v4_record(size_t head, const RecordLines& rows) {
    // "> EPH G18 LNAV": split on blanks.
    std::array<std::string_view, 4> token{};
    size_t count = 0;
    const std::string_view line = text_[head];
    size_t pos = 1;
    while (pos < line.size() && count < token.size()) {
      while (pos < line.size() && line[pos] == ' ') ++pos;
      const size_t start = pos;
      while (pos < line.size() && line[pos] != ' ') ++pos;
      if (pos > start) token[count++] = line.substr(start, pos - start);
    }
    const std::string_view type = token[0];
    if (type.empty()) return text_.error_at(head, "record start '>' without a record type (EPH, STO, EOP, ION)");
    if (type != "EPH" && type != "ION" && type != "STO") {  // EOP and future records
      ++skipped_[std::string(type) + " records"];
      return Ok{};
    }
    if (count < 3) return text_.error_at(head, "record start needs a satellite and a message type: " + quoted(line));
    auto sat = satellite_at(head, token[1]);
    if (!sat) return sat.error();
    const std::string_view message = token[2];
    if (type == "EPH") return decode_v4_ephemeris(head, rows, *sat, message);
    if (type == "ION") return decode_v4_ionosphere(head, rows, *sat, message);
    return decode_v4_time_offset(head, rows, *sat);
  }

  // Checks the line count of a RINEX 4 record (the lines after its '>' line).
  Status check_rows(size_t head, const RecordLines& rows, const SatelliteId& sat, size_t expected_min,
                    size_t expected_max) const {
    if (rows.count < expected_min) return truncated(head, sat, rows.count, expected_min);
    if (rows.count > expected_max) {
      return text_.error_at(rows.index[expected_max], "record of " + sat.to_string() + " has " +
                                                          std::to_string(rows.count) + " lines, expected " +
                                                          std::to_string(expected_max));
    }
    return Ok{};
  }

  Status decode_v4_ephemeris(size_t head, const RecordLines& rows, const SatelliteId& sat, std::string_view message) {
    using S = GnssSystem;
    enum class Kind { kLegacy, kCnav, kCnav2, kBdsCnav1, kBdsCnav2, kBdsCnav3, kGlonass, kSbas, kSkip };
    Kind kind = Kind::kSkip;
    std::optional<NavMessage> named;
    switch (sat.system) {
      case S::kGps:
      case S::kQzss: {
        const bool gps = sat.system == S::kGps;
        if (message == "LNAV") { kind = Kind::kLegacy; named = gps ? NavMessage::kGpsLnav : NavMessage::kQzssLnav; }
        if (message == "CNAV") { kind = Kind::kCnav; named = gps ? NavMessage::kGpsCnav : NavMessage::kQzssCnav; }
        if (message == "CNV2") { kind = Kind::kCnav2; named = gps ? NavMessage::kGpsCnav2 : NavMessage::kQzssCnav2; }
        break;
      }
      case S::kGalileo:
        if (message == "INAV") { kind = Kind::kLegacy; named = NavMessage::kGalileoInav; }
        if (message == "FNAV") { kind = Kind::kLegacy; named = NavMessage::kGalileoFnav; }
        break;
      case S::kBeiDou:
        if (message == "D1") { kind = Kind::kLegacy; named = NavMessage::kBeiDouD1; }
        if (message == "D2") { kind = Kind::kLegacy; named = NavMessage::kBeiDouD2; }
        if (message == "CNV1") { kind = Kind::kBdsCnav1; named = NavMessage::kBeiDouCnav1; }
        if (message == "CNV2") { kind = Kind::kBdsCnav2; named = NavMessage::kBeiDouCnav2; }
        if (message == "CNV3") { kind = Kind::kBdsCnav3; named = NavMessage::kBeiDouCnav3; }
        break;
      case S::kNavic:
        if (message == "LNAV") { kind = Kind::kLegacy; named = NavMessage::kNavicLnav; }
        break;
      case S::kGlonass:
        if (message == "FDMA") kind = Kind::kGlonass;
        break;
      case S::kSbas:
        if (message == "SBAS") kind = Kind::kSbas;
        break;
    }
    if (kind == Kind::kSkip) {  // GLONASS L1OC/L3OC, NavIC L1NV, ...: not used
      ++skipped_["EPH " + std::string(system_name(sat.system)) + " " + std::string(message)];
      return Ok{};
    }

    size_t min_rows = 8, max_rows = 8;
    switch (kind) {
      case Kind::kCnav: case Kind::kBdsCnav3: min_rows = max_rows = 9; break;
      case Kind::kCnav2: case Kind::kBdsCnav1: case Kind::kBdsCnav2: min_rows = max_rows = 10; break;
      case Kind::kGlonass: min_rows = 4; max_rows = 5; break;
      case Kind::kSbas: min_rows = max_rows = 4; break;
      default: break;
    }
    if (auto status = check_rows(head, rows, sat, min_rows, max_rows); !status) return status;
    auto in_record = satellite_at(rows.index[0], text_[rows.index[0]].substr(0, 3));
    if (!in_record) return in_record.error();
    if (*in_record != sat) {
      return text_.error_at(rows.index[0], "satellite " + in_record->to_string() + " differs from " + sat.to_string() +
                                               " named on the record start");
    }
    const std::string source = where(head);
    switch (kind) {
      case Kind::kLegacy: return decode_legacy_kepler(rows, sat, named, 23, 4, source);
      case Kind::kCnav:
      case Kind::kCnav2: return decode_cnav(rows, sat, *named, source);
      case Kind::kBdsCnav1:
      case Kind::kBdsCnav2:
      case Kind::kBdsCnav3: return decode_bds_cnav(rows, sat, *named, source);
      case Kind::kGlonass: return decode_glonass(rows, sat, 23, 4, source);
      case Kind::kSbas: return decode_sbas(rows, sat, 23, 4, source);
      case Kind::kSkip: break;
    }
    return Ok{};
  }

  Status decode_v4_ionosphere(size_t head, const RecordLines& rows, const SatelliteId& sat, std::string_view message) {
    using S = GnssSystem;
    std::optional<KlobucharCoefficients>* klobuchar = nullptr;
    if (sat.system == S::kGps && message == "LNAV") klobuchar = &data_.ionosphere.gps;
    if (sat.system == S::kQzss && message == "LNAV") klobuchar = &data_.ionosphere.qzss;
    if (sat.system == S::kBeiDou && message == "D1D2") klobuchar = &data_.ionosphere.beidou;
    if (sat.system == S::kNavic && message == "LNAV") klobuchar = &data_.ionosphere.navic;
    const bool nequick = sat.system == S::kGalileo && message == "IFNV";
    if (klobuchar == nullptr && !nequick) {  // BDGIM (CNVX) and others are not used
      ++skipped_["ION " + std::string(system_name(sat.system)) + " " + std::string(message)];
      return Ok{};
    }

    if (auto status = check_rows(head, rows, sat, nequick ? 2 : 3, nequick ? 2 : 3); !status) return status;
    if (auto epoch = parse_epoch(rows.index[0], false); !epoch) return epoch.error();
    FieldReader f(text_, rows, 23, 4);
    if (nequick) {
      NequickGCoefficients c{f.required(0, 1, "ai0"), f.required(0, 2, "ai1"), f.required(0, 3, "ai2")};
      if (f.error()) return *f.error();
      if (!data_.ionosphere.galileo) data_.ionosphere.galileo = c;
      return Ok{};
    }
    KlobucharCoefficients c;
    c.alpha = {f.required(0, 1, "alpha0"), f.required(0, 2, "alpha1"), f.required(0, 3, "alpha2"), f.required(1, 0, "alpha3")};
    c.beta = {f.required(1, 1, "beta0"), f.required(1, 2, "beta1"), f.required(1, 3, "beta2"), f.required(2, 0, "beta3")};
    if (f.error()) return *f.error();
    if (!*klobuchar) *klobuchar = c;  // the first set (header or record) is kept
    return Ok{};
  }

  Status decode_v4_time_offset(size_t head, const RecordLines& rows, const SatelliteId& sat) {
    if (auto status = check_rows(head, rows, sat, 2, 2); !status) return status;
    const TimeScale scale = sat.system == GnssSystem::kGlonass ? TimeScale::kUtc : system_time_scale(sat.system);
    auto epoch = parse_epoch(rows.index[0], false);
    if (!epoch) return epoch.error();
    const std::string_view type = field(text_[rows.index[0]], 24, 4);
    if (type.size() != 4) return text_.error_at(rows.index[0], "field 'time offset type': " + quoted(type) + " is not a 4-letter code such as GPUT");
    FieldReader f(text_, rows, 23, 4);
    // Line 2: transmission time, A0, A1, A2 (the quadratic term is not kept).
    f.optional(1, 0, "transmission time");
    const double a0 = f.required(1, 1, "A0");
    const double a1 = f.required(1, 2, "A1");
    if (f.error()) return *f.error();
    add_time_correction(TimeSystemCorrection{std::string(type), a0, a1, GnssTime::from_calendar(*epoch, scale), where(head)});
    return Ok{};
  }

  // ------------------------------------------------------------------------------------ epochs
  // The epoch of a record line: RINEX 2 "I2,5(1X,I2),F5.1" with a two-digit year; RINEX 3/4 a
  // four-digit year from column 4 and whole seconds.
  Result<CalendarTime> parse_epoch(size_t index, bool rinex2) const {
    const std::string_view line = text_[index];
    struct Part {
      const char* name;
      size_t start, width;
      int min, max;
    };
    const std::array<Part, 5> parts = rinex2 ? std::array<Part, 5>{{{"year", 3, 2, 0, 99},
                                                                    {"month", 6, 2, 1, 12},
                                                                    {"day", 9, 2, 1, 31},
                                                                    {"hour", 12, 2, 0, 23},
                                                                    {"minute", 15, 2, 0, 59}}}
                                             : std::array<Part, 5>{{{"year", 4, 4, 1980, 2200},
                                                                    {"month", 9, 2, 1, 12},
                                                                    {"day", 12, 2, 1, 31},
                                                                    {"hour", 15, 2, 0, 23},
                                                                    {"minute", 18, 2, 0, 59}}};
    std::array<int, 5> value{};
    for (size_t k = 0; k < parts.size(); ++k) {
      const std::string_view raw = field(line, parts[k].start, parts[k].width);
      auto number = parse_integer(raw);
      if (!number) return text_.error_at(index, std::string("field 'epoch ") + parts[k].name + "': not an integer " + quoted(raw));
      if (*number < parts[k].min || *number > parts[k].max) {
        return text_.error_at(index, std::string("field 'epoch ") + parts[k].name + "': " + std::to_string(*number) + " out of range");
      }
      value[k] = static_cast<int>(*number);
    }
    const std::string_view raw_second = rinex2 ? field(line, 17, 5) : field(line, 21, 2);
    auto second = parse_fortran_double(raw_second);
    if (!second || *second < 0.0 || *second >= 61.0) {
      return text_.error_at(index, "field 'epoch second': invalid " + quoted(raw_second));
    }
    int year = value[0];
    if (rinex2) year += year >= 80 ? 1900 : 2000;
    return CalendarTime{year, value[1], value[2], value[3], value[4], *second};
  }

  // ---------------------------------------------------------------------------------- decoders
  // GPS/QZSS LNAV, Galileo I/NAV and F/NAV, BeiDou D1/D2, NavIC LNAV: the common 8-line layout.
  Status decode_legacy_kepler(const RecordLines& rows, const SatelliteId& sat, std::optional<NavMessage> named,
                              size_t epoch_col, size_t orbit_col, std::string source = {}) {
    using S = GnssSystem;
    auto epoch = parse_epoch(rows.index[0], major_ == 2);
    if (!epoch) return epoch.error();
    FieldReader f(text_, rows, epoch_col, orbit_col);
    KeplerEphemeris e;
    e.satellite = sat;
    e.toc = GnssTime::from_calendar(*epoch, system_time_scale(sat.system));
    const char* iod_name = sat.system == S::kGalileo ? "IODnav" : sat.system == S::kBeiDou ? "AODE"
                           : sat.system == S::kNavic ? "IODEC" : "IODE";
    const double iode = f.required(1, 0, iod_name);
    decode_kepler_elements(f, e, "Delta n");
    e.iode = static_cast<int>(std::lround(iode));
    e.iodc = e.iode;
    double week = 0.0;
    double data_source = 0.0;
    switch (sat.system) {
      case S::kGps:
      case S::kQzss: {
        e.codes_on_l2 = static_cast<int>(std::lround(f.optional(5, 1, "codes on L2 channel")));
        week = f.required(5, 2, "GPS week");
        e.l2p_data_flag = static_cast<int>(std::lround(f.optional(5, 3, "L2 P data flag")));
        e.accuracy_m = f.optional(6, 0, "SV accuracy");
        e.health = static_cast<int>(std::lround(f.required(6, 1, "SV health")));
        e.group_delays.tgd_s = f.optional(6, 2, "TGD");
        e.iodc = static_cast<int>(std::lround(f.optional(6, 3, "IODC", iode)));
        e.transmission_time_sow = f.optional(7, 0, "transmission time of message", kUnknownTransmissionTime_s);
        const double fit = f.optional(7, 1, "fit interval");
        // QZSS writes the fit-interval flag (0: 2 hours, 1: more than 2 hours, not quantified).
        if (sat.system == S::kQzss && fit < 1.5) e.fit_interval_h = fit == 0.0 ? 2.0 : 0.0;
        else e.fit_interval_h = fit;
        e.message = sat.system == S::kGps ? NavMessage::kGpsLnav : NavMessage::kQzssLnav;
        break;
      }
      case S::kGalileo:
        data_source = f.required(5, 1, "data sources");
        week = f.required(5, 2, "GAL week");
        e.accuracy_m = f.optional(6, 0, "SISA");
        e.health = static_cast<int>(std::lround(f.required(6, 1, "SV health")));
        e.group_delays.bgd_e1e5a_s = f.optional(6, 2, "BGD E5a/E1");
        e.group_delays.bgd_e1e5b_s = f.optional(6, 3, "BGD E5b/E1");
        e.transmission_time_sow = f.optional(7, 0, "transmission time of message", kUnknownTransmissionTime_s);
        break;
      case S::kBeiDou:
        week = f.required(5, 2, "BDT week");
        e.accuracy_m = f.optional(6, 0, "SV accuracy");
        e.health = static_cast<int>(std::lround(f.required(6, 1, "SatH1")));
        e.group_delays.tgd1_s = f.optional(6, 2, "TGD1 B1/B3");
        e.group_delays.tgd2_s = f.optional(6, 3, "TGD2 B2/B3");
        e.transmission_time_sow = f.optional(7, 0, "transmission time of message", kUnknownTransmissionTime_s);
        e.iodc = static_cast<int>(std::lround(f.optional(7, 1, "AODC")));
        // GEO satellites (C01-C05, C59-C63) broadcast D2, the others D1.
        e.message = (sat.number <= 5 || sat.number >= 59) ? NavMessage::kBeiDouD2 : NavMessage::kBeiDouD1;
        break;
      case S::kNavic:
        week = f.required(5, 2, "IRN week");
        e.accuracy_m = f.optional(6, 0, "user range accuracy");
        e.health = static_cast<int>(std::lround(f.required(6, 1, "SV health")));
        e.group_delays.tgd_s = f.optional(6, 2, "TGD");
        e.transmission_time_sow = f.optional(7, 0, "transmission time of message", kUnknownTransmissionTime_s);
        e.message = NavMessage::kNavicLnav;
        break;
      case S::kGlonass:
      case S::kSbas: break;  // decoded elsewhere
    }
    if (f.error()) return *f.error();

    if (sat.system == S::kGalileo) {
      if (data_source < 0.0 || data_source > 65535.0) {
        return text_.error_at(rows.index[5], "field 'data sources': " + std::to_string(data_source) + " out of range");
      }
      e.data_source = static_cast<std::uint32_t>(std::lround(data_source));
      // Bit 0 I/NAV E1-B, bit 2 I/NAV E5b-I, bit 9 clock for E5b: I/NAV. Bit 1 F/NAV E5a-I, bit 8
      // clock for E5a: F/NAV.
      const bool inav = (e.data_source & ((1u << 0) | (1u << 2) | (1u << 9))) != 0;
      const bool fnav = (e.data_source & ((1u << 1) | (1u << 8))) != 0;
      if (!named) {
        if (inav == fnav) {
          return text_.error_at(rows.index[5], "field 'data sources': " + std::to_string(e.data_source) +
                                                   (inav ? " sets both I/NAV and F/NAV bits" : " sets neither I/NAV nor F/NAV bits"));
        }
        e.message = inav ? NavMessage::kGalileoInav : NavMessage::kGalileoFnav;
      }
    }
    if (named) e.message = *named;

    e.week = static_cast<int>(std::lround(week));
    const TimeScale week_scale = sat.system == S::kBeiDou ? TimeScale::kBdt : TimeScale::kGpst;
    e.toe = nearest_instance(GnssTime::from_week_tow(week_scale, e.week, e.toe_sow), e.toc);
    e.source = source.empty() ? where(rows.index[0]) : std::move(source);
    data_.kepler.push_back(std::move(e));
    return Ok{};
  }

  // The first five lines shared by the RINEX 4 CNAV layouts (GPS/QZSS CNAV, CNAV-2; BeiDou CNAV).
  void decode_cnav_orbit(FieldReader& f, KeplerEphemeris& e) const {
    e.a_dot_m_per_s = f.required(1, 0, "Adot");
    decode_kepler_elements(f, e, "Delta n0");
    e.delta_n_dot_rad_per_s2 = f.required(5, 1, "Delta n0 dot");
  }

  // The clock polynomial and Keplerian elements every Keplerian layout (legacy and CNAV) holds in
  // the same places; the layouts differ in the first field of line 1 and from line 5 on.
  static void decode_kepler_elements(FieldReader& f, KeplerEphemeris& e, const char* delta_n_name) {
    e.af0_s = f.required(0, 1, "SV clock bias");
    e.af1_s_per_s = f.required(0, 2, "SV clock drift");
    e.af2_s_per_s2 = f.required(0, 3, "SV clock drift rate");
    e.crs_m = f.required(1, 1, "Crs");
    e.delta_n_rad_per_s = f.required(1, 2, delta_n_name);
    e.m0_rad = f.required(1, 3, "M0");
    e.cuc_rad = f.required(2, 0, "Cuc");
    e.eccentricity = f.required_in(2, 1, "e Eccentricity", 0.0, 0.9, "an orbit around the Earth");
    e.cus_rad = f.required(2, 2, "Cus");
    // 1000-10000 sqrt(m): semi-major axes from 1,000 to 100,000 km hold every navigation orbit.
    e.sqrt_a_sqrtm = f.required_in(2, 3, "sqrt(A)", 1000.0, 10000.0, "a semi-major axis of 1,000 to 100,000 km");
    e.toe_sow = f.seconds_of_week(3, 0, "Toe");
    e.cic_rad = f.required(3, 1, "Cic");
    e.omega0_rad = f.required(3, 2, "OMEGA0");
    e.cis_rad = f.required(3, 3, "Cis");
    e.i0_rad = f.required(4, 0, "i0");
    e.crc_m = f.required(4, 1, "Crc");
    e.omega_rad = f.required(4, 2, "omega");
    e.omega_dot_rad_per_s = f.required(4, 3, "OMEGA DOT");
    e.idot_rad_per_s = f.required(5, 0, "IDOT");
  }

  Status decode_cnav(const RecordLines& rows, const SatelliteId& sat, NavMessage message, std::string source) {
    auto epoch = parse_epoch(rows.index[0], false);
    if (!epoch) return epoch.error();
    FieldReader f(text_, rows, 23, 4);
    KeplerEphemeris e;
    e.satellite = sat;
    e.message = message;
    e.toc = GnssTime::from_calendar(*epoch, system_time_scale(sat.system));
    decode_cnav_orbit(f, e);
    // Row 5: URAI_NED0, URAI_NED1; row 6: URAI_ED, health, TGD, URAI_NED2.
    e.accuracy_m = ura_index_to_m(static_cast<int>(std::lround(f.optional(6, 0, "URAI_ED"))));
    e.health = static_cast<int>(std::lround(f.required(6, 1, "SV health")));
    e.group_delays.tgd_s = f.optional(6, 2, "TGD");
    e.group_delays.isc_l1ca_s = f.optional(7, 0, "ISC_L1CA");
    e.group_delays.isc_l2c_s = f.optional(7, 1, "ISC_L2C");
    e.group_delays.isc_l5i5_s = f.optional(7, 2, "ISC_L5I5");
    e.group_delays.isc_l5q5_s = f.optional(7, 3, "ISC_L5Q5");
    size_t last = 8;
    if (message == NavMessage::kGpsCnav2 || message == NavMessage::kQzssCnav2) {
      e.group_delays.isc_l1cd_s = f.optional(8, 0, "ISC_L1Cd");
      e.group_delays.isc_l1cp_s = f.optional(8, 1, "ISC_L1Cp");
      last = 9;
    }
    e.transmission_time_sow = f.optional(last, 0, "transmission time of message", kUnknownTransmissionTime_s);
    const std::optional<double> week = f.maybe(last, 1, "week");
    if (f.error()) return *f.error();
    e.week = week ? static_cast<int>(std::lround(*week)) : e.toc.to_week_tow(TimeScale::kGpst).week;
    e.toe = nearest_instance(GnssTime::from_week_tow(TimeScale::kGpst, e.week, e.toe_sow), e.toc);
    e.source = std::move(source);
    data_.kepler.push_back(std::move(e));
    return Ok{};
  }

  Status decode_bds_cnav(const RecordLines& rows, const SatelliteId& sat, NavMessage message, std::string source) {
    auto epoch = parse_epoch(rows.index[0], false);
    if (!epoch) return epoch.error();
    FieldReader f(text_, rows, 23, 4);
    KeplerEphemeris e;
    e.satellite = sat;
    e.message = message;
    e.toc = GnssTime::from_calendar(*epoch, TimeScale::kBdt);
    decode_cnav_orbit(f, e);
    // Row 5: SatType, t_op; row 6: SISAI_oe, SISAI_ocb, SISAI_oc1, SISAI_oc2 (the orbit part is
    // kept as the accuracy).
    e.accuracy_m = ura_index_to_m(static_cast<int>(std::lround(f.optional(6, 0, "SISAI_oe"))));
    auto& gd = e.group_delays;
    if (message == NavMessage::kBeiDouCnav3) {
      e.health = static_cast<int>(std::lround(f.required(7, 1, "health")));
      gd.tgd_b2bi_s = f.optional(7, 3, "TGD_B2bI");
      e.transmission_time_sow = f.optional(8, 0, "transmission time of message", kUnknownTransmissionTime_s);
    } else {
      if (message == NavMessage::kBeiDouCnav1) gd.isc_b1cd_s = f.optional(7, 0, "ISC_B1Cd");
      else gd.isc_b2ad_s = f.optional(7, 1, "ISC_B2ad");
      gd.tgd_b1cp_s = f.optional(7, 2, "TGD_B1Cp");
      gd.tgd_b2ap_s = f.optional(7, 3, "TGD_B2ap");
      e.health = static_cast<int>(std::lround(f.required(8, 1, "health")));
      e.iodc = static_cast<int>(std::lround(f.optional(8, 3, "IODC")));
      e.transmission_time_sow = f.optional(9, 0, "transmission time of message", kUnknownTransmissionTime_s);
      e.iode = static_cast<int>(std::lround(f.optional(9, 3, "IODE")));
    }
    if (f.error()) return *f.error();
    // These records carry no week: toe is the instance nearest toc on the BDT week count.
    const int toc_week = e.toc.to_week_tow(TimeScale::kBdt).week;
    e.toe = nearest_instance(GnssTime::from_week_tow(TimeScale::kBdt, toc_week, e.toe_sow), e.toc);
    e.week = e.toe.to_week_tow(TimeScale::kBdt).week;
    e.source = std::move(source);
    data_.kepler.push_back(std::move(e));
    return Ok{};
  }

  Status decode_glonass(const RecordLines& rows, const SatelliteId& sat, size_t epoch_col, size_t orbit_col,
                        std::string source = {}) {
    auto epoch = parse_epoch(rows.index[0], major_ == 2);
    if (!epoch) return epoch.error();
    FieldReader f(text_, rows, epoch_col, orbit_col);
    GlonassEphemeris g;
    g.satellite = sat;
    g.toe = GnssTime::from_calendar(*epoch, TimeScale::kUtc);  // RINEX gives t_b in UTC
    // t_b lies on a 15-minute grid of UTC; some writers put GPST in the field (e.g. 12:15:17 in
    // a 2016 brdc file). Offsets up to 30 s are snapped back to the grid, as RTKLIB does.
    const double second_of_day_s = epoch->hour * 3600.0 + epoch->minute * 60.0 + epoch->second;
    const double off_grid_s = second_of_day_s - std::round(second_of_day_s / kGlonassTbStep_s) * kGlonassTbStep_s;
    if (off_grid_s != 0.0 && std::fabs(off_grid_s) <= kGlonassTbSnapLimit_s) g.toe -= off_grid_s;
    g.minus_tau_n_s = f.required(0, 1, "SV clock bias (-TauN)");
    g.gamma_n = f.required(0, 2, "SV relative frequency bias (+GammaN)");
    // Seconds of the UTC day in RINEX 2, of the UTC week in RINEX 3.02+: reduced to the day.
    // Blank or 0.9999E9: unknown, kept as the marker.
    const double frame_s = f.optional(0, 3, "message frame time", kUnknownTransmissionTime_s);
    if (std::fabs(frame_s) >= kUnknownTransmissionTime_s) {
      g.message_frame_time_s = kUnknownTransmissionTime_s;
    } else {
      g.message_frame_time_s = std::fmod(frame_s, kDay_s);
      if (g.message_frame_time_s < 0.0) g.message_frame_time_s += kDay_s;
    }
    static constexpr std::array<const char*, 3> kAxis = {"X", "Y", "Z"};
    for (size_t axis = 0; axis < 3; ++axis) {
      const std::string a = kAxis[axis];
      g.position_m[static_cast<Eigen::Index>(axis)] = f.required(axis + 1, 0, a) * kKm_m;
      g.velocity_mps[static_cast<Eigen::Index>(axis)] = f.required(axis + 1, 1, a + " velocity") * kKm_m;
      g.acceleration_mps2[static_cast<Eigen::Index>(axis)] = f.required(axis + 1, 2, a + " acceleration") * kKm_m;
    }
    const double health = f.required(1, 3, "health (Bn)");
    const double channel = f.required(2, 3, "frequency number");
    g.age_days = f.optional(3, 3, "age of operation information");
    if (rows.count >= 5) {
      // RINEX 3.05 fourth line: status flags, delta tau_n, URAI, health flags; blank or
      // .999999999999E+09 means unknown.
      auto known = [](std::optional<double> v) { return v && std::fabs(*v) < kUnknownMarker ? v : std::nullopt; };
      const auto status = known(f.maybe(4, 0, "status flags"));
      g.delta_tau_n_s = known(f.maybe(4, 1, "L1/L2 group delay difference"));
      const auto urai = known(f.maybe(4, 2, "URAI"));
      const auto flags = known(f.maybe(4, 3, "health flags"));
      g.status_flags = status ? static_cast<int>(std::lround(*status)) : 0;
      g.urai = urai ? static_cast<int>(std::lround(*urai)) : 15;  // 15: no accuracy given
      g.health_flags = flags ? static_cast<int>(std::lround(*flags)) : 0;
    }
    if (f.error()) return *f.error();
    g.health = static_cast<int>(std::lround(health));
    g.frequency_channel = static_cast<int>(std::lround(channel));
    if (g.frequency_channel < -7 || g.frequency_channel > 13) {
      return text_.error_at(rows.index[2], "field 'frequency number': " + std::to_string(g.frequency_channel) +
                                               " out of range -7..13");
    }
    g.source = source.empty() ? where(rows.index[0]) : std::move(source);
    data_.glonass.push_back(std::move(g));
    return Ok{};
  }

  Status decode_sbas(const RecordLines& rows, const SatelliteId& sat, size_t epoch_col, size_t orbit_col,
                     std::string source = {}) {
    auto epoch = parse_epoch(rows.index[0], major_ == 2);
    if (!epoch) return epoch.error();
    FieldReader f(text_, rows, epoch_col, orbit_col);
    SbasEphemeris s;
    s.satellite = sat;
    s.toe = GnssTime::from_calendar(*epoch, TimeScale::kGpst);
    s.agf0_s = f.required(0, 1, "SV clock bias (aGf0)");
    s.agf1_s_per_s = f.required(0, 2, "SV relative frequency bias (aGf1)");
    s.transmission_time_sow = f.optional(0, 3, "transmission time of message", kUnknownTransmissionTime_s);
    static constexpr std::array<const char*, 3> kAxis = {"X", "Y", "Z"};
    for (size_t axis = 0; axis < 3; ++axis) {
      const std::string a = kAxis[axis];
      s.position_m[static_cast<Eigen::Index>(axis)] = f.required(axis + 1, 0, a) * kKm_m;
      s.velocity_mps[static_cast<Eigen::Index>(axis)] = f.required(axis + 1, 1, a + " velocity") * kKm_m;
      s.acceleration_mps2[static_cast<Eigen::Index>(axis)] = f.required(axis + 1, 2, a + " acceleration") * kKm_m;
    }
    s.health = static_cast<int>(std::lround(f.required(1, 3, "health")));
    s.accuracy_m = f.optional(2, 3, "URA");
    s.iodn = static_cast<int>(std::lround(f.optional(3, 3, "IODN")));
    if (f.error()) return *f.error();
    s.source = source.empty() ? where(rows.index[0]) : std::move(source);
    data_.sbas.push_back(std::move(s));
    return Ok{};
  }

  const TextLines& text_;
  std::string file_name_;
  NavigationData data_;
  int major_ = 0;
  char file_system_ = ' ';
  GnssSystem v2_system_ = GnssSystem::kGps;
  size_t body_start_ = 0;
  std::optional<int> leap_value_;
  // Records skipped as not used, by kind ("EOP records", "EPH GLONASS L1OC"), with their count.
  std::map<std::string, size_t> skipped_;
  bool leap_is_bdt_ = false;
  bool leap_system_blank_ = true;
};

}  // namespace

Result<NavigationData> parse_rinex_nav(const std::string& name, std::string content) {
  const TextLines text(name, std::move(content));
  return NavReader(text).run();
}

Result<NavigationData> read_rinex_nav(const std::filesystem::path& path) {
  auto text = TextLines::read(path);
  if (!text) return text.error();
  return NavReader(*text).run();
}

}  // namespace skytrace::orbits
