// RINEX 3.04 / 4.00 observation writer: a streaming body with hand-made fixed-point formatting
// (the hot path of long simulations) and an atomic final file with the header written last (or first,
// when the epochs' span is known beforehand and the epochs confirm it).
#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <random>
#include <system_error>

#include "skytrace/io/rinex_obs.hpp"

#include "skytrace/core/decimal_text.hpp"
#include "skytrace/core/output_file.hpp"

namespace skytrace::io {

namespace detail {

namespace {
// "00" .. "99": two digits per division halves the work of the integer part.
constexpr const char* kDigitPairs = decimal_text_detail::kPairs;
}  // namespace

bool format_f14_3(double value, char* out) {
  // Largest magnitude with a leading blank (positive) or sign (negative) in 14 columns.
  constexpr double kLimit = 999999999.9995;
  if (!(value < kLimit && value > -kLimit)) return false;  // also rejects NaN
  const bool negative = value < 0.0;
  // Round half away from zero to 1e-3 (as printf does except at exact binary ties).
  const auto milli = static_cast<std::uint64_t>((negative ? -value : value) * 1000.0 + 0.5);
  if (milli > 999999999999ULL) return false;  // rounding at the limit
  auto whole = static_cast<std::uint32_t>(milli / 1000);  // <= 999999999
  const auto frac = static_cast<std::uint32_t>(milli % 1000);
  char* p = out + 14;
  p[-1] = static_cast<char>('0' + frac % 10);
  p[-2] = kDigitPairs[2 * (frac / 10) + 1];
  p[-3] = kDigitPairs[2 * (frac / 10)];
  p[-4] = '.';
  p -= 4;
  while (whole >= 100) {
    const std::uint32_t pair = whole % 100;
    whole /= 100;
    *--p = kDigitPairs[2 * pair + 1];
    *--p = kDigitPairs[2 * pair];
  }
  if (whole >= 10) {
    *--p = kDigitPairs[2 * whole + 1];
    *--p = kDigitPairs[2 * whole];
  } else {
    *--p = static_cast<char>('0' + whole);
  }
  if (negative && milli != 0) *--p = '-';  // no "-0.000"
  while (p > out) *--p = ' ';
  return true;
}

}  // namespace detail

namespace {

constexpr int kEpochDecimals = 7;  // RINEX epoch resolution 1e-7 s (F11.7 / F13.7)

// An epoch split into the fields of a RINEX epoch line, seconds in 1e-7 s ticks.
struct EpochFields {
  int year = 0, month = 0, day = 0, hour = 0, minute = 0;
  long long second_ticks = 0;
};

EpochFields epoch_fields(const GnssTime& t, TimeScale scale) {
  // Rounded to 1e-7 s on the continuous timeline first, then split (exact integers), so that
  // 59.99999996 s carries into the next minute, hour, day, month and year; second 60 only inside a
  // real leap second of UTC (GLO).
  const RoundedCalendarTime c = t.to_rounded_calendar(scale, kEpochDecimals);
  return EpochFields{c.year, c.month, c.day, c.hour, c.minute,
                     static_cast<long long>(c.second) * 10000000LL + static_cast<long long>(c.fraction)};
}

std::optional<std::string_view> rinex_time_system_label(TimeScale scale) {
  switch (scale) {
    case TimeScale::kGpst: return "GPS";
    case TimeScale::kUtc: return "GLO";  // RINEX's GLO time tags are UTC(SU)
    case TimeScale::kGst: return "GAL";
    case TimeScale::kBdt: return "BDT";
    case TimeScale::kQzsst: return "QZS";
    case TimeScale::kIrnwt: return "IRN";
    default: return std::nullopt;  // GLONASST (UTC + 3 h) and TAI are not RINEX observation time systems
  }
}

bool is_version(double version, double wanted) { return std::fabs(version - wanted) < 1e-6; }

// Header text field: control characters become blanks, then cut/padded to `width`.
std::string text_field(std::string_view text, size_t width) {
  std::string s(text.substr(0, std::min(text.size(), width)));
  for (char& c : s) {
    if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) >= 0x7f) c = ' ';
  }
  s.resize(width, ' ');
  return s;
}

