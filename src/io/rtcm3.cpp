#include "skytrace/io/rtcm3.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "skytrace/core/constants.hpp"

namespace skytrace::io {
namespace {

constexpr double kLightMs_m = constants::kSpeedOfLight_mps * 1e-3;  // range of one light millisecond
constexpr double kSemicircle_rad = constants::kPi;

double p2(int exponent) { return std::ldexp(1.0, exponent); }

std::int64_t round_to(double value, double unit) { return std::llround(value / unit); }

// ---- time fields --------------------------------------------------------------------------------

// Milliseconds of GPST since the GPS epoch of an instant already rounded to 1 ms (rounded_to(3)).
std::int64_t milliseconds_since_gps_epoch(const GnssTime& rounded) {
  return rounded.whole_seconds() * 1000 + std::llround(rounded.fraction_s() * 1000.0);
}

constexpr std::int64_t kWeek_ms = 604'800'000;
constexpr std::int64_t kDay_ms = 86'400'000;

std::int64_t positive_mod(std::int64_t a, std::int64_t m) { return ((a % m) + m) % m; }

// DF004/DF248/DF427/DF428 or, for GLONASS, DF416 day of week (3 bits) and DF034 ms of day (27 bits).
// The time is rounded to 1 ms on the continuous timeline first; the week, day and leap-second
// offset are then taken from the rounded instant (604799.9996 s is millisecond 0 of the next week,
// and the end of a leap second is 00:00:00.000 UTC with the new GPS - UTC).
std::uint32_t msm_epoch_field(GnssSystem system, const GnssTime& t) {
  const GnssTime rounded = t.rounded_to(3);
  const std::int64_t ms = milliseconds_since_gps_epoch(rounded);
  switch (system) {
    case GnssSystem::kBeiDou: return static_cast<std::uint32_t>(positive_mod(ms - 14'000, kWeek_ms));
    case GnssSystem::kGlonass: {
      // GLONASS time = UTC + 3 h; GPS weeks start on Sunday like DF416's day 0.
      const std::int64_t glonass_ms = ms - static_cast<std::int64_t>(gps_minus_utc_s(rounded)) * 1000 + 10'800'000;
      const std::int64_t of_week = positive_mod(glonass_ms, kWeek_ms);
      return static_cast<std::uint32_t>(((of_week / kDay_ms) << 27) | (of_week % kDay_ms));
    }
    default: return static_cast<std::uint32_t>(positive_mod(ms, kWeek_ms));
  }
}

// ---- signal tables (RTCM 10403.3 tables 3.5-91, -96, -99, -105, -108) ---------------------------

struct SignalRow {
  int id;
  const char* code;
};

constexpr std::array kGpsSignals = {
    SignalRow{2, "1C"},  SignalRow{3, "1P"},  SignalRow{4, "1W"},  SignalRow{8, "2C"},  SignalRow{9, "2P"},
    SignalRow{10, "2W"}, SignalRow{15, "2S"}, SignalRow{16, "2L"}, SignalRow{17, "2X"}, SignalRow{22, "5I"},
    SignalRow{23, "5Q"}, SignalRow{24, "5X"}, SignalRow{30, "1S"}, SignalRow{31, "1L"}, SignalRow{32, "1X"}};
constexpr std::array kGlonassSignals = {SignalRow{2, "1C"}, SignalRow{3, "1P"}, SignalRow{8, "2C"},
                                        SignalRow{9, "2P"}};
constexpr std::array kGalileoSignals = {
    SignalRow{2, "1C"},  SignalRow{3, "1A"},  SignalRow{4, "1B"},  SignalRow{5, "1X"},  SignalRow{6, "1Z"},
    SignalRow{8, "6C"},  SignalRow{9, "6A"},  SignalRow{10, "6B"}, SignalRow{11, "6X"}, SignalRow{12, "6Z"},
    SignalRow{14, "7I"}, SignalRow{15, "7Q"}, SignalRow{16, "7X"}, SignalRow{18, "8I"}, SignalRow{19, "8Q"},
    SignalRow{20, "8X"}, SignalRow{22, "5I"}, SignalRow{23, "5Q"}, SignalRow{24, "5X"}};
constexpr std::array kQzssSignals = {
    SignalRow{2, "1C"},  SignalRow{9, "6S"},  SignalRow{10, "6L"}, SignalRow{11, "6X"}, SignalRow{15, "2S"},
    SignalRow{16, "2L"}, SignalRow{17, "2X"}, SignalRow{22, "5I"}, SignalRow{23, "5Q"}, SignalRow{24, "5X"},
    SignalRow{30, "1S"}, SignalRow{31, "1L"}, SignalRow{32, "1X"}};
// BeiDou B1I is "2I" in RINEX 3.03 and later (RTKLIB 2.4.3 names it so too).
constexpr std::array kBeiDouSignals = {
    SignalRow{2, "2I"},  SignalRow{3, "2Q"},  SignalRow{4, "2X"},  SignalRow{8, "6I"},  SignalRow{9, "6Q"},
    SignalRow{10, "6X"}, SignalRow{14, "7I"}, SignalRow{15, "7Q"}, SignalRow{16, "7X"}, SignalRow{22, "5D"},
    SignalRow{23, "5P"}, SignalRow{24, "5X"}, SignalRow{25, "7D"}, SignalRow{30, "1D"}, SignalRow{31, "1P"},
    SignalRow{32, "1X"}};

template <size_t N>
std::optional<int> lookup(const std::array<SignalRow, N>& table, const Signal& signal) {
  const std::string code = signal.code();
  for (const auto& row : table) {
    if (code == row.code) return row.id;
  }
  return std::nullopt;
}

// MSM satellite ID (1-64) of a satellite.
std::optional<int> msm_satellite_id(const SatelliteId& satellite) {
  const int n = satellite.number;
  if (n < 1 || n > 64) return std::nullopt;
  return n;  // GPS/Galileo/BeiDou PRN, GLONASS slot, QZSS PRN - 192
}

// ---- ephemeris helpers --------------------------------------------------------------------------

int ura_index(double accuracy_m) {
  static constexpr std::array<double, 15> kUra_m = {2.4,  3.4,  4.85,  6.85,  9.65,   13.65,  24.0,  48.0,
                                                    96.0, 192.0, 384.0, 768.0, 1536.0, 3072.0, 6144.0};
  for (size_t i = 0; i < kUra_m.size(); ++i) {
    if (accuracy_m <= kUra_m[i]) return static_cast<int>(i);
  }
  return 15;
}

int sisa_index(double accuracy_m) {
  if (accuracy_m < 0.0) return 255;  // no accuracy prediction available
  if (accuracy_m < 0.5) return static_cast<int>(std::lround(accuracy_m / 0.01));
  if (accuracy_m < 1.0) return 50 + static_cast<int>(std::lround((accuracy_m - 0.5) / 0.02));
  if (accuracy_m < 2.0) return 75 + static_cast<int>(std::lround((accuracy_m - 1.0) / 0.04));
  if (accuracy_m <= 6.0) return 100 + static_cast<int>(std::lround((accuracy_m - 2.0) / 0.16));
  return 255;
}

Status check_range(std::int64_t value, int bits, bool is_signed, const char* name) {
  const std::int64_t max = is_signed ? (std::int64_t{1} << (bits - 1)) - 1 : (std::int64_t{1} << bits) - 1;
  const std::int64_t min = is_signed ? -(std::int64_t{1} << (bits - 1)) : 0;
  if (value < min || value > max) {
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("{} = {} does not fit the {}-bit field", name, value, bits));
  }
  return Ok{};
}

// Writes fields and collects the first range error.
class FieldWriter {
 public:
  void u(std::int64_t value, int bits, const char* name) {
    note(check_range(value, bits, false, name));
    w_.put_unsigned(static_cast<std::uint64_t>(std::max<std::int64_t>(value, 0)), bits);
  }
  void s(std::int64_t value, int bits, const char* name) {
    note(check_range(value, bits, true, name));
    w_.put_signed(value, bits);
  }
  void sm(std::int64_t value, int bits, const char* name) {
    note(check_range(std::abs(value), bits - 1, false, name));
    w_.put_sign_magnitude(value, bits);
  }
  [[nodiscard]] Result<std::vector<std::uint8_t>> frame(const std::string& what) const {
    if (!status_.ok()) return status_.error().with_context(what);
    return rtcm3_frame(w_.bytes());
  }
  [[nodiscard]] BitWriter& bits() { return w_; }

 private:
  void note(Status s) {
    if (status_.ok() && !s.ok()) status_ = std::move(s);
  }
  BitWriter w_;
  Status status_ = Ok{};
};

// Days since 1970-01-01 of a civil date (proleptic Gregorian).
std::int64_t days_from_civil(std::int64_t y, unsigned m, unsigned d) {
  y -= m <= 2;
  const std::int64_t era = (y >= 0 ? y : y - 399) / 400;
  const auto yoe = static_cast<unsigned>(y - era * 400);
  const unsigned doy = (153 * (m + (m > 2 ? -3 : 9)) + 2) / 5 + d - 1;
  const unsigned doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
  return era * 146097 + static_cast<std::int64_t>(doe) - 719468;
}

}  // namespace

// ---- bits ---------------------------------------------------------------------------------------

std::uint32_t crc24q(std::span<const std::uint8_t> bytes) {
  std::uint32_t crc = 0;
  for (const std::uint8_t byte : bytes) {
    crc ^= static_cast<std::uint32_t>(byte) << 16;
    for (int i = 0; i < 8; ++i) {
      crc <<= 1;
      if (crc & 0x1000000U) crc ^= 0x1864CFBU;
    }
  }
  return crc & 0xFFFFFFU;
}

void BitWriter::put_unsigned(std::uint64_t value, int bits) {
  // Most significant bit first, as many bits per step as the current byte has room for.
  while (bits > 0) {
    const int used = static_cast<int>(bits_ % 8);
    if (used == 0) bytes_.push_back(0);
    const int take = std::min(8 - used, bits);
    const auto chunk = static_cast<std::uint8_t>((value >> (bits - take)) & ((1U << take) - 1U));
    bytes_.back() |= static_cast<std::uint8_t>(chunk << (8 - used - take));
    bits -= take;
    bits_ += static_cast<size_t>(take);
  }
}

void BitWriter::put_signed(std::int64_t value, int bits) {
  const std::uint64_t mask = bits >= 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << bits) - 1;
  put_unsigned(static_cast<std::uint64_t>(value) & mask, bits);
}

void BitWriter::put_sign_magnitude(std::int64_t value, int bits) {
  put_unsigned(value < 0 ? 1 : 0, 1);
  put_unsigned(static_cast<std::uint64_t>(value < 0 ? -value : value), bits - 1);
}

std::uint64_t BitReader::get_unsigned(int bits) {
  std::uint64_t value = 0;
  for (int i = 0; i < bits; ++i) {
    value <<= 1;
    const size_t byte = position_ / 8;
    if (byte < bytes_.size()) {
      value |= (bytes_[byte] >> (7 - position_ % 8)) & 1U;
    } else {
      overrun_ = true;
    }
    ++position_;
  }
  return value;
}

std::int64_t BitReader::get_signed(int bits) {
  if (bits <= 0) return 0;  // an empty field (and no sign bit to shift to)
  const std::uint64_t raw = get_unsigned(bits);
  // Sign extension by setting the bits above the field (raw - 2^bits overflows for 63 bits).
  if (bits < 64 && (raw >> (bits - 1)) & 1U) return static_cast<std::int64_t>(raw | (~std::uint64_t{0} << bits));
  return static_cast<std::int64_t>(raw);
}

std::int64_t BitReader::get_sign_magnitude(int bits) {
  if (bits <= 0) return 0;
  const bool negative = get_unsigned(1) != 0;
  // At most 63 bits of magnitude, so that its negation exists (fields are at most 64 bits).
  const auto magnitude = static_cast<std::int64_t>(get_unsigned(bits - 1) & ~(std::uint64_t{1} << 63));
  return negative ? -magnitude : magnitude;
}

Result<std::vector<std::uint8_t>> rtcm3_frame(std::span<const std::uint8_t> message) {
  if (message.size() > 1023) {
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("RTCM 3 message of {} bytes exceeds the 1023-byte frame limit", message.size()));
  }
  std::vector<std::uint8_t> frame;
  frame.reserve(message.size() + 6);
  frame.push_back(0xD3);
  frame.push_back(static_cast<std::uint8_t>(message.size() >> 8));
  frame.push_back(static_cast<std::uint8_t>(message.size() & 0xFF));
  frame.insert(frame.end(), message.begin(), message.end());
  const std::uint32_t crc = crc24q(frame);
  frame.push_back(static_cast<std::uint8_t>(crc >> 16));
  frame.push_back(static_cast<std::uint8_t>((crc >> 8) & 0xFF));
  frame.push_back(static_cast<std::uint8_t>(crc & 0xFF));
  return frame;
}

