// RINEX observation reader: versions 2.10/2.11 (one type list per file, 2-letter codes,
// continuation lines) and 3.0x/4.0x (type lists per system, one line per satellite).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <set>

#include "skytrace/core/signal.hpp"
#include "skytrace/core/text_file.hpp"
#include "skytrace/io/rinex_obs.hpp"

namespace skytrace::io {

char ObservationType::kind() const {
  const char c = !code.empty() ? code[0] : (!rinex2_code.empty() ? rinex2_code[0] : '\0');
  switch (c) {
    case 'C': case 'L': case 'D': case 'S': case 'I': case 'X': return c;
    case 'P': return 'C';  // RINEX 2 P-code pseudorange
    default: return '\0';
  }
}

const SatelliteObservations* ObservationEpoch::find(const SatelliteId& satellite) const {
  for (const auto& s : satellites) {
    if (s.satellite == satellite) return &s;
  }
  return nullptr;
}

std::optional<size_t> ObservationHeader::type_index(GnssSystem system, std::string_view code) const {
  const auto it = observation_types.find(system);
  if (it == observation_types.end()) return std::nullopt;
  for (size_t i = 0; i < it->second.size(); ++i) {
    if (it->second[i].code == code || (!it->second[i].rinex2_code.empty() && it->second[i].rinex2_code == code)) {
      return i;
    }
  }
  return std::nullopt;
}

std::string rinex2_to_rinex3_code(GnssSystem system, std::string_view rinex2_code) {
  if (rinex2_code.size() != 2) return {};
  const char type = rinex2_code[0];
  const char band = rinex2_code[1];
  using G = GnssSystem;
  // Tracking attribute a RINEX 2 observation of this band stands for: RINEX 2.11 section 10.1 and
  // the RINEX 3 tables (GPS L2 under anti-spoofing is semi-codeless P(Y) -> W; Galileo and the
  // modernised signals carry no attribute in RINEX 2 -> X, the combined channels).
  char attribute = '\0';
  if (type == 'P') {
    if (band != '1' && band != '2') return {};
    if (system == G::kGps) attribute = 'W';
    if (system == G::kGlonass) attribute = 'P';
    if (attribute == '\0') return {};
    return std::string{'C', band, attribute};
  }
  if (type != 'C' && type != 'L' && type != 'D' && type != 'S') return {};
  switch (band) {
    case '1':
      if (system == G::kGps || system == G::kGlonass || system == G::kSbas || system == G::kQzss) attribute = 'C';
      if (system == G::kGalileo) attribute = 'X';
      break;
    case '2':
      if (type == 'C') {  // C2 is the civil L2 code
        if (system == G::kGps || system == G::kQzss) attribute = 'X';
        if (system == G::kGlonass) attribute = 'C';
      } else {
        if (system == G::kGps) attribute = 'W';
        if (system == G::kGlonass) attribute = 'P';
        if (system == G::kQzss) attribute = 'X';
      }
      break;
    case '5':
      if (system == G::kGps || system == G::kGalileo || system == G::kSbas || system == G::kQzss) attribute = 'X';
      if (system == G::kNavic) attribute = 'A';  // L5 SPS
      break;
    case '6':
      if (system == G::kGalileo || system == G::kQzss) attribute = 'X';
      if (system == G::kBeiDou) attribute = 'I';  // B3I
      break;
    case '7':
      if (system == G::kGalileo) attribute = 'X';
      if (system == G::kBeiDou) attribute = 'I';  // B2I
      break;
    case '8':
      if (system == G::kGalileo) attribute = 'X';
      break;
    case '9':
      if (system == G::kNavic) attribute = 'A';  // S SPS
      break;
    default: break;
  }
  // BeiDou in RINEX 2.12 files: B1I is band 2 (band 1 as RINEX 3.01 wrote it).
  if (system == G::kBeiDou && (band == '1' || band == '2')) return std::string{type, '2', 'I'};
  if (attribute == '\0') return {};
  return std::string{type, band, attribute};
}

namespace {

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

std::string_view header_label(std::string_view line) { return line.size() > 60 ? trim(line.substr(60)) : std::string_view{}; }

// A RINEX 3/4 observation code: type (C, L, D, S; I from 3.01, X from 3.02), band digit, then an
// attribute letter, blank only for I and X ("I5", "X1").
bool is_rinex3_code(std::string_view code) {
  if (code.size() != 2 && code.size() != 3) return false;
  if (std::string_view("CLDSIX").find(code[0]) == std::string_view::npos) return false;
  if (code[1] < '0' || code[1] > '9') return false;
  if (code.size() == 2) return code[0] == 'I' || code[0] == 'X';
  return code[2] >= 'A' && code[2] <= 'Z';
}

// A RINEX 2 observation type: C, P, L, D, S or T (Transit) and a band digit.
bool is_rinex2_code(std::string_view code) {
  return code.size() == 2 && std::string_view("CPLDST").find(code[0]) != std::string_view::npos && code[1] >= '1' &&
         code[1] <= '9';
}

constexpr std::array<double, 19> kPowersOfTen = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,  1e8, 1e9,
                                                 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18};

// A fixed-point number such as "  23332073.875", ".000" or "-5": integer arithmetic, then one
// correctly rounded division. Returns false for anything else (exponents, stray characters).
bool parse_fixed_point(std::string_view s, double& value) {
  size_t i = 0;
  while (i < s.size() && s[i] == ' ') ++i;
  bool negative = false;
  if (i < s.size() && (s[i] == '-' || s[i] == '+')) negative = s[i++] == '-';
  std::uint64_t mantissa = 0;
  int digits = 0;
  int decimals = -1;
  for (; i < s.size(); ++i) {
    const char c = s[i];
    if (c >= '0' && c <= '9') {
      mantissa = mantissa * 10 + static_cast<std::uint64_t>(c - '0');
      ++digits;
      if (decimals >= 0) ++decimals;
    } else if (c == '.' && decimals < 0) {
      decimals = 0;
    } else {
      break;
    }
  }
  while (i < s.size() && s[i] == ' ') ++i;
  if (i != s.size() || digits == 0 || digits > 18) return false;
  value = static_cast<double>(mantissa) / kPowersOfTen[static_cast<size_t>(std::max(decimals, 0))];
  if (negative) value = -value;
  return true;
}

std::optional<TimeScale> time_system_from_label(std::string_view label) {
  if (label == "GPS") return TimeScale::kGpst;
  // RINEX's GLO time tags are UTC(SU) (RINEX 2.10 8.1.1, 3.0x Table A2 "GLO (=UTC time system)"),
  // not GLONASS system time (UTC(SU) + 3 h).
  if (label == "GLO") return TimeScale::kUtc;
  if (label == "GAL") return TimeScale::kGst;
  if (label == "BDT" || label == "BDS") return TimeScale::kBdt;
  if (label == "QZS") return TimeScale::kQzsst;
  if (label == "IRN") return TimeScale::kIrnwt;
  return std::nullopt;
}

TimeScale default_time_system(const std::optional<GnssSystem>& file_system) {
  if (!file_system) return TimeScale::kGpst;
  switch (*file_system) {
    case GnssSystem::kGlonass: return TimeScale::kUtc;  // GLO
    case GnssSystem::kGalileo: return TimeScale::kGst;
    case GnssSystem::kBeiDou: return TimeScale::kBdt;
    case GnssSystem::kQzss: return TimeScale::kQzsst;
    case GnssSystem::kNavic: return TimeScale::kIrnwt;
    default: return TimeScale::kGpst;
  }
}

// Calendar fields of an epoch as read, seconds split into whole seconds and fraction.
struct EpochText {
  int year = 0, month = 0, day = 0, hour = 0, minute = 0;
  int whole_second = 0;
  double fraction_s = 0.0;
};

class Parser {
 public:
  explicit Parser(const TextLines& lines) : lines_(lines) {}