void add_header_line(std::string& out, std::string content, std::string_view label) {
  content.resize(60, ' ');
  out += content;
  out += label;
  out += '\n';
}

std::string format_epoch_record(const EpochFields& f, std::string_view time_system) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%6d%6d%6d%6d%6d%5lld.%07lld     %.3s", f.year, f.month, f.day, f.hour,
                f.minute, f.second_ticks / 10000000LL, f.second_ticks % 10000000LL, time_system.data());
  return buf;
}

std::string current_utc_date() {
  const std::time_t now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm utc{};
  gmtime_r(&now, &utc);
  char buf[80];
  std::snprintf(buf, sizeof buf, "%04d%02d%02d %02d%02d%02d UTC", utc.tm_year + 1900, utc.tm_mon + 1,
                utc.tm_mday, utc.tm_hour, utc.tm_min, utc.tm_sec);
  return buf;
}

Status check_code(GnssSystem system, const std::string& code) {
  const auto fail = [&](const std::string& why) -> Status {
    return make_error(ErrorCode::kInvalidArgument, std::string("observation type '") + code + "' of " +
                                                       std::string(system_name(system)) + ": " + why);
  };
  if (code.size() != 3) return fail("expected 3 characters such as C1C");
  if (std::strchr("CLDSX", code[0]) == nullptr) return fail("type letter must be C, L, D, S or X");
  if (code[1] < '0' || code[1] > '9') return fail("band must be a digit");
  if (!std::isalnum(static_cast<unsigned char>(code[2]))) return fail("attribute must be a letter");
  return Ok{};
}

Status validate_header(const ObservationHeader& h) {
  const auto invalid = [](const std::string& why) -> Status {
    return make_error(ErrorCode::kInvalidArgument, "RINEX observation header: " + why);
  };
  if (!is_version(h.version, 3.04) && !is_version(h.version, 4.00)) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.2f", h.version);
    return make_error(ErrorCode::kUnsupported,
                      std::string("RINEX observation writer: version ") + buf + " (use 3.04 or 4.00)");
  }
  if (h.observation_types.empty()) return invalid("no SYS / # / OBS TYPES");
  for (const auto& [system, types] : h.observation_types) {
    if (types.empty()) return invalid(std::string(system_name(system)) + " has no observation types");
    if (types.size() > 999) return invalid(std::string(system_name(system)) + " has more than 999 types");
    for (size_t i = 0; i < types.size(); ++i) {
      if (auto ok = check_code(system, types[i].code); !ok) return ok;
      for (size_t j = 0; j < i; ++j) {
        if (types[j].code == types[i].code) {
          return invalid("observation type " + types[i].code + " listed twice for " + std::string(system_name(system)));
        }
      }
    }
  }
  if (!rinex_time_system_label(h.time_system)) {
    return invalid(std::string("time system ") + std::string(to_string(h.time_system)) +
                   " is not allowed in observation files (GPS, GLO, GAL, BDT, QZS, IRN)");
  }
  if (h.approx_position_ecef_m) {
    for (double v : *h.approx_position_ecef_m) {
      if (!std::isfinite(v) || std::fabs(v) >= 1e9) return invalid("APPROX POSITION XYZ out of range");
    }
  }
  for (double v : h.antenna_delta_hen_m) {
    if (!std::isfinite(v) || std::fabs(v) >= 1e9) return invalid("ANTENNA: DELTA H/E/N out of range");
  }
  if (h.interval_s && !(*h.interval_s > 0.0 && *h.interval_s < 1e6)) return invalid("INTERVAL out of range");
  for (const auto& s : h.glonass_slots) {
    if (s.slot < 1 || s.slot > 99 || s.channel < -7 || s.channel > 13) {
      return invalid("GLONASS slot " + std::to_string(s.slot) + " / channel " + std::to_string(s.channel) +
                     " out of range");
    }
  }
  for (const auto& b : h.glonass_code_phase_biases) {
    if (b.code.size() != 3) return invalid("GLONASS COD/PHS/BIS code '" + b.code + "' must have 3 characters");
    if (b.bias_m && !(std::fabs(*b.bias_m) < 9999.0)) return invalid("GLONASS COD/PHS/BIS bias out of range");
  }
  if (h.glonass_code_phase_biases.size() > 4) return invalid("more than 4 GLONASS COD/PHS/BIS entries");
  for (const auto& p : h.phase_shifts) {
    if (!p.code.empty() && (p.code.size() != 3 || p.code[0] != 'L')) {
      return invalid("SYS / PHASE SHIFT code '" + p.code + "' is not a phase code");
    }
    if (p.shift_cycles && !(std::fabs(*p.shift_cycles) < 99.0)) return invalid("SYS / PHASE SHIFT out of range");
    if (p.satellites.size() > 99) return invalid("SYS / PHASE SHIFT lists more than 99 satellites");
    for (const auto& sat : p.satellites) {
      if (sat.system != p.system) return invalid("SYS / PHASE SHIFT lists " + sat.to_string() + " under another system");
    }
  }
  if (h.leap_seconds && (*h.leap_seconds < 0 || *h.leap_seconds > 999)) return invalid("LEAP SECONDS out of range");
  return Ok{};
}