std::vector<Rtcm3Frame> rtcm3_split_frames(std::span<const std::uint8_t> stream) {
  std::vector<Rtcm3Frame> frames;
  size_t i = 0;
  while (i + 6 <= stream.size()) {
    if (stream[i] != 0xD3 || (stream[i + 1] & 0xFC) != 0) {
      ++i;
      continue;
    }
    const size_t length = (static_cast<size_t>(stream[i + 1] & 0x03) << 8) | stream[i + 2];
    if (i + length + 6 > stream.size()) {  // a false preamble, or a frame cut off at the end
      ++i;
      continue;
    }
    const auto body = stream.subspan(i, length + 3);
    const std::uint32_t crc = (static_cast<std::uint32_t>(stream[i + length + 3]) << 16) |
                              (static_cast<std::uint32_t>(stream[i + length + 4]) << 8) | stream[i + length + 5];
    if (crc24q(body) != crc) {
      ++i;
      continue;
    }
    Rtcm3Frame frame;
    frame.message.assign(stream.begin() + static_cast<std::ptrdiff_t>(i + 3),
                         stream.begin() + static_cast<std::ptrdiff_t>(i + 3 + length));
    if (length >= 2) frame.message_number = (frame.message[0] << 4) | (frame.message[1] >> 4);
    frames.push_back(std::move(frame));
    i += length + 6;
  }
  return frames;
}