  Result<ObservationFile> run() {
    if (auto s = parse_header(); !s) return s.error();
    const Status body = major_ == 2 ? parse_body_v2() : parse_body_v3();
    if (!body) return body.error();
    if (major_ == 2) finish_v2_types();
    note_unused_types();
    return std::move(file_);
  }

 private:
  const TextLines& lines_;
  ObservationFile file_;
  size_t index_ = 0;
  int major_ = 3;
  std::vector<std::string> v2_codes_;
  std::set<GnssSystem> v2_systems_;
  std::optional<GnssTime> previous_time_;
  // Per system: divisor of each type (SYS / SCALE FACTOR), empty when none applies.
  std::array<std::vector<double>, 7> divisors_;

  Error error(size_t index, const std::string& message) const { return lines_.error_at(index, message); }

  Result<int> integer_field(size_t index, size_t start, size_t width, const char* what) const {
    const auto text = field(lines_[index], start, width);
    auto v = parse_integer(text);
    if (!v) return error(index, std::string(what) + ": not an integer '" + std::string(text) + "'");
    return static_cast<int>(*v);
  }

  Result<double> double_field(size_t index, size_t start, size_t width, const char* what) const {
    const auto text = field(lines_[index], start, width);
    auto v = parse_fortran_double(text);
    if (!v) return error(index, std::string(what) + ": not a number '" + std::string(text) + "'");
    return *v;
  }

  // "41.7000000" -> 41 and 0.7, the fraction read from its digits (no 41.7 - 41 rounding).
  Result<std::pair<int, double>> seconds_field(size_t index, std::string_view text, const char* what) const {
    text = trim(text);
    const size_t dot = text.find('.');
    const std::string_view whole_text = dot == std::string_view::npos ? text : text.substr(0, dot);
    auto whole = parse_integer(whole_text.empty() ? std::string_view("0") : whole_text);
    double fraction = 0.0;
    bool ok = whole.ok() && !text.empty();
    if (ok && dot != std::string_view::npos) {
      const std::string_view frac_text = text.substr(dot + 1);
      std::uint64_t digits = 0;
      if (frac_text.size() > 15) ok = false;
      for (char c : frac_text) {
        if (c < '0' || c > '9') ok = false;
        digits = digits * 10 + static_cast<std::uint64_t>(c - '0');
      }
      if (ok) fraction = static_cast<double>(digits) / kPowersOfTen[frac_text.size()];
    }
    if (!ok) return error(index, std::string(what) + ": bad seconds '" + std::string(text) + "'");
    return std::pair<int, double>{static_cast<int>(*whole), fraction};
  }