std::string format_header(const ObservationHeader& h, const GnssTime& first, const std::optional<GnssTime>& last,
                          const std::optional<double>& interval_s) {
  const bool v3 = is_version(h.version, 3.04);
  std::string out;
  out.reserve(4096);
  char buf[128];

  const char system_char = h.observation_types.size() == 1 ? system_letter(h.observation_types.begin()->first) : 'M';
  std::snprintf(buf, sizeof buf, "%9.2f%11s%-20s%c", h.version, "", "OBSERVATION DATA", system_char);
  add_header_line(out, buf, "RINEX VERSION / TYPE");
  add_header_line(out,
                  text_field(h.program.empty() ? "skytrace" : h.program, 20) + text_field(h.run_by, 20) +
                      text_field(h.date.empty() ? current_utc_date() : h.date, 20),
                  "PGM / RUN BY / DATE");
  for (const auto& comment : h.comments) add_header_line(out, text_field(comment, 60), "COMMENT");
  add_header_line(out, text_field(h.marker_name, 60), "MARKER NAME");
  if (!h.marker_number.empty()) add_header_line(out, text_field(h.marker_number, 20), "MARKER NUMBER");
  if (!h.marker_type.empty()) add_header_line(out, text_field(h.marker_type, 20), "MARKER TYPE");
  add_header_line(out, text_field(h.observer, 20) + text_field(h.agency, 40), "OBSERVER / AGENCY");
  add_header_line(out,
                  text_field(h.receiver_number, 20) + text_field(h.receiver_type, 20) +
                      text_field(h.receiver_version, 20),
                  "REC # / TYPE / VERS");
  add_header_line(out, text_field(h.antenna_number, 20) + text_field(h.antenna_type, 20), "ANT # / TYPE");
  if (h.approx_position_ecef_m) {
    const auto& p = *h.approx_position_ecef_m;
    std::snprintf(buf, sizeof buf, "%14.4f%14.4f%14.4f", p[0], p[1], p[2]);
    add_header_line(out, buf, "APPROX POSITION XYZ");
  }
  std::snprintf(buf, sizeof buf, "%14.4f%14.4f%14.4f", h.antenna_delta_hen_m[0], h.antenna_delta_hen_m[1],
                h.antenna_delta_hen_m[2]);
  add_header_line(out, buf, "ANTENNA: DELTA H/E/N");

  for (const auto& [system, types] : h.observation_types) {
    std::snprintf(buf, sizeof buf, "%c  %3zu", system_letter(system), types.size());
    std::string line = buf;
    for (size_t i = 0; i < types.size(); ++i) {
      if (i > 0 && i % 13 == 0) {
        add_header_line(out, line, "SYS / # / OBS TYPES");
        line.assign(6, ' ');
      }
      line += ' ';
      line += types[i].code;
    }
    add_header_line(out, line, "SYS / # / OBS TYPES");
  }
  if (!h.signal_strength_unit.empty()) {
    add_header_line(out, text_field(h.signal_strength_unit, 20), "SIGNAL STRENGTH UNIT");
  }
  if (interval_s) {
    std::snprintf(buf, sizeof buf, "%10.3f", *interval_s);
    add_header_line(out, buf, "INTERVAL");
  }
  const std::string_view ts = *rinex_time_system_label(h.time_system);
  add_header_line(out, format_epoch_record(epoch_fields(first, h.time_system), ts), "TIME OF FIRST OBS");
  if (last) add_header_line(out, format_epoch_record(epoch_fields(*last, h.time_system), ts), "TIME OF LAST OBS");
  if (h.receiver_clock_offset_applied) {
    std::snprintf(buf, sizeof buf, "%6d", *h.receiver_clock_offset_applied);
    add_header_line(out, buf, "RCV CLOCK OFFS APPL");
  }

  // 4.00 deprecates SYS / PHASE SHIFT and GLONASS COD/PHS/BIS (decoders must ignore them).
  if (v3) {
    std::vector<PhaseShift> shifts = h.phase_shifts;
    if (shifts.empty()) {
      for (const auto& [system, types] : h.observation_types) {
        for (const auto& type : types) {
          if (type.code[0] == 'L') shifts.push_back(PhaseShift{system, type.code, 0.0, {}});
        }
      }
    }
    for (const auto& p : shifts) {
      std::string line{system_letter(p.system)};
      if (!p.code.empty()) {
        line += ' ';
        line += p.code;
        if (p.shift_cycles) {
          std::snprintf(buf, sizeof buf, " %8.5f", *p.shift_cycles);
          line += buf;
        } else {
          line.append(9, ' ');
        }
        if (!p.satellites.empty()) {
          std::snprintf(buf, sizeof buf, "  %02zu", p.satellites.size());
          line += buf;
          for (size_t i = 0; i < p.satellites.size(); ++i) {
            if (i > 0 && i % 10 == 0) {
              add_header_line(out, line, "SYS / PHASE SHIFT");
              line.assign(18, ' ');
            }
            line += ' ';
            line += p.satellites[i].to_string();
          }
        }
      }
      add_header_line(out, line, "SYS / PHASE SHIFT");
    }
  }

  const bool has_glonass = h.observation_types.count(GnssSystem::kGlonass) > 0;
  if (has_glonass || !h.glonass_slots.empty()) {
    std::snprintf(buf, sizeof buf, "%3zu ", h.glonass_slots.size());
    std::string line = buf;
    for (size_t i = 0; i < h.glonass_slots.size(); ++i) {
      if (i > 0 && i % 8 == 0) {
        add_header_line(out, line, "GLONASS SLOT / FRQ #");
        line.assign(4, ' ');
      }
      std::snprintf(buf, sizeof buf, "R%02d %2d ", h.glonass_slots[i].slot, h.glonass_slots[i].channel);
      line += buf;
    }
    add_header_line(out, line, "GLONASS SLOT / FRQ #");
  }
  if (v3 && has_glonass) {
    std::vector<GlonassCodePhaseBias> biases = h.glonass_code_phase_biases;
    if (biases.empty()) {
      biases = {{"C1C", std::nullopt}, {"C1P", std::nullopt}, {"C2C", std::nullopt}, {"C2P", std::nullopt}};
    }
    std::string line;
    for (const auto& b : biases) {
      line += ' ';
      line += b.code;
      if (b.bias_m) {
        std::snprintf(buf, sizeof buf, " %8.3f", *b.bias_m);
        line += buf;
      } else {
        line.append(9, ' ');
      }
    }
    add_header_line(out, line, "GLONASS COD/PHS/BIS");
  }
  if (h.leap_seconds) {
    std::snprintf(buf, sizeof buf, "%6d", *h.leap_seconds);
    add_header_line(out, buf, "LEAP SECONDS");
  }
  add_header_line(out, "", "END OF HEADER");
  return out;
}