// ---- station ------------------------------------------------------------------------------------

Result<std::vector<std::uint8_t>> rtcm3_station(const RtcmStation& station, int message_number) {
  if (message_number != 1005 && message_number != 1006) {
    return make_error(ErrorCode::kInvalidArgument, fmt::format("station message {} is not 1005 or 1006", message_number));
  }
  FieldWriter f;
  f.u(message_number, 12, "DF002 message number");
  f.u(station.station_id, 12, "DF003 reference station ID");
  f.u(0, 6, "DF021 ITRF realization year");
  f.u(station.gps ? 1 : 0, 1, "DF022");
  f.u(station.glonass ? 1 : 0, 1, "DF023");
  f.u(station.galileo ? 1 : 0, 1, "DF024");
  f.u(0, 1, "DF141 reference-station indicator (physical station)");
  f.s(round_to(station.arp_ecef_m.x(), 1e-4), 38, "DF025 ARP ECEF-X");
  f.u(station.single_receiver_oscillator ? 1 : 0, 1, "DF142 single receiver oscillator");
  f.u(0, 1, "DF001 reserved");
  f.s(round_to(station.arp_ecef_m.y(), 1e-4), 38, "DF026 ARP ECEF-Y");
  f.u(0, 2, "DF364 quarter cycle indicator");
  f.s(round_to(station.arp_ecef_m.z(), 1e-4), 38, "DF027 ARP ECEF-Z");
  if (message_number == 1006) f.u(round_to(station.antenna_height_m, 1e-4), 16, "DF028 antenna height");
  return f.frame(fmt::format("message {}", message_number));
}

// ---- MSM ----------------------------------------------------------------------------------------

std::optional<int> msm_base(GnssSystem system) {
  switch (system) {
    case GnssSystem::kGps: return 1070;
    case GnssSystem::kGlonass: return 1080;
    case GnssSystem::kGalileo: return 1090;
    case GnssSystem::kQzss: return 1110;
    case GnssSystem::kBeiDou: return 1120;
    default: return std::nullopt;
  }
}

std::optional<int> msm_signal_id(const Signal& signal) {
  switch (signal.system) {
    case GnssSystem::kGps: return lookup(kGpsSignals, signal);
    case GnssSystem::kGlonass: return lookup(kGlonassSignals, signal);
    case GnssSystem::kGalileo: return lookup(kGalileoSignals, signal);
    case GnssSystem::kQzss: return lookup(kQzssSignals, signal);
    case GnssSystem::kBeiDou: return lookup(kBeiDouSignals, signal);
    default: return std::nullopt;
  }
}

std::optional<Signal> msm_signal(GnssSystem system, int signal_id) {
  const auto find = [&](const auto& table) -> std::optional<Signal> {
    for (const auto& row : table) {
      if (row.id == signal_id) {
        auto signal = Signal::from_code(system, row.code);
        if (signal) return *signal;
      }
    }
    return std::nullopt;
  };
  switch (system) {
    case GnssSystem::kGps: return find(kGpsSignals);
    case GnssSystem::kGlonass: return find(kGlonassSignals);
    case GnssSystem::kGalileo: return find(kGalileoSignals);
    case GnssSystem::kQzss: return find(kQzssSignals);
    case GnssSystem::kBeiDou: return find(kBeiDouSignals);
    default: return std::nullopt;
  }
}