  Result<GnssTime> to_time(size_t index, const EpochText& e) const {
    if (e.month < 1 || e.month > 12 || e.day < 1 || e.day > 31 || e.hour < 0 || e.hour > 23 || e.minute < 0 ||
        e.minute > 59 || e.whole_second < 0 || e.whole_second > 60) {
      return error(index, "epoch date or time out of range");
    }
    const GnssTime whole = GnssTime::from_calendar(
        CalendarTime{e.year, e.month, e.day, e.hour, e.minute, static_cast<double>(e.whole_second)},
        file_.header.time_system);
    return whole + e.fraction_s;
  }

  // ---------------------------------------------------------------- header
  Status parse_header() {
    if (lines_.size() == 0) return make_error(ErrorCode::kParse, lines_.name() + ": empty file");
    auto& h = file_.header;
    const std::string_view first = lines_[0];
    if (header_label(first) == "CRINEX VERS   / TYPE") {
      return make_error(ErrorCode::kUnsupported, lines_.where(0) +
                                                     ": Hatanaka-compressed (CRINEX) file: expand it with crx2rnx first");
    }
    if (header_label(first) != "RINEX VERSION / TYPE") {
      return error(0, "first line is not RINEX VERSION / TYPE");
    }
    auto version = double_field(0, 0, 9, "RINEX VERSION / TYPE version");
    if (!version) return version.error();
    h.version = *version;
    // Range first: a version such as 2E11 has no int (the cast would be undefined).
    if (!(h.version >= 2.0 && h.version < 5.0)) {
      return make_error(ErrorCode::kUnsupported, lines_.where(0) + ": RINEX version " +
                                                     std::string(field(first, 0, 9)) +
                                                     " is not supported (2.x, 3.x and 4.x are read)");
    }
    major_ = static_cast<int>(std::floor(h.version));
    const char type = first.size() > 20 ? first[20] : ' ';
    if (type != 'O' && type != 'o') return error(0, "not an observation file (type '" + std::string(1, type) + "')");
    const char system_char = first.size() > 40 ? first[40] : ' ';
    if (system_char == 'M' || system_char == 'm') {
      h.file_system = std::nullopt;
    } else if (system_char == ' ') {
      h.file_system = GnssSystem::kGps;  // RINEX 2: blank means GPS
    } else {
      auto system = system_from_letter(system_char);
      if (!system) return error(0, "unknown satellite system '" + std::string(1, system_char) + "'");
      h.file_system = *system;
    }

    std::optional<size_t> first_obs_line, last_obs_line;
    std::optional<GnssSystem> types_system;  // list being continued (RINEX 3)
    size_t types_expected = 0;
    size_t v2_expected = 0;
    std::optional<size_t> slots_expected;
    PhaseShift* open_shift = nullptr;  // phase shift whose satellite list continues
    size_t shift_satellites_expected = 0;
    std::optional<GnssSystem> scale_system;
    int scale_factor = 1;
    size_t scale_expected = 0;
    bool have_program = false;

    size_t i = 1;
    for (; i < lines_.size(); ++i) {
      const std::string_view line = lines_[i];
      const std::string_view label = header_label(line);
      const std::string_view content = line.substr(0, std::min<size_t>(line.size(), 60));
      if (label != "SYS / PHASE SHIFT") open_shift = nullptr;
      if (label == "END OF HEADER") break;
      if (label == "PGM / RUN BY / DATE") {
        if (have_program) {
          h.other_records.emplace_back(line);
        } else {
          h.program = field(line, 0, 20);
          h.run_by = field(line, 20, 20);
          h.date = field(line, 40, 20);
          have_program = true;
        }
      } else if (label == "COMMENT") {
        std::string_view c = content;
        while (!c.empty() && c.back() == ' ') c.remove_suffix(1);
        h.comments.emplace_back(c);
      } else if (label == "MARKER NAME") {
        h.marker_name = field(line, 0, 60);
      } else if (label == "MARKER NUMBER") {
        h.marker_number = field(line, 0, 20);
      } else if (label == "MARKER TYPE") {
        h.marker_type = field(line, 0, 20);
      } else if (label == "OBSERVER / AGENCY") {
        h.observer = field(line, 0, 20);
        h.agency = field(line, 20, 40);
      } else if (label == "REC # / TYPE / VERS") {
        h.receiver_number = field(line, 0, 20);
        h.receiver_type = field(line, 20, 20);
        h.receiver_version = field(line, 40, 20);
      } else if (label == "ANT # / TYPE") {
        h.antenna_number = field(line, 0, 20);
        h.antenna_type = field(line, 20, 20);
      } else if (label == "APPROX POSITION XYZ" || label == "ANTENNA: DELTA H/E/N") {
        std::array<double, 3> v{};
        for (size_t k = 0; k < 3; ++k) {
          auto x = double_field(i, 14 * k, 14, label == "APPROX POSITION XYZ" ? "APPROX POSITION XYZ"
                                                                              : "ANTENNA: DELTA H/E/N");
          if (!x) return x.error();
          v[k] = *x;
        }
        if (label == "APPROX POSITION XYZ") {
          h.approx_position_ecef_m = v;
        } else {
          h.antenna_delta_hen_m = v;
        }
      } else if (label == "SYS / # / OBS TYPES") {
        if (line[0] != ' ') {
          auto system = system_from_letter(line[0]);
          if (!system) return error(i, "SYS / # / OBS TYPES: unknown system '" + std::string(1, line[0]) + "'");
          auto n = integer_field(i, 3, 3, "SYS / # / OBS TYPES count");
          if (!n) return n.error();
          types_system = *system;
          types_expected = static_cast<size_t>(*n);
          h.observation_types[*system].clear();
        } else if (!types_system) {
          return error(i, "SYS / # / OBS TYPES continuation without a system");
        }
        auto& list = h.observation_types[*types_system];
        for (size_t k = 0; k < 13 && list.size() < types_expected; ++k) {
          const auto code = field(line, 7 + 4 * k, 3);
          if (code.empty()) break;
          if (!is_rinex3_code(code)) {
            return error(i, "SYS / # / OBS TYPES: bad code '" + std::string(code) +
                                "' (expected type C, L, D, S, I or X, a band digit and an attribute letter, "
                                "e.g. C1C; blank attribute only for I and X, e.g. X1)");
          }
          std::string text(code);
          // BeiDou B1I in band 1 ("C1I", 3.01 and 3.02 drafts, as RTKLIB reads them): band 2 from 3.02
          // on; band 1 means B1C only from 3.04.
          if (*types_system == GnssSystem::kBeiDou && h.version < 3.035 && text.size() == 3 && text[1] == '1' &&
              (text[2] == 'I' || text[2] == 'Q' || text[2] == 'X')) {
            text[1] = '2';
          }
          list.push_back(ObservationType{std::move(text), {}});
        }
      } else if (label == "# / TYPES OF OBSERV") {
        const auto count_text = field(line, 0, 6);
        if (!count_text.empty()) {
          auto n = integer_field(i, 0, 6, "# / TYPES OF OBSERV count");
          if (!n) return n.error();
          v2_expected = static_cast<size_t>(*n);
          v2_codes_.clear();
        }
        for (size_t k = 0; k < 9 && v2_codes_.size() < v2_expected; ++k) {
          const auto code = field(line, 6 + 6 * k + 4, 2);
          if (code.empty()) break;
          if (!is_rinex2_code(code)) {
            return error(i, "# / TYPES OF OBSERV: bad type '" + std::string(code) +
                                "' (expected C, P, L, D, S or T and a band digit, e.g. L1, C5)");
          }
          v2_codes_.emplace_back(code);
        }
      } else if (label == "SIGNAL STRENGTH UNIT") {
        h.signal_strength_unit = field(line, 0, 20);
      } else if (label == "INTERVAL") {
        auto v = double_field(i, 0, 10, "INTERVAL");
        if (!v) return v.error();
        h.interval_s = *v;
      } else if (label == "TIME OF FIRST OBS") {
        first_obs_line = i;
      } else if (label == "TIME OF LAST OBS") {
        last_obs_line = i;
      } else if (label == "RCV CLOCK OFFS APPL") {
        if (!field(line, 0, 6).empty()) {
          auto v = integer_field(i, 0, 6, "RCV CLOCK OFFS APPL");
          if (!v) return v.error();
          h.receiver_clock_offset_applied = *v;
        }
      } else if (label == "LEAP SECONDS") {
        if (!field(line, 0, 6).empty()) {
          auto v = integer_field(i, 0, 6, "LEAP SECONDS");
          if (!v) return v.error();
          h.leap_seconds = *v;
        }
      } else if (label == "GLONASS SLOT / FRQ #") {
        if (!field(line, 0, 3).empty()) {
          auto n = integer_field(i, 0, 3, "GLONASS SLOT / FRQ # count");
          if (!n) return n.error();
          slots_expected = static_cast<size_t>(*n);
        }
        for (size_t k = 0; k < 8; ++k) {
          const auto sat_text = field(line, 4 + 7 * k, 3);
          if (sat_text.empty()) break;
          // The count rules: text after the announced satellites is left alone, with a note
          // (GNSS-SDR 0.0.17 writes "  0 R 0  0" when it lists none).
          if (slots_expected && h.glonass_slots.size() >= *slots_expected) {
            file_.warnings.push_back(lines_.where(i) + ": GLONASS SLOT / FRQ #: text after the " +
                                     std::to_string(*slots_expected) +
                                     " satellites the count announces ignored");
            break;
          }
          auto sat = SatelliteId::parse(sat_text);
          if (!sat || sat->system != GnssSystem::kGlonass) {
            return error(i, "GLONASS SLOT / FRQ #: bad satellite '" + std::string(sat_text) + "'");
          }
          auto k_channel = integer_field(i, 8 + 7 * k, 2, "GLONASS SLOT / FRQ # channel");
          if (!k_channel) return k_channel.error();
          h.glonass_slots.push_back(GlonassSlotFrequency{sat->number, *k_channel});
        }
      } else if (label == "GLONASS COD/PHS/BIS") {
        for (size_t k = 0; k < 4; ++k) {
          const auto code = field(line, 1 + 13 * k, 3);
          if (code.empty()) continue;
          GlonassCodePhaseBias bias{std::string(code), std::nullopt};
          if (!field(line, 5 + 13 * k, 8).empty()) {
            auto v = double_field(i, 5 + 13 * k, 8, "GLONASS COD/PHS/BIS");
            if (!v) return v.error();
            bias.bias_m = *v;
          }
          h.glonass_code_phase_biases.push_back(bias);
        }
      } else if (label == "SYS / PHASE SHIFT") {
        if (line[0] != ' ') {
          auto system = system_from_letter(line[0]);
          if (!system) return error(i, "SYS / PHASE SHIFT: unknown system '" + std::string(1, line[0]) + "'");
          PhaseShift shift{*system, std::string(field(line, 2, 3)), std::nullopt, {}};
          if (!field(line, 6, 8).empty()) {
            auto v = double_field(i, 6, 8, "SYS / PHASE SHIFT correction");
            if (!v) return v.error();
            shift.shift_cycles = *v;
          }
          shift_satellites_expected = 0;
          if (!field(line, 16, 2).empty()) {
            auto n = integer_field(i, 16, 2, "SYS / PHASE SHIFT satellite count");
            if (!n) return n.error();
            shift_satellites_expected = static_cast<size_t>(*n);
          }
          h.phase_shifts.push_back(std::move(shift));
          open_shift = &h.phase_shifts.back();
        } else if (open_shift == nullptr) {
          return error(i, "SYS / PHASE SHIFT continuation without a preceding record");
        }
        for (size_t k = 0; k < 10 && open_shift->satellites.size() < shift_satellites_expected; ++k) {
          const auto sat_text = field(line, 19 + 4 * k, 3);
          if (sat_text.empty()) break;
          auto sat = SatelliteId::parse(sat_text);
          if (!sat) return error(i, "SYS / PHASE SHIFT: " + sat.error().message);
          open_shift->satellites.push_back(*sat);
        }
      } else if (label == "SYS / SCALE FACTOR") {
        if (line[0] != ' ') {
          auto system = system_from_letter(line[0]);
          if (!system) return error(i, "SYS / SCALE FACTOR: unknown system '" + std::string(1, line[0]) + "'");
          auto factor = integer_field(i, 2, 4, "SYS / SCALE FACTOR factor");
          if (!factor) return factor.error();
          if (*factor != 1 && *factor != 10 && *factor != 100 && *factor != 1000) {
            return error(i, "SYS / SCALE FACTOR must be 1, 10, 100 or 1000");
          }
          scale_system = *system;
          scale_factor = *factor;
          scale_expected = 0;
          if (!field(line, 8, 2).empty()) {
            auto n = integer_field(i, 8, 2, "SYS / SCALE FACTOR count");
            if (!n) return n.error();
            scale_expected = static_cast<size_t>(*n);
          }
          if (scale_expected == 0) h.scale_factors[*system][""] = scale_factor;  // every type
        } else if (!scale_system) {
          return error(i, "SYS / SCALE FACTOR continuation without a system");
        }
        auto& factors = h.scale_factors[*scale_system];
        for (size_t k = 0; k < 12; ++k) {
          const auto code = field(line, 11 + 4 * k, 3);
          if (code.empty()) break;
          factors[std::string(code)] = scale_factor;
        }
      } else if (label.empty() && trim(line).empty()) {
        continue;  // stray blank line
      } else {
        h.other_records.emplace_back(line);
      }
    }
    if (i >= lines_.size()) return make_error(ErrorCode::kParse, lines_.name() + ": no END OF HEADER");
    index_ = i + 1;

    if (slots_expected && *slots_expected != h.glonass_slots.size()) {
      return error(i, "GLONASS SLOT / FRQ # announces " + std::to_string(*slots_expected) + " satellites but lists " +
                          std::to_string(h.glonass_slots.size()));
    }
    if (major_ == 2) {
      if (v2_codes_.empty()) return error(i, "no # / TYPES OF OBSERV record");
      if (v2_codes_.size() != v2_expected) return error(i, "# / TYPES OF OBSERV lists fewer types than announced");
    } else {
      if (h.observation_types.empty()) return error(i, "no SYS / # / OBS TYPES record");
      if (types_system && h.observation_types[*types_system].size() != types_expected) {
        return error(i, "SYS / # / OBS TYPES of " + std::string(system_name(*types_system)) +
                            " lists fewer types than announced");
      }
      for (const auto& [system, types] : h.observation_types) {
        std::vector<double> divisors(types.size(), 1.0);
        bool any = false;
        if (const auto it = h.scale_factors.find(system); it != h.scale_factors.end()) {
          for (size_t k = 0; k < types.size(); ++k) {
            auto f = it->second.find(types[k].code);
            if (f == it->second.end()) f = it->second.find("");
            if (f != it->second.end() && f->second != 1) {
              divisors[k] = f->second;
              any = true;
            }
          }
        }
        if (any) divisors_[static_cast<size_t>(system)] = std::move(divisors);
      }
    }

    // Times last: their own time-system field decides how the calendar fields are read.
    h.time_system = default_time_system(h.file_system);
    if (first_obs_line) {
      const auto label = field(lines_[*first_obs_line], 48, 3);
      if (!label.empty()) {
        auto ts = time_system_from_label(label);
        if (!ts) return error(*first_obs_line, "TIME OF FIRST OBS: unknown time system '" + std::string(label) + "'");
        h.time_system = *ts;
      }
      auto t = header_time(*first_obs_line);
      if (!t) return t.error();
      h.time_of_first_obs = *t;
    } else if (major_ >= 3) {
      return error(i, "no TIME OF FIRST OBS record");
    }
    if (last_obs_line) {
      auto t = header_time(*last_obs_line);
      if (!t) return t.error();
      h.time_of_last_obs = *t;
    }
    return Ok{};
  }