char* put_two_digits(char* p, int v) {
  p[0] = static_cast<char>('0' + (v / 10) % 10);
  p[1] = static_cast<char>('0' + v % 10);
  return p + 2;
}

}  // namespace

struct RinexObsWriter::Impl {
  std::filesystem::path target;
  std::filesystem::path body_path;
  ObservationHeader header;
  RinexObsWriterOptions options;
  std::FILE* body = nullptr;
  std::vector<char> buffer;
  size_t used = 0;
  size_t epochs = 0;
  size_t omitted = 0;
  bool finished = false;
  std::optional<GnssTime> first_obs;
  std::optional<GnssTime> last_obs;
  std::optional<GnssTime> previous_time;
  std::optional<double> min_interval_s;
  // The header written at the start of the body from the expected span (empty: none).
  std::string early_header;
  std::array<const std::vector<ObservationType>*, 7> types_by_system{};  // indexed by GnssSystem
  std::vector<size_t> order;  // scratch for sorting satellites

  ~Impl() { discard(); }

  void discard() {
    if (body != nullptr) {
      std::fclose(body);
      body = nullptr;
    }
    if (!body_path.empty()) {
      std::error_code ignored;
      std::filesystem::remove(body_path, ignored);
      body_path.clear();
    }
  }

  Status flush_buffer() {
    if (used == 0) return Ok{};
    if (std::fwrite(buffer.data(), 1, used, body) != used) {
      return make_error(ErrorCode::kOutput, body_path.string() + ": write failed (" + std::strerror(errno) + ")");
    }
    used = 0;
    return Ok{};
  }