// DF407: indicators 0-63 count milliseconds; each further block of 32 doubles the step, block k
// (k = 1..20) starting at indicator 32 + 32 k with 2^(k+5) ms; 704 means at least 2^26 ms.
int msm_lock_time_indicator(double lock_time_s) {
  if (!(lock_time_s > 0.0)) return 0;
  const double ms_d = std::floor(lock_time_s * 1000.0);
  if (ms_d >= 67108864.0) return 704;
  const auto ms = static_cast<std::int64_t>(ms_d);
  if (ms < 64) return static_cast<int>(ms);
  for (int k = 1; k <= 20; ++k) {
    const std::int64_t start_ms = std::int64_t{1} << (k + 5);
    const std::int64_t end_ms = std::int64_t{1} << (k + 6);
    if (ms < end_ms) return 32 + 32 * k + static_cast<int>((ms - start_ms) >> k);
  }
  return 704;
}

double msm_lock_time_min_s(int indicator) {
  if (indicator <= 0) return 0.0;
  if (indicator < 64) return indicator * 1e-3;
  if (indicator >= 704) return 67108.864;
  const int k = (indicator - 32) / 32;
  const std::int64_t ms = (std::int64_t{1} << (k + 5)) + (static_cast<std::int64_t>(indicator - 32 - 32 * k) << k);
  return static_cast<double>(ms) * 1e-3;
}