  Result<GnssTime> header_time(size_t index) const {
    EpochText e;
    int* targets[] = {&e.year, &e.month, &e.day, &e.hour, &e.minute};
    for (size_t k = 0; k < 5; ++k) {
      auto v = integer_field(index, 6 * k, 6, "time of observation");
      if (!v) return v.error();
      *targets[k] = *v;
    }
    auto s = seconds_field(index, field(lines_[index], 30, 13), "time of observation");
    if (!s) return s.error();
    e.whole_second = s->first;
    e.fraction_s = s->second;
    return to_time(index, e);
  }

  // ---------------------------------------------------------------- observations
  // One F14.3 value with its LLI and SSI columns; a line shorter than the field means blank.
  Status parse_value(size_t index, std::string_view line, size_t start, const SatelliteId& sat, size_t type_index,
                     double divisor, ObservationValue& out) const {
    out = ObservationValue{};
    if (start >= line.size()) return Ok{};
    const std::string_view text = line.substr(start, 14);
    if (trim(text).empty()) {
      out.value = std::nullopt;
    } else {
      double v = 0.0;
      if (!parse_fixed_point(text, v)) {
        auto slow = parse_fortran_double(text);
        if (!slow) {
          return error(index, sat.to_string() + " value " + std::to_string(type_index + 1) + ": not a number '" +
                                  std::string(trim(text)) + "'");
        }
        // Exponent forms ("1e308") read, but the field is F14.3: anything it cannot hold is malformed.
        constexpr double kF14_3Limit = 1e10;
        if (!(std::fabs(*slow) < kF14_3Limit)) {
          return error(index, sat.to_string() + " value " + std::to_string(type_index + 1) + ": '" +
                                  std::string(trim(text)) + "' does not fit the F14.3 field");
        }
        v = *slow;
      }
      out.value = v / divisor;
    }
    for (size_t k = 0; k < 2; ++k) {
      const size_t pos = start + 14 + k;
      if (pos >= line.size()) break;
      const char c = line[pos];
      if (c == ' ') continue;
      if (c < '0' || c > '9') {
        return error(index, sat.to_string() + " value " + std::to_string(type_index + 1) + ": bad " +
                                (k == 0 ? "LLI" : "SSI") + " '" + std::string(1, c) + "'");
      }
      (k == 0 ? out.lli : out.ssi) = static_cast<std::uint8_t>(c - '0');
    }
    return Ok{};
  }