  // Room for `bytes` more characters in the buffer, writing it out first if needed.
  Status reserve(size_t bytes) {
    if (used + bytes > buffer.size()) {
      if (auto s = flush_buffer(); !s) return s;
      if (bytes > buffer.size()) buffer.resize(bytes);
    }
    return Ok{};
  }

  Error value_error(const ObservationEpoch& epoch, const SatelliteObservations& sat, size_t index, double value) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.6g", value);
    return make_error(ErrorCode::kOutOfRange,
                      target.string() + ": " + sat.satellite.to_string() + " " +
                          (*types_by_system[static_cast<size_t>(sat.satellite.system)])[index].code + " at " +
                          epoch.time.to_iso8601(TimeScale::kGpst, 7) + " GPST: value " + buf +
                          " does not fit RINEX F14.3 (|value| <= 999999999.999)");
  }

  char* write_epoch_line(char* p, const ObservationEpoch& epoch, size_t count, Status& status) {
    const EpochFields f = epoch_fields(epoch.time, header.time_system);
    if (f.year < 0 || f.year > 9999) {
      status = make_error(ErrorCode::kOutOfRange, target.string() + ": epoch year out of range");
      return p;
    }
    *p++ = '>';
    *p++ = ' ';
    *p++ = static_cast<char>('0' + f.year / 1000);
    *p++ = static_cast<char>('0' + (f.year / 100) % 10);
    p = put_two_digits(p, f.year % 100);
    for (int v : {f.month, f.day, f.hour, f.minute}) {
      *p++ = ' ';
      p = put_two_digits(p, v);
    }
    const long long whole = f.second_ticks / 10000000LL;
    long long frac = f.second_ticks % 10000000LL;
    *p++ = ' ';  // F11.7: three integer columns
    *p++ = whole >= 10 ? static_cast<char>('0' + whole / 10) : ' ';
    *p++ = static_cast<char>('0' + whole % 10);
    *p++ = '.';
    for (int i = 6; i >= 0; --i) {
      p[i] = static_cast<char>('0' + frac % 10);
      frac /= 10;
    }
    p += 7;
    *p++ = ' ';
    *p++ = ' ';
    *p++ = static_cast<char>('0' + static_cast<int>(epoch.flag));
    char count_buf[8];
    std::snprintf(count_buf, sizeof count_buf, "%3zu", count);
    std::memcpy(p, count_buf, 3);
    p += 3;
    if (epoch.receiver_clock_offset_s) {
      char clock_buf[32];
      const int n = std::snprintf(clock_buf, sizeof clock_buf, "      %15.12f", *epoch.receiver_clock_offset_s);
      if (n != 21 || !std::isfinite(*epoch.receiver_clock_offset_s)) {
        status = make_error(ErrorCode::kOutOfRange,
                            target.string() + ": receiver clock offset at " +
                                epoch.time.to_iso8601(TimeScale::kGpst, 7) + " GPST does not fit F15.12");
        return p;
      }
      std::memcpy(p, clock_buf, 21);
      p += 21;
    }
    *p++ = '\n';
    return p;
  }

  Status write(const ObservationEpoch& epoch) {
    const bool event = is_event_flag(epoch.flag);
    if (static_cast<int>(epoch.flag) > 6) {
      return make_error(ErrorCode::kInvalidArgument, target.string() + ": epoch flag must be 0..6");
    }
    if (previous_time && epoch.time < *previous_time) {
      return make_error(ErrorCode::kInvalidArgument,
                        target.string() + ": epoch " + epoch.time.to_iso8601(TimeScale::kGpst, 7) +
                            " GPST is before the previous one " + previous_time->to_iso8601(TimeScale::kGpst, 7));
    }
    const size_t count = event ? epoch.event_records.size() : epoch.satellites.size();
    if (count > 999) return make_error(ErrorCode::kInvalidArgument, target.string() + ": more than 999 records in an epoch");

    // Validate and size the whole epoch first so nothing partial reaches the buffer.
    size_t bytes = 64;
    if (event) {
      for (const auto& record : epoch.event_records) {
        if (record.size() > 80 || record.find('\n') != std::string::npos) {
          return make_error(ErrorCode::kInvalidArgument, target.string() + ": event record longer than 80 characters");
        }
        bytes += record.size() + 1;
      }
    } else {
      order.resize(count);
      for (size_t i = 0; i < count; ++i) {
        order[i] = i;
        const auto& sat = epoch.satellites[i];
        const auto* types = static_cast<size_t>(sat.satellite.system) < types_by_system.size()
                                ? types_by_system[static_cast<size_t>(sat.satellite.system)]
                                : nullptr;
        if (types == nullptr) {
          return make_error(ErrorCode::kInvalidArgument, target.string() + ": " + sat.satellite.to_string() +
                                                             " belongs to a system without observation types");
        }
        if (sat.values.size() > types->size()) {
          return make_error(ErrorCode::kInvalidArgument,
                            target.string() + ": " + sat.satellite.to_string() + " has " +
                                std::to_string(sat.values.size()) + " values for " + std::to_string(types->size()) +
                                " observation types");
        }
        if (sat.satellite.number < 1 || sat.satellite.number > 99) {
          return make_error(ErrorCode::kInvalidArgument, target.string() + ": satellite number out of range");
        }
        bytes += 4 + 16 * sat.values.size();
      }
      std::sort(order.begin(), order.end(), [&](size_t a, size_t b) {
        return epoch.satellites[a].satellite < epoch.satellites[b].satellite;
      });
      for (size_t i = 1; i < count; ++i) {
        if (epoch.satellites[order[i]].satellite == epoch.satellites[order[i - 1]].satellite) {
          return make_error(ErrorCode::kInvalidArgument, target.string() + ": " +
                                                             epoch.satellites[order[i]].satellite.to_string() +
                                                             " appears twice in the epoch at " +
                                                             epoch.time.to_iso8601(TimeScale::kGpst, 7));
        }
      }
    }
    if (auto s = reserve(bytes); !s) return s;

    char* const start = buffer.data() + used;
    Status status = Ok{};
    char* p = write_epoch_line(start, epoch, count, status);
    if (!status) return status;
    size_t omitted_here = 0;
    if (event) {
      for (const auto& record : epoch.event_records) {
        std::memcpy(p, record.data(), record.size());
        p += record.size();
        *p++ = '\n';
      }
    } else {
      for (size_t k = 0; k < count; ++k) {
        const auto& sat = epoch.satellites[order[k]];
        *p++ = system_letter(sat.satellite.system);
        p = put_two_digits(p, sat.satellite.number);
        for (size_t i = 0; i < sat.values.size(); ++i) {
          const ObservationValue& v = sat.values[i];
          if (v.lli > 7 || v.ssi > 9) {
            return make_error(ErrorCode::kInvalidArgument,
                              target.string() + ": " + sat.satellite.to_string() +
                                  " LLI must be 0..7 and SSI 0..9 at " + epoch.time.to_iso8601(TimeScale::kGpst, 7));
          }
          bool written = false;
          if (v.value) {
            written = detail::format_f14_3(*v.value, p);
            if (!written) {
              if (!options.omit_unrepresentable_values) return value_error(epoch, sat, i, *v.value);
              ++omitted_here;
            }
          }
          if (written) {
            p[14] = v.lli != 0 ? static_cast<char>('0' + v.lli) : ' ';
            p[15] = v.ssi != 0 ? static_cast<char>('0' + v.ssi) : ' ';
          } else {
            const bool keep_flags = !v.value;  // flags of an omitted value are meaningless
            std::memset(p, ' ', 14);
            p[14] = keep_flags && v.lli != 0 ? static_cast<char>('0' + v.lli) : ' ';
            p[15] = keep_flags && v.ssi != 0 ? static_cast<char>('0' + v.ssi) : ' ';
          }
          p += 16;
        }
        while (p[-1] == ' ') --p;  // trailing blanks are not written
        *p++ = '\n';
      }
    }
    used = static_cast<size_t>(p - buffer.data());
    omitted += omitted_here;
    ++epochs;
    previous_time = epoch.time;
    if (epoch.flag == EpochFlag::kOk || epoch.flag == EpochFlag::kPowerFailure) {  // observation epochs only
      if (last_obs && epoch.time > *last_obs) {
        const double dt_s = epoch.time - *last_obs;
        if (!min_interval_s || dt_s < *min_interval_s) min_interval_s = dt_s;
      }
      if (!first_obs) first_obs = epoch.time;
      last_obs = epoch.time;
    }
    if (used >= options.buffer_bytes) return flush_buffer();
    return Ok{};
  }

  Status finish() {
    const auto fail = [&](Error e) -> Status {
      discard();
      return e;
    };
    if (auto s = flush_buffer(); !s) return fail(s.error());
    if (std::fflush(body) != 0 || std::ferror(body)) {
      return fail(make_error(ErrorCode::kOutput, body_path.string() + ": write failed (disk full?)"));
    }
    if (std::fclose(body) != 0) {
      body = nullptr;
      return fail(make_error(ErrorCode::kOutput, body_path.string() + ": close failed"));
    }
    body = nullptr;

    const std::optional<GnssTime> first = first_obs ? first_obs : header.time_of_first_obs;
    if (!first) {
      return fail(make_error(ErrorCode::kInvalidArgument,
                             target.string() + ": no observation epoch written and no TIME OF FIRST OBS given"));
    }
    const std::optional<GnssTime> last = first_obs ? last_obs : header.time_of_last_obs;
    const std::optional<double> interval = header.interval_s ? header.interval_s : min_interval_s;
    const std::string head = format_header(header, *first, last, interval);
    if (!early_header.empty() && head == early_header) {
      // The body file already begins with this header: it is the file.
      if (auto installed = install_output_file(body_path, target); !installed) return fail(installed.error());
      body_path.clear();
      finished = true;
      return Ok{};
    }

    const std::filesystem::path final_tmp = temporary_sibling(body_path.parent_path() / target.filename(), "part");
    std::FILE* out = std::fopen(final_tmp.c_str(), "wb");
    if (out == nullptr) {
      return fail(make_error(ErrorCode::kOutput, final_tmp.string() + ": cannot create (" + std::strerror(errno) + ")"));
    }
    const auto fail_final = [&](const std::string& why) -> Status {
      std::fclose(out);
      std::error_code ignored;
      std::filesystem::remove(final_tmp, ignored);
      return fail(make_error(ErrorCode::kOutput, final_tmp.string() + ": " + why));
    };
    if (std::fwrite(head.data(), 1, head.size(), out) != head.size()) return fail_final("write failed");
    std::FILE* in = std::fopen(body_path.c_str(), "rb");
    if (in == nullptr) return fail_final("cannot reopen the body " + body_path.string());
    // Past a header written before the body that the epochs did not confirm.
    if (std::fseek(in, static_cast<long>(early_header.size()), SEEK_SET) != 0) {
      std::fclose(in);
      return fail_final("cannot read back the body " + body_path.string());
    }
    std::vector<char> chunk(size_t{1} << 22);
    while (true) {
      const size_t n = std::fread(chunk.data(), 1, chunk.size(), in);
      if (n > 0 && std::fwrite(chunk.data(), 1, n, out) != n) {
        std::fclose(in);
        return fail_final("write failed (disk full?)");
      }
      if (n < chunk.size()) break;
    }
    const bool read_error = std::ferror(in) != 0;
    std::fclose(in);
    if (read_error) return fail_final("cannot read back the body " + body_path.string());
    if (std::fflush(out) != 0 || std::ferror(out)) return fail_final("write failed (disk full?)");
    if (std::fclose(out) != 0) {
      std::error_code ignored;
      std::filesystem::remove(final_tmp, ignored);
      return fail(make_error(ErrorCode::kOutput, final_tmp.string() + ": close failed"));
    }
    if (auto installed = install_output_file(final_tmp, target); !installed) return fail(installed.error());
    discard();
    finished = true;
    return Ok{};
  }
};