Result<std::vector<std::vector<std::uint8_t>>> Msm7Encoder::encode(const RtcmEpoch& epoch) {
  struct Cell {
    const RtcmSignalObservation* observation;
    double wavelength_m;
    int signal_id;
  };
  struct Sat {
    int id;
    SatelliteId satellite;
    int glonass_channel;
    std::vector<Cell> cells;  // by signal ID
  };
  struct Message {
    GnssSystem system;
    std::vector<const Sat*> satellites;
  };

  // Per system, the satellites with their representable signals.
  constexpr std::array kOrder = {GnssSystem::kGps, GnssSystem::kGlonass, GnssSystem::kGalileo, GnssSystem::kQzss,
                                 GnssSystem::kBeiDou};
  std::map<GnssSystem, std::vector<Sat>> by_system;
  for (const auto& sat_obs : epoch.satellites) {
    const auto sat_id = msm_satellite_id(sat_obs.satellite);
    const bool system_ok = msm_base(sat_obs.satellite.system).has_value() && sat_id.has_value();
    Sat sat{sat_id.value_or(0), sat_obs.satellite, sat_obs.glonass_channel, {}};
    for (const auto& s : sat_obs.signals) {
      const auto signal_id = system_ok ? msm_signal_id(s.signal) : std::nullopt;
      const SignalInfo* info = find_signal_info(s.signal);
      if (!signal_id || info == nullptr) {
        dropped_.insert(s.signal);
        continue;
      }
      const double carrier_hz = info->carrier_frequency_hz(sat_obs.glonass_channel);
      sat.cells.push_back({&s, constants::kSpeedOfLight_mps / carrier_hz, *signal_id});
    }
    std::sort(sat.cells.begin(), sat.cells.end(), [](const Cell& a, const Cell& b) { return a.signal_id < b.signal_id; });
    // One observation per signal ID.
    sat.cells.erase(std::unique(sat.cells.begin(), sat.cells.end(),
                                [](const Cell& a, const Cell& b) { return a.signal_id == b.signal_id; }),
                    sat.cells.end());
    if (!sat.cells.empty()) by_system[sat_obs.satellite.system].push_back(std::move(sat));
  }

  // Group satellites into messages of at most 64 cells (satellites x union of signals).
  std::vector<Message> messages;
  for (const GnssSystem system : kOrder) {
    auto it = by_system.find(system);
    if (it == by_system.end()) continue;
    auto& sats = it->second;
    std::sort(sats.begin(), sats.end(), [](const Sat& a, const Sat& b) { return a.id < b.id; });
    sats.erase(std::unique(sats.begin(), sats.end(), [](const Sat& a, const Sat& b) { return a.id == b.id; }),
               sats.end());
    Message current{system, {}};
    std::set<int> signals;
    for (const auto& sat : sats) {
      std::set<int> with = signals;
      for (const auto& c : sat.cells) with.insert(c.signal_id);
      if (!current.satellites.empty() && (current.satellites.size() + 1) * with.size() > 64) {
        messages.push_back(std::move(current));
        current = Message{system, {}};
        with.clear();
        for (const auto& c : sat.cells) with.insert(c.signal_id);
      }
      current.satellites.push_back(&sat);
      signals = std::move(with);
    }
    if (!current.satellites.empty()) messages.push_back(std::move(current));
  }

  std::vector<std::vector<std::uint8_t>> frames;
  for (size_t m = 0; m < messages.size(); ++m) {
    const Message& message = messages[m];
    std::vector<int> signal_ids;
    for (const Sat* sat : message.satellites) {
      for (const auto& c : sat->cells) signal_ids.push_back(c.signal_id);
    }
    std::sort(signal_ids.begin(), signal_ids.end());
    signal_ids.erase(std::unique(signal_ids.begin(), signal_ids.end()), signal_ids.end());

    FieldWriter f;
    const int message_number = *msm_base(message.system) + 7;
    f.u(message_number, 12, "DF002 message number");
    f.u(station_id_, 12, "DF003 reference station ID");
    f.u(msm_epoch_field(message.system, epoch.time), 30, "epoch time");
    f.u(m + 1 < messages.size() ? 1 : 0, 1, "DF393 multiple message bit");
    f.u(0, 3, "DF409 IODS");
    f.u(0, 7, "DF001 reserved");
    f.u(0, 2, "DF411 clock steering");
    f.u(0, 2, "DF412 external clock");
    f.u(0, 1, "DF417 smoothing");
    f.u(0, 3, "DF418 smoothing interval");
    std::uint64_t satellite_mask = 0;
    for (const Sat* sat : message.satellites) satellite_mask |= std::uint64_t{1} << (64 - sat->id);
    f.bits().put_unsigned(satellite_mask, 64);
    std::uint32_t signal_mask = 0;
    for (const int id : signal_ids) signal_mask |= std::uint32_t{1} << (32 - id);
    f.bits().put_unsigned(signal_mask, 32);
    // Cell mask, and the cells in transmission order.
    std::vector<std::pair<const Sat*, const Cell*>> cells;
    for (const Sat* sat : message.satellites) {
      for (const int id : signal_ids) {
        const auto c = std::find_if(sat->cells.begin(), sat->cells.end(), [id](const Cell& x) { return x.signal_id == id; });
        f.bits().put_unsigned(c != sat->cells.end() ? 1 : 0, 1);
        if (c != sat->cells.end()) cells.emplace_back(sat, &*c);
      }
    }

    // Satellite data: rough range from the first signal with a pseudorange, rough rate likewise.
    struct Rough {
      std::optional<std::int64_t> range_units;  // 2^-10 ms
      std::optional<std::int64_t> rate_mps;
    };
    std::map<const Sat*, Rough> rough;
    for (const Sat* sat : message.satellites) {
      Rough r;
      for (const auto& c : sat->cells) {
        if (!r.range_units && c.observation->pseudorange_m) {
          const std::int64_t units = std::llround(*c.observation->pseudorange_m / kLightMs_m * 1024.0);
          if (units >= 0 && (units >> 10) <= 254) r.range_units = units;
        }
        if (!r.rate_mps && c.observation->doppler_hz) {
          const std::int64_t rate = std::llround(-*c.observation->doppler_hz * c.wavelength_m);
          if (std::abs(rate) <= 8191) r.rate_mps = rate;
        }
      }
      rough[sat] = r;
    }
    for (const Sat* sat : message.satellites) {
      const auto& r = rough[sat];
      f.u(r.range_units ? (*r.range_units >> 10) : 255, 8, "DF397 rough range integer ms");
    }
    for (const Sat* sat : message.satellites) {
      const int info = message.system == GnssSystem::kGlonass ? sat->glonass_channel + 7 : 0;
      f.u(info, 4, "extended satellite information");
    }
    for (const Sat* sat : message.satellites) {
      const auto& r = rough[sat];
      f.u(r.range_units ? (*r.range_units & 1023) : 0, 10, "DF398 rough range modulo 1 ms");
    }
    for (const Sat* sat : message.satellites) {
      const auto& r = rough[sat];
      f.s(r.rate_mps ? *r.rate_mps : -8192, 14, "DF399 rough phase-range rate");
    }

    // Signal data.
    struct Fine {
      std::int64_t pseudorange = -524288;
      std::int64_t phase = -8388608;
      int lock = 0;
      bool half = false;
      std::int64_t cnr = 0;
      std::int64_t rate = -16384;
    };
    std::vector<Fine> fine(cells.size());
    for (size_t k = 0; k < cells.size(); ++k) {
      const Sat& sat = *cells[k].first;
      const Cell& cell = *cells[k].second;
      const RtcmSignalObservation& o = *cell.observation;
      const Rough& r = rough[&sat];
      Fine& out = fine[k];
      double lock_time_s = std::max(0.0, o.lock_time_s);
      if (r.range_units) {
        const double rough_m = static_cast<double>(*r.range_units) * kLightMs_m / 1024.0;
        if (o.pseudorange_m) {
          const std::int64_t v = std::llround((*o.pseudorange_m - rough_m) / kLightMs_m / p2(-29));
          if (std::abs(v) <= 524287) out.pseudorange = v;
        }
        if (o.phase_cycles) {
          const auto key = std::make_pair(sat.satellite, o.signal);
          auto arc = arcs_.find(key);
          const auto offset_for = [&](double rough_range_m) {
            return std::llround(*o.phase_cycles - rough_range_m / cell.wavelength_m);
          };
          if (arc == arcs_.end() || o.lock_time_s <= 0.0 || o.lock_time_s < arc->second.last_lock_time_s) {
            Arc fresh;
            fresh.offset_cycles = offset_for(rough_m);
            fresh.offset_since = epoch.time - lock_time_s;
            arc = arcs_.insert_or_assign(key, fresh).first;
          }
          arc->second.last_lock_time_s = o.lock_time_s;
          const auto phase_units = [&]() {
            const double phase_m = (*o.phase_cycles - static_cast<double>(arc->second.offset_cycles)) * cell.wavelength_m;
            return std::llround((phase_m - rough_m) / kLightMs_m / p2(-31));
          };
          std::int64_t v = phase_units();
          if (std::abs(v) > 8388607) {
            // Code and carrier drifted apart: new offset, and the lock time restarts.
            arc->second.offset_cycles = offset_for(rough_m);
            arc->second.offset_since = epoch.time;
            v = phase_units();
          }
          if (std::abs(v) <= 8388607) out.phase = v;
          lock_time_s = std::min(lock_time_s, epoch.time - arc->second.offset_since);
        }
      }
      out.lock = msm_lock_time_indicator(lock_time_s);
      out.half = o.half_cycle;
      if (o.cn0_dbhz > 0.0) out.cnr = std::clamp<std::int64_t>(std::llround(o.cn0_dbhz / 0.0625), 1, 1023);
      if (r.rate_mps && o.doppler_hz) {
        const double rate_mps = -*o.doppler_hz * cell.wavelength_m;
        const std::int64_t v = std::llround((rate_mps - static_cast<double>(*r.rate_mps)) / 1e-4);
        if (std::abs(v) <= 16383) out.rate = v;
      }
    }
    for (const auto& x : fine) f.s(x.pseudorange, 20, "DF405 fine pseudorange");
    for (const auto& x : fine) f.s(x.phase, 24, "DF406 fine phase range");
    for (const auto& x : fine) f.u(x.lock, 10, "DF407 lock time indicator");
    for (const auto& x : fine) f.u(x.half ? 1 : 0, 1, "DF420 half-cycle ambiguity");
    for (const auto& x : fine) f.u(x.cnr, 10, "DF408 CNR");
    for (const auto& x : fine) f.s(x.rate, 15, "DF404 fine phase-range rate");

    auto frame = f.frame(fmt::format("message {}", message_number));
    if (!frame) return frame.error();
    frames.push_back(std::move(frame).value());
  }
  return frames;
}