  Status check_event_records(const ObservationEpoch& epoch, size_t first_record_line) const {
    for (size_t k = 0; k < epoch.event_records.size(); ++k) {
      const auto label = header_label(epoch.event_records[k]);
      if (label == "SYS / # / OBS TYPES" || label == "# / TYPES OF OBSERV" || label == "SYS / SCALE FACTOR") {
        return make_error(ErrorCode::kUnsupported,
                          lines_.where(first_record_line + k) + ": " + std::string(label) +
                              " changed inside the file is not supported");
      }
    }
    return Ok{};
  }

  Result<EpochFlag> flag_field(size_t index, size_t column) const {
    const auto text = field(lines_[index], column, 1);
    if (text.empty()) return EpochFlag::kOk;
    if (text[0] < '0' || text[0] > '6') return error(index, "epoch flag must be 0..6");
    return static_cast<EpochFlag>(text[0] - '0');
  }

  Status parse_body_v3() {
    auto& epochs = file_.epochs;
    while (index_ < lines_.size()) {
      const size_t epoch_line = index_;
      const std::string_view line = lines_[index_++];
      if (trim(line).empty()) continue;
      if (line[0] != '>') return error(epoch_line, "expected an epoch record starting with '>'");
      ObservationEpoch epoch;
      auto flag = flag_field(epoch_line, 31);
      if (!flag) return flag.error();
      epoch.flag = *flag;
      auto count = integer_field(epoch_line, 32, 3, "number of satellites");
      if (!count) return count.error();
      if (*count < 0) return error(epoch_line, "negative number of satellites");
      if (auto t = epoch_time_v3(epoch_line, is_event_flag(epoch.flag)); t) {
        epoch.time = *t;
      } else {
        return t.error();
      }
      if (!field(line, 41, 15).empty()) {
        auto clock = double_field(epoch_line, 41, 15, "receiver clock offset");
        if (!clock) return clock.error();
        epoch.receiver_clock_offset_s = *clock;
      }
      const size_t n = static_cast<size_t>(*count);
      if (index_ + n > lines_.size()) return error(epoch_line, "file ends inside the epoch");
      if (is_event_flag(epoch.flag)) {
        for (size_t k = 0; k < n; ++k) epoch.event_records.emplace_back(lines_[index_ + k]);
        if (auto s = check_event_records(epoch, index_); !s) return s;
        index_ += n;
      } else {
        epoch.satellites.resize(n);
        for (size_t k = 0; k < n; ++k) {
          const size_t li = index_++;
          const std::string_view sat_line = lines_[li];
          auto sat = SatelliteId::parse(sat_line.substr(0, std::min<size_t>(3, sat_line.size())));
          if (!sat) return error(li, sat.error().message);
          const auto it = file_.header.observation_types.find(sat->system);
          if (it == file_.header.observation_types.end()) {
            return error(li, sat->to_string() + ": no SYS / # / OBS TYPES for " + std::string(system_name(sat->system)));
          }
          const size_t ntypes = it->second.size();
          if (sat_line.size() > 3 + 16 * ntypes && !trim(sat_line.substr(3 + 16 * ntypes)).empty()) {
            return error(li, sat->to_string() + ": more values than the " + std::to_string(ntypes) +
                                 " observation types of its system");
          }
          auto& record = epoch.satellites[k];
          record.satellite = *sat;
          record.values.resize(ntypes);
          const auto& divisors = divisors_[static_cast<size_t>(sat->system)];
          for (size_t t = 0; t < ntypes; ++t) {
            if (auto s = parse_value(li, sat_line, 3 + 16 * t, *sat, t, divisors.empty() ? 1.0 : divisors[t],
                                     record.values[t]);
                !s) {
              return s;
            }
          }
        }
      }
      previous_time_ = epoch.time;
      epochs.push_back(std::move(epoch));
    }
    return Ok{};
  }