RinexObsWriter::RinexObsWriter() = default;
RinexObsWriter::~RinexObsWriter() = default;
RinexObsWriter::RinexObsWriter(RinexObsWriter&&) noexcept = default;
RinexObsWriter& RinexObsWriter::operator=(RinexObsWriter&&) noexcept = default;

Status RinexObsWriter::open(const std::filesystem::path& path, ObservationHeader header,
                            RinexObsWriterOptions options) {
  if (impl_) return make_error(ErrorCode::kInvalidArgument, path.string() + ": writer already opened");
  if (auto s = validate_header(header); !s) return s.error().with_context(path.string());
  if (path.filename().empty()) return make_error(ErrorCode::kInvalidArgument, path.string() + ": not a file name");
  auto impl = std::make_unique<Impl>();
  impl->target = path;
  impl->header = std::move(header);
  impl->options = options;
  impl->options.buffer_bytes = std::max<size_t>(options.buffer_bytes, 4096);
  impl->buffer.resize(impl->options.buffer_bytes + 65536);
  for (const auto& [system, types] : impl->header.observation_types) {
    impl->types_by_system[static_cast<size_t>(system)] = &types;
  }
  // Temporary files beside the file the path leads to (through links), or in the temporary folder
  // when the target is a device or FIFO, which is written in place at the end.
  auto resolved = resolve_output_target(path);
  if (!resolved) return resolved.error();
  const auto scratch_anchor = resolved->kind == OutputKind::kFile
                                  ? resolved->path
                                  : std::filesystem::temp_directory_path() / path.filename();
  impl->body_path = temporary_sibling(scratch_anchor, "body");
  impl->body = std::fopen(impl->body_path.c_str(), "wb");
  if (impl->body == nullptr) {
    const std::string why = std::strerror(errno);
    impl->body_path.clear();
    return make_error(ErrorCode::kOutput, path.string() + ": cannot create a temporary file beside it (" + why + ")");
  }
  if (options.expected_first_obs && options.expected_last_obs) {
    const std::optional<double> interval =
        impl->header.interval_s ? impl->header.interval_s : options.expected_interval_s;
    impl->early_header = format_header(impl->header, *options.expected_first_obs, options.expected_last_obs, interval);
    if (std::fwrite(impl->early_header.data(), 1, impl->early_header.size(), impl->body) != impl->early_header.size()) {
      impl->discard();
      return make_error(ErrorCode::kOutput, path.string() + ": cannot write its temporary file (disk full?)");
    }
  }
  impl_ = std::move(impl);
  return Ok{};
}