// ---- ephemerides --------------------------------------------------------------------------------

std::optional<int> rtcm3_ephemeris_message(const orbits::KeplerEphemeris& e) {
  using orbits::NavMessage;
  switch (e.message) {
    case NavMessage::kGpsLnav: return 1019;
    case NavMessage::kQzssLnav: return 1044;
    case NavMessage::kBeiDouD1:
    case NavMessage::kBeiDouD2: return 1042;
    case NavMessage::kGalileoFnav: return 1045;
    case NavMessage::kGalileoInav: return 1046;
    default: return std::nullopt;
  }
}

Result<std::vector<std::uint8_t>> rtcm3_ephemeris(const orbits::KeplerEphemeris& e) {
  const auto message_number = rtcm3_ephemeris_message(e);
  if (!message_number) {
    return make_error(ErrorCode::kUnsupported,
                      fmt::format("{} {} record: no RTCM 3.3 ephemeris message", e.satellite.to_string(),
                                  to_string(e.message)));
  }
  const int type = *message_number;
  const TimeScale scale = system_time_scale(e.satellite.system);
  const WeekTow toe = e.toe.to_week_tow(scale);
  const WeekTow toc = e.toc.to_week_tow(scale);
  const auto sc = [](double rad, int exponent) { return std::llround(rad / kSemicircle_rad / p2(exponent)); };
  const auto sq = [](double value, int exponent) { return std::llround(value / p2(exponent)); };
  const std::int64_t sqrt_a = sq(e.sqrt_a_sqrtm, -19);
  const std::int64_t ecc = sq(e.eccentricity, -33);
  const auto& gd = e.group_delays;

  FieldWriter f;
  f.u(type, 12, "DF002 message number");
  if (type == 1019 || type == 1044) {
    const bool gps = type == 1019;
    if (gps) {
      f.u(e.satellite.number, 6, "DF009 satellite ID");
      f.u(toe.week % 1024, 10, "DF076 week");
      f.u(ura_index(e.accuracy_m), 4, "DF077 URA");
      f.u(e.codes_on_l2, 2, "DF078 codes on L2");
      f.s(sc(e.idot_rad_per_s, -43), 14, "DF079 IDOT");
      f.u(e.iode, 8, "DF071 IODE");
    } else {
      f.u(e.satellite.number, 4, "DF429 satellite ID");
    }
    f.u(std::llround(toc.tow_s / 16.0), 16, "toc");
    f.s(sq(e.af2_s_per_s2, -55), 8, "af2");
    f.s(sq(e.af1_s_per_s, -43), 16, "af1");
    f.s(sq(e.af0_s, -31), 22, "af0");
    if (gps) {
      f.u(e.iodc, 10, "DF085 IODC");
    } else {
      f.u(e.iode, 8, "DF434 IODE");
    }
    f.s(sq(e.crs_m, -5), 16, "Crs");
    f.s(sc(e.delta_n_rad_per_s, -43), 16, "delta n");
    f.s(sc(e.m0_rad, -31), 32, "M0");
    f.s(sq(e.cuc_rad, -29), 16, "Cuc");
    f.u(ecc, 32, "e");
    f.s(sq(e.cus_rad, -29), 16, "Cus");
    f.u(sqrt_a, 32, "sqrt A");
    f.u(std::llround(toe.tow_s / 16.0), 16, "toe");
    f.s(sq(e.cic_rad, -29), 16, "Cic");
    f.s(sc(e.omega0_rad, -31), 32, "Omega0");
    f.s(sq(e.cis_rad, -29), 16, "Cis");
    f.s(sc(e.i0_rad, -31), 32, "i0");
    f.s(sq(e.crc_m, -5), 16, "Crc");
    f.s(sc(e.omega_rad, -31), 32, "omega");
    f.s(sc(e.omega_dot_rad_per_s, -43), 24, "Omega dot");
    if (gps) {
      f.s(sq(gd.tgd_s, -31), 8, "DF096 TGD");
      f.u(e.health & 0x3F, 6, "DF102 SV health");
      f.u(e.l2p_data_flag, 1, "DF103 L2 P data flag");
      f.u(e.fit_interval_h > 4.0 ? 1 : 0, 1, "DF137 fit interval");
    } else {
      f.s(sc(e.idot_rad_per_s, -43), 14, "DF443 IDOT");
      f.u(e.codes_on_l2, 2, "DF451 codes on L2");
      f.u(toe.week % 1024, 10, "DF452 week");
      f.u(ura_index(e.accuracy_m), 4, "DF453 URA");
      f.u(e.health & 0x3F, 6, "DF454 SV health");
      f.s(sq(gd.tgd_s, -31), 8, "DF455 TGD");
      f.u(e.iodc, 10, "DF456 IODC");
      f.u(e.fit_interval_h == 2.0 || e.fit_interval_h == 0.0 ? 0 : 1, 1, "DF457 fit interval");
    }
  } else if (type == 1042) {
    f.u(e.satellite.number, 6, "DF488 satellite ID");
    f.u(toe.week % 8192, 13, "DF489 week");
    f.u(ura_index(e.accuracy_m), 4, "DF490 URAI");
    f.s(sc(e.idot_rad_per_s, -43), 14, "DF491 IDOT");
    f.u(e.iode, 5, "DF492 AODE");
    f.u(std::llround(toc.tow_s / 8.0), 17, "DF493 toc");
    f.s(sq(e.af2_s_per_s2, -66), 11, "DF494 a2");
    f.s(sq(e.af1_s_per_s, -50), 22, "DF495 a1");
    f.s(sq(e.af0_s, -33), 24, "DF496 a0");
    f.u(e.iodc, 5, "DF497 AODC");
    f.s(sq(e.crs_m, -6), 18, "DF498 Crs");
    f.s(sc(e.delta_n_rad_per_s, -43), 16, "DF499 delta n");
    f.s(sc(e.m0_rad, -31), 32, "DF500 M0");
    f.s(sq(e.cuc_rad, -31), 18, "DF501 Cuc");
    f.u(ecc, 32, "DF502 e");
    f.s(sq(e.cus_rad, -31), 18, "DF503 Cus");
    f.u(sqrt_a, 32, "DF504 sqrt A");
    f.u(std::llround(toe.tow_s / 8.0), 17, "DF505 toe");
    f.s(sq(e.cic_rad, -31), 18, "DF506 Cic");
    f.s(sc(e.omega0_rad, -31), 32, "DF507 Omega0");
    f.s(sq(e.cis_rad, -31), 18, "DF508 Cis");
    f.s(sc(e.i0_rad, -31), 32, "DF509 i0");
    f.s(sq(e.crc_m, -6), 18, "DF510 Crc");
    f.s(sc(e.omega_rad, -31), 32, "DF511 omega");
    f.s(sc(e.omega_dot_rad_per_s, -43), 24, "DF512 Omega dot");
    f.s(std::llround(gd.tgd1_s / 1e-10), 10, "DF513 TGD1");
    f.s(std::llround(gd.tgd2_s / 1e-10), 10, "DF514 TGD2");
    f.u(e.health & 1, 1, "DF515 SV health");
  } else {  // 1045, 1046
    f.u(e.satellite.number, 6, "DF252 satellite ID");
    f.u(toe.week % 4096, 12, "DF289 week");
    f.u(e.iode, 10, "DF290 IODnav");
    f.u(sisa_index(e.accuracy_m), 8, "DF291 SISA");
    f.s(sc(e.idot_rad_per_s, -43), 14, "DF292 IDOT");
    f.u(std::llround(toc.tow_s / 60.0), 14, "DF293 toc");
    f.s(sq(e.af2_s_per_s2, -59), 6, "DF294 af2");
    f.s(sq(e.af1_s_per_s, -46), 21, "DF295 af1");
    f.s(sq(e.af0_s, -34), 31, "DF296 af0");
    f.s(sq(e.crs_m, -5), 16, "DF297 Crs");
    f.s(sc(e.delta_n_rad_per_s, -43), 16, "DF298 delta n");
    f.s(sc(e.m0_rad, -31), 32, "DF299 M0");
    f.s(sq(e.cuc_rad, -29), 16, "DF300 Cuc");
    f.u(ecc, 32, "DF301 e");
    f.s(sq(e.cus_rad, -29), 16, "DF302 Cus");
    f.u(sqrt_a, 32, "DF303 sqrt A");
    f.u(std::llround(toe.tow_s / 60.0), 14, "DF304 toe");
    f.s(sq(e.cic_rad, -29), 16, "DF305 Cic");
    f.s(sc(e.omega0_rad, -31), 32, "DF306 Omega0");
    f.s(sq(e.cis_rad, -29), 16, "DF307 Cis");
    f.s(sc(e.i0_rad, -31), 32, "DF308 i0");
    f.s(sq(e.crc_m, -5), 16, "DF309 Crc");
    f.s(sc(e.omega_rad, -31), 32, "DF310 omega");
    f.s(sc(e.omega_dot_rad_per_s, -43), 24, "DF311 Omega dot");
    f.s(sq(gd.bgd_e1e5a_s, -32), 10, "DF312 BGD E1/E5a");
    // RINEX health bits: 0 E1-B DVS, 1-2 E1-B HS, 3 E5a DVS, 4-5 E5a HS, 6 E5b DVS, 7-8 E5b HS.
    const int h = e.health;
    if (type == 1045) {
      f.u((h >> 4) & 3, 2, "DF314 E5a signal health");
      f.u((h >> 3) & 1, 1, "DF315 E5a data validity");
      f.u(0, 7, "DF001 reserved");
    } else {
      f.s(sq(gd.bgd_e1e5b_s, -32), 10, "DF313 BGD E1/E5b");
      f.u((h >> 7) & 3, 2, "DF316 E5b signal health");
      f.u((h >> 6) & 1, 1, "DF317 E5b data validity");
      f.u((h >> 1) & 3, 2, "DF287 E1-B signal health");
      f.u(h & 1, 1, "DF288 E1-B data validity");
      f.u(0, 2, "DF001 reserved");
    }
  }
  return f.frame(fmt::format("message {} of {} ({})", type, e.satellite.to_string(), e.source));
}