  Result<GnssTime> epoch_time_v3(size_t index, bool event) const {
    const std::string_view line = lines_[index];
    if (event && field(line, 2, 4).empty()) {  // events may leave the epoch blank
      return previous_time_.value_or(file_.header.time_of_first_obs.value_or(GnssTime{}));
    }
    EpochText e;
    const std::pair<size_t, size_t> columns[] = {{2, 4}, {7, 2}, {10, 2}, {13, 2}, {16, 2}};
    int* targets[] = {&e.year, &e.month, &e.day, &e.hour, &e.minute};
    for (size_t k = 0; k < 5; ++k) {
      auto v = integer_field(index, columns[k].first, columns[k].second, "epoch");
      if (!v) return v.error();
      *targets[k] = *v;
    }
    auto s = seconds_field(index, field(line, 18, 11), "epoch");
    if (!s) return s.error();
    e.whole_second = s->first;
    e.fraction_s = s->second;
    return to_time(index, e);
  }

  Result<GnssTime> epoch_time_v2(size_t index, bool event) const {
    const std::string_view line = lines_[index];
    if (event && field(line, 1, 2).empty()) {
      return previous_time_.value_or(file_.header.time_of_first_obs.value_or(GnssTime{}));
    }
    EpochText e;
    int* targets[] = {&e.year, &e.month, &e.day, &e.hour, &e.minute};
    for (size_t k = 0; k < 5; ++k) {
      auto v = integer_field(index, 1 + 3 * k, 2, "epoch");
      if (!v) return v.error();
      *targets[k] = *v;
    }
    e.year += e.year < 80 ? 2000 : 1900;  // RINEX 2 two-digit years: 1980-2079
    auto s = seconds_field(index, field(line, 15, 11), "epoch");
    if (!s) return s.error();
    e.whole_second = s->first;
    e.fraction_s = s->second;
    return to_time(index, e);
  }