Status RinexObsWriter::write_epoch(const ObservationEpoch& epoch) {
  if (!impl_ || impl_->finished || impl_->body == nullptr) {
    return make_error(ErrorCode::kInvalidArgument, "RINEX observation writer is not open");
  }
  return impl_->write(epoch);
}

Status RinexObsWriter::finish() {
  if (!impl_ || impl_->finished || impl_->body == nullptr) {
    return make_error(ErrorCode::kInvalidArgument, "RINEX observation writer is not open");
  }
  return impl_->finish();
}

bool RinexObsWriter::is_open() const { return impl_ && !impl_->finished && impl_->body != nullptr; }
size_t RinexObsWriter::epoch_count() const { return impl_ ? impl_->epochs : 0; }
size_t RinexObsWriter::omitted_value_count() const { return impl_ ? impl_->omitted : 0; }

Status write_rinex_obs(const std::filesystem::path& path, const ObservationHeader& header,
                       const std::vector<ObservationEpoch>& epochs, RinexObsWriterOptions options) {
  RinexObsWriter writer;
  if (auto s = writer.open(path, header, options); !s) return s;
  for (const auto& epoch : epochs) {
    if (auto s = writer.write_epoch(epoch); !s) return s;
  }
  return writer.finish();
}

}  // namespace skytrace::io