Result<std::vector<std::uint8_t>> rtcm3_ephemeris(const orbits::GlonassEphemeris& g) {
  // GLONASS messages count time in Moscow time (UTC + 3 h).
  const CalendarTime toe_msk = g.toe.to_calendar(TimeScale::kGlonasst);
  const double toe_of_day_s = toe_msk.hour * 3600.0 + toe_msk.minute * 60.0 + toe_msk.second;
  double tk_s = std::fmod(g.message_frame_time_s + 10800.0, 86400.0);
  if (tk_s < 0.0) tk_s += 86400.0;
  const int tk_h = static_cast<int>(tk_s / 3600.0);
  const int tk_m = static_cast<int>((tk_s - tk_h * 3600.0) / 60.0);
  const int tk_30 = tk_s - tk_h * 3600.0 - tk_m * 60.0 >= 30.0 ? 1 : 0;
  // Calendar day within the four-year interval starting with a leap year.
  const int first_year = toe_msk.year - toe_msk.year % 4;
  const std::int64_t nt = days_from_civil(toe_msk.year, static_cast<unsigned>(toe_msk.month),
                                          static_cast<unsigned>(toe_msk.day)) -
                          days_from_civil(first_year, 1, 1) + 1;

  FieldWriter f;
  f.u(1020, 12, "DF002 message number");
  f.u(g.satellite.number, 6, "DF038 satellite ID");
  f.u(g.frequency_channel + 7, 5, "DF040 frequency channel");
  f.u(0, 1, "DF104 almanac health");
  f.u(0, 1, "DF105 almanac health availability");
  f.u(0, 2, "DF106 P1");
  f.u(tk_h, 5, "DF107 tk hours");
  f.u(tk_m, 6, "DF107 tk minutes");
  f.u(tk_30, 1, "DF107 tk 30 s");
  f.u(g.health != 0 ? 1 : 0, 1, "DF108 Bn");
  f.u(0, 1, "DF109 P2");
  f.u(std::llround(toe_of_day_s / 900.0), 7, "DF110 tb");
  for (int axis = 0; axis < 3; ++axis) {
    f.sm(std::llround(g.velocity_mps[axis] / 1e3 / p2(-20)), 24, "DF111 velocity");
    f.sm(std::llround(g.position_m[axis] / 1e3 / p2(-11)), 27, "DF112 position");
    f.sm(std::llround(g.acceleration_mps2[axis] / 1e3 / p2(-30)), 5, "DF113 acceleration");
  }
  f.u(0, 1, "DF120 P3");
  f.sm(std::llround(g.gamma_n / p2(-40)), 11, "DF121 gamma_n");
  f.u(0, 2, "DF122 P");
  f.u(0, 1, "DF123 ln");
  f.sm(std::llround(-g.minus_tau_n_s / p2(-30)), 22, "DF124 tau_n");
  f.sm(std::llround(g.delta_tau_n_s.value_or(0.0) / p2(-30)), 5, "DF125 delta tau_n");
  f.u(std::lround(g.age_days), 5, "DF126 E_n");
  f.u(0, 1, "DF127 P4");
  f.u(g.urai >= 0 && g.urai <= 15 ? g.urai : 15, 4, "DF128 F_T");
  f.u(nt, 11, "DF129 N_T");
  f.u(1, 2, "DF130 M (GLONASS-M)");
  f.u(0, 1, "DF131 additional data available");
  f.u(0, 11, "DF132 N_A");
  f.sm(0, 32, "DF133 tau_c");
  f.u(0, 5, "DF134 N_4");
  f.sm(0, 22, "DF135 tau_GPS");
  f.u(0, 1, "DF136 ln");
  f.u(0, 7, "DF001 reserved");
  return f.frame(fmt::format("message 1020 of {} ({})", g.satellite.to_string(), g.source));
}