  Result<SatelliteId> satellite_v2(size_t index, std::string_view text) const {
    std::string id(text);
    if (id.size() != 3) return error(index, "truncated satellite list");
    if (id[0] == ' ') id[0] = 'G';  // RINEX 2: blank system means GPS
    auto sat = SatelliteId::parse(id);
    if (!sat) return error(index, sat.error().message);
    return *sat;
  }

  Status parse_body_v2() {
    auto& epochs = file_.epochs;
    const size_t ntypes = v2_codes_.size();
    const size_t lines_per_satellite = (ntypes + 4) / 5;
    while (index_ < lines_.size()) {
      const size_t epoch_line = index_;
      const std::string_view line = lines_[index_++];
      if (trim(line).empty()) continue;
      ObservationEpoch epoch;
      auto flag = flag_field(epoch_line, 28);
      if (!flag) return flag.error();
      epoch.flag = *flag;
      auto count = integer_field(epoch_line, 29, 3, "number of satellites");
      if (!count) return count.error();
      if (*count < 0) return error(epoch_line, "negative number of satellites");
      auto epoch_time = epoch_time_v2(epoch_line, is_event_flag(epoch.flag));
      if (!epoch_time) return epoch_time.error();
      epoch.time = *epoch_time;
      const size_t n = static_cast<size_t>(*count);
      if (is_event_flag(epoch.flag)) {
        if (index_ + n > lines_.size()) return error(epoch_line, "file ends inside the event");
        for (size_t k = 0; k < n; ++k) epoch.event_records.emplace_back(lines_[index_ + k]);
        if (auto s = check_event_records(epoch, index_); !s) return s;
        index_ += n;
        previous_time_ = epoch.time;
        epochs.push_back(std::move(epoch));
        continue;
      }
      if (!field(line, 68, 12).empty()) {
        auto clock = double_field(epoch_line, 68, 12, "receiver clock offset");
        if (!clock) return clock.error();
        epoch.receiver_clock_offset_s = *clock;
      }
      // Satellite list: 12 per line, continued from column 33 of the following lines.
      epoch.satellites.resize(n);
      size_t list_line = epoch_line;
      for (size_t k = 0; k < n; ++k) {
        if (k > 0 && k % 12 == 0) {
          list_line = index_++;
          if (list_line >= lines_.size()) return error(epoch_line, "file ends inside the satellite list");
        }
        const std::string_view l = lines_[list_line];
        const size_t column = 32 + 3 * (k % 12);
        if (column + 3 > l.size()) return error(list_line, "satellite list shorter than announced");
        auto sat = satellite_v2(list_line, l.substr(column, 3));
        if (!sat) return sat.error();
        epoch.satellites[k].satellite = *sat;
        v2_systems_.insert(sat->system);
      }
      if (index_ + n * lines_per_satellite > lines_.size()) return error(epoch_line, "file ends inside the epoch");
      for (size_t k = 0; k < n; ++k) {
        auto& record = epoch.satellites[k];
        record.values.resize(ntypes);
        for (size_t t = 0; t < ntypes; ++t) {
          const size_t li = index_ + t / 5;
          if (auto s = parse_value(li, lines_[li], 16 * (t % 5), record.satellite, t, 1.0, record.values[t]); !s) {
            return s;
          }
        }
        for (size_t r = 0; r < lines_per_satellite; ++r) {
          const std::string_view l = lines_[index_ + r];
          if (l.size() > 80 && !trim(l.substr(80)).empty()) {
            return error(index_ + r, record.satellite.to_string() + ": observation line longer than 5 values");
          }
        }
        index_ += lines_per_satellite;
      }
      previous_time_ = epoch.time;
      epochs.push_back(std::move(epoch));
    }
    return Ok{};
  }

  // One note for the file naming the types it defines that skytrace does not use: channel numbers,
  // ionosphere pseudo-observables, codes of signals outside the catalogue.
  void note_unused_types() {
    std::string list;
    for (const auto& [system, types] : file_.header.observation_types) {
      std::string codes;
      for (const auto& type : types) {
        const bool used = type.code.size() == 3 && std::string_view("CLDS").find(type.code[0]) != std::string_view::npos &&
                          Signal::from_code(system, std::string_view(type.code).substr(1)).ok();
        if (used) continue;
        const std::string& shown = type.code.empty() ? type.rinex2_code : type.code;
        if (codes.find(shown) == std::string::npos) codes += " " + shown;
      }
      if (!codes.empty()) list += std::string(list.empty() ? "" : ";") + " " + system_letter(system) + ":" + codes;
    }
    if (list.empty()) return;
    file_.warnings.push_back(lines_.name() + ": observation types read but not used (channel numbers, ionosphere "
                             "pseudo-observables, signals outside the catalogue or without a RINEX 3 code):" + list);
  }

  // RINEX 2 lists one set of types for all systems: give each system present its mapped copy.
  void finish_v2_types() {
    auto& h = file_.header;
    if (v2_systems_.empty()) v2_systems_.insert(h.file_system.value_or(GnssSystem::kGps));
    for (GnssSystem system : v2_systems_) {
      auto& list = h.observation_types[system];
      list.clear();
      for (const auto& code : v2_codes_) list.push_back(ObservationType{rinex2_to_rinex3_code(system, code), code});
    }
  }
};

}  // namespace

Result<ObservationFile> parse_rinex_obs(std::string name, std::string content) {
  const TextLines lines(std::move(name), std::move(content));
  return Parser(lines).run();
}

Result<ObservationFile> read_rinex_obs(const std::filesystem::path& path) {
  auto lines = TextLines::read(path);
  if (!lines) return lines.error();
  return Parser(*lines).run();
}

}  // namespace skytrace::io