// ---- stream -------------------------------------------------------------------------------------

Rtcm3Stream::Rtcm3Stream(Rtcm3StreamSettings settings, RtcmStation station)
    : settings_(settings), station_(std::move(station)), msm_(settings.station_id) {
  station_.station_id = settings.station_id;
}

Result<std::vector<std::uint8_t>> Rtcm3Stream::epoch(const RtcmEpoch& observations,
                                                     std::span<const orbits::KeplerEphemeris* const> kepler,
                                                     std::span<const orbits::GlonassEphemeris* const> glonass) {
  std::vector<std::uint8_t> out;
  const auto append = [&out](const std::vector<std::uint8_t>& bytes) { out.insert(out.end(), bytes.begin(), bytes.end()); };
  const GnssTime now = observations.time;
  if (!last_station_ || now - *last_station_ >= settings_.station_interval_s - 1e-6 || now < *last_station_) {
    auto station = rtcm3_station(station_, 1006);
    if (!station) return station.error();
    append(*station);
    last_station_ = now;
  }
  // Observations before ephemerides: decoders date GLONASS and week-truncated records by the
  // latest observation time.
  auto msm = msm_.encode(observations);
  if (!msm) return msm.error();
  for (const auto& frame : *msm) append(frame);

  const auto due = [&](const void* record, const SatelliteId& sat, const GnssTime& toe,
                       const auto& newest_by_sat) {
    const auto it = sent_.find(record);
    if (it == sent_.end()) return true;
    const auto newest = newest_by_sat.find(sat);
    const bool is_newest = newest != newest_by_sat.end() && newest->second == toe;
    return is_newest && (now - it->second >= settings_.ephemeris_interval_s - 1e-6 || now < it->second);
  };
  std::map<std::pair<SatelliteId, int>, GnssTime> newest_kepler_key;
  for (const auto* e : kepler) {
    const auto message = rtcm3_ephemeris_message(*e);
    if (!message) continue;
    auto& t = newest_kepler_key[{e->satellite, *message}];
    t = std::max(t, e->toe);
  }
  for (const auto* e : kepler) {
    const auto message = rtcm3_ephemeris_message(*e);
    if (!message) continue;
    std::map<SatelliteId, GnssTime> newest{{e->satellite, newest_kepler_key[{e->satellite, *message}]}};
    if (!due(e, e->satellite, e->toe, newest)) continue;
    auto bytes = rtcm3_ephemeris(*e);
    if (!bytes) return bytes.error();
    append(*bytes);
    sent_[e] = now;
  }
  std::map<SatelliteId, GnssTime> newest_glonass;
  for (const auto* g : glonass) {
    auto& t = newest_glonass[g->satellite];
    t = std::max(t, g->toe);
  }
  for (const auto* g : glonass) {
    if (!due(g, g->satellite, g->toe, newest_glonass)) continue;
    auto bytes = rtcm3_ephemeris(*g);
    if (!bytes) return bytes.error();
    append(*bytes);
    sent_[g] = now;
  }
  return out;
}

}  // namespace skytrace::io
