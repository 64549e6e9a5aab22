// Reading RTCM 3 streams of a reference station: 1005/1006 and MSM4-MSM7 (RTCM 10403.3, section
// 3.5.12), the inverse of the encoder in rtcm3.cpp.
#include <algorithm>
#include <cmath>

#include "skytrace/core/constants.hpp"
#include "skytrace/io/rtcm3.hpp"

namespace skytrace::io {
namespace {

constexpr double kLightMs_m = constants::kSpeedOfLight_mps * 1e-3;  // range of one light millisecond
constexpr double kWeek_s = 604800.0;

std::optional<GnssSystem> msm_system(int message_number) {
  switch (message_number / 10) {
    case 107: return GnssSystem::kGps;
    case 108: return GnssSystem::kGlonass;
    case 109: return GnssSystem::kGalileo;
    case 111: return GnssSystem::kQzss;
    case 112: return GnssSystem::kBeiDou;
    default: return std::nullopt;
  }
}

// The instant nearest `reference` whose time of week in `scale` is `tow_s`.
GnssTime nearest_time_of_week(TimeScale scale, double tow_s, const GnssTime& reference) {
  const WeekTow ref = reference.to_week_tow(scale);
  GnssTime t = GnssTime::from_week_tow(scale, ref.week, tow_s);
  const double offset_s = t - reference;
  if (offset_s > kWeek_s / 2) t -= kWeek_s;
  if (offset_s < -kWeek_s / 2) t += kWeek_s;
  return t;
}

// DF416 + DF034: GLONASS day of week (7: unknown) and time of day (UTC(SU) + 3 h) in ms.
GnssTime glonass_epoch_time(std::uint64_t field, const GnssTime& reference) {
  const auto day = static_cast<int>(field >> 27);
  const double time_of_day_s = static_cast<double>(field & ((1U << 27) - 1)) * 1e-3;
  const double leap_s = gps_minus_utc_s(reference);
  // GLONASS time of the week (weeks starting on Sunday as GPS's), moved to GPS time of week.
  if (day < 7) {
    return nearest_time_of_week(TimeScale::kGpst, std::fmod(day * 86400.0 + time_of_day_s - 10800.0 + leap_s + kWeek_s, kWeek_s),
                                reference);
  }
  // Unknown day: the nearest day to the reference.
  const WeekTow ref = reference.to_week_tow(TimeScale::kGpst);
  const double ref_day_start_s = std::floor(ref.tow_s / 86400.0) * 86400.0;
  GnssTime t = GnssTime::from_week_tow(TimeScale::kGpst, ref.week, ref_day_start_s + time_of_day_s - 10800.0 + leap_s);
  if (t - reference > 43200.0) t -= 86400.0;
  if (t - reference < -43200.0) t += 86400.0;
  return t;
}

}  // namespace

void Rtcm3Decoder::feed(std::span<const std::uint8_t> bytes) {
  pending_.insert(pending_.end(), bytes.begin(), bytes.end());
  size_t i = 0;
  while (i + 6 <= pending_.size()) {
    if (pending_[i] != 0xD3 || (pending_[i + 1] & 0xFC) != 0) {
      ++i;
      ++counts_.skipped_bytes;
      continue;
    }
    const size_t length = (static_cast<size_t>(pending_[i + 1] & 0x03) << 8) | pending_[i + 2];
    if (i + length + 6 > pending_.size()) break;  // wait for the rest of the frame
    const std::span<const std::uint8_t> body(pending_.data() + i, length + 3);
    const std::uint32_t crc = (static_cast<std::uint32_t>(pending_[i + length + 3]) << 16) |
                              (static_cast<std::uint32_t>(pending_[i + length + 4]) << 8) | pending_[i + length + 5];
    if (crc24q(body) != crc) {
      ++i;
      ++counts_.skipped_bytes;
      continue;
    }
    ++counts_.frames;
    const std::span<const std::uint8_t> message(pending_.data() + i + 3, length);
    if (length >= 2) decode(message, (message[0] << 4) | (message[1] >> 4));
    i += length + 6;
  }
  pending_.erase(pending_.begin(), pending_.begin() + static_cast<std::ptrdiff_t>(i));
}

void Rtcm3Decoder::finish() {
  counts_.skipped_bytes += pending_.size();
  pending_.clear();
  if (current_) done_.push_back(std::move(*current_));
  current_.reset();
}

std::vector<RtcmEpoch> Rtcm3Decoder::take_epochs() {
  std::vector<RtcmEpoch> out;
  out.swap(done_);
  return out;
}

void Rtcm3Decoder::decode(std::span<const std::uint8_t> message, int message_number) {
  if (message_number == 1005 || message_number == 1006) {
    decode_station(message, message_number);
  } else if (msm_system(message_number) && message_number % 10 >= 4 && message_number % 10 <= 7) {
    decode_msm(message, message_number);
  } else {
    ++counts_.other_messages;
  }
}

void Rtcm3Decoder::decode_station(std::span<const std::uint8_t> message, int message_number) {
  BitReader r(message);
  (void)r.get_unsigned(12);  // DF002
  RtcmStation s;
  s.station_id = static_cast<int>(r.get_unsigned(12));  // DF003
  (void)r.get_unsigned(6);                                // DF021 ITRF realization year
  s.gps = r.get_unsigned(1) == 1;                         // DF022
  s.glonass = r.get_unsigned(1) == 1;                     // DF023
  s.galileo = r.get_unsigned(1) == 1;                     // DF024
  (void)r.get_unsigned(1);                                // DF141 reference-station indicator
  const double x = static_cast<double>(r.get_signed(38)) * 1e-4;  // DF025
  s.single_receiver_oscillator = r.get_unsigned(1) == 1;          // DF142
  (void)r.get_unsigned(1);                                        // DF001
  const double y = static_cast<double>(r.get_signed(38)) * 1e-4;  // DF026
  (void)r.get_unsigned(2);                                        // DF364 quarter-cycle indicator
  const double z = static_cast<double>(r.get_signed(38)) * 1e-4;  // DF027
  if (message_number == 1006) s.antenna_height_m = static_cast<double>(r.get_unsigned(16)) * 1e-4;  // DF028
  s.arp_ecef_m = Eigen::Vector3d(x, y, z);
  if (r.overrun()) {
    ++counts_.malformed_messages;
    return;
  }
  ++counts_.station_messages;
  station_ = s;
}

void Rtcm3Decoder::decode_msm(std::span<const std::uint8_t> message, int message_number) {
  const GnssSystem system = *msm_system(message_number);
  const int msm = message_number % 10;
  BitReader r(message);
  (void)r.get_unsigned(12);  // DF002
  (void)r.get_unsigned(12);  // DF003
  const std::uint64_t epoch_field = r.get_unsigned(30);
  const bool more_follow = r.get_unsigned(1) == 1;  // DF393
  (void)r.get_unsigned(3 + 7 + 2 + 2 + 1 + 3);      // DF409, DF001, DF411, DF412, DF417, DF418
  const std::uint64_t satellite_mask = r.get_unsigned(64);
  const auto signal_mask = static_cast<std::uint32_t>(r.get_unsigned(32));
  std::vector<int> satellite_ids, signal_ids;
  for (int k = 1; k <= 64; ++k) {
    if ((satellite_mask >> (64 - k)) & 1U) satellite_ids.push_back(k);
  }
  for (int k = 1; k <= 32; ++k) {
    if ((signal_mask >> (32 - k)) & 1U) signal_ids.push_back(k);
  }
  if (satellite_ids.size() * signal_ids.size() > 64) {
    ++counts_.malformed_messages;
    return;
  }
  std::vector<std::pair<size_t, size_t>> cells;  // (satellite index, signal index)
  for (size_t s = 0; s < satellite_ids.size(); ++s) {
    for (size_t g = 0; g < signal_ids.size(); ++g) {
      if (r.get_unsigned(1) == 1) cells.emplace_back(s, g);
    }
  }

  // Satellite data.
  const size_t n = satellite_ids.size();
  std::vector<std::uint64_t> rough_ms(n, 255), rough_mod(n, 0), info(n, 0);
  std::vector<std::int64_t> rough_rate(n, -8192);
  for (auto& v : rough_ms) v = r.get_unsigned(8);  // DF397
  if (msm == 5 || msm == 7) {
    for (auto& v : info) v = r.get_unsigned(4);  // extended satellite information
  }
  for (auto& v : rough_mod) v = r.get_unsigned(10);  // DF398
  if (msm == 5 || msm == 7) {
    for (auto& v : rough_rate) v = r.get_signed(14);  // DF399
  }

  // Signal data: MSM4/5 with standard resolution, MSM6/7 extended.
  const bool extended = msm >= 6;
  const int pr_bits = extended ? 20 : 15, ph_bits = extended ? 24 : 22, lock_bits = extended ? 10 : 4;
  const int cnr_bits = extended ? 10 : 6;
  const double pr_scale = extended ? std::ldexp(1.0, -29) : std::ldexp(1.0, -24);
  const double ph_scale = extended ? std::ldexp(1.0, -31) : std::ldexp(1.0, -29);
  const double cnr_scale = extended ? 0.0625 : 1.0;
  const size_t m = cells.size();
  std::vector<std::int64_t> fine_pr(m), fine_ph(m), fine_rate(m, -16384);
  std::vector<std::uint64_t> lock(m), half(m), cnr(m);
  for (auto& v : fine_pr) v = r.get_signed(pr_bits);
  for (auto& v : fine_ph) v = r.get_signed(ph_bits);
  for (auto& v : lock) v = r.get_unsigned(lock_bits);
  for (auto& v : half) v = r.get_unsigned(1);
  for (auto& v : cnr) v = r.get_unsigned(cnr_bits);
  if (msm == 5 || msm == 7) {
    for (auto& v : fine_rate) v = r.get_signed(15);
  }
  if (r.overrun()) {
    ++counts_.malformed_messages;
    return;
  }
  ++counts_.msm_messages;

  GnssTime time;
  switch (system) {
    case GnssSystem::kGlonass: time = glonass_epoch_time(epoch_field, reference_); break;
    case GnssSystem::kBeiDou: time = nearest_time_of_week(TimeScale::kBdt, static_cast<double>(epoch_field) * 1e-3, reference_); break;
    default: time = nearest_time_of_week(TimeScale::kGpst, static_cast<double>(epoch_field) * 1e-3, reference_); break;
  }
  if (current_ && std::abs(current_->time - time) > 5e-4) {
    done_.push_back(std::move(*current_));
    current_.reset();
  }
  if (!current_) current_ = RtcmEpoch{time, {}};

  const std::int64_t invalid_pr = -(std::int64_t{1} << (pr_bits - 1));
  const std::int64_t invalid_ph = -(std::int64_t{1} << (ph_bits - 1));
  std::vector<RtcmSatelliteObservation> satellites(n);
  for (size_t s = 0; s < n; ++s) {
    SatelliteId id{system, static_cast<std::uint8_t>(satellite_ids[s])};
    satellites[s].satellite = id;
    if (system == GnssSystem::kGlonass) satellites[s].glonass_channel = static_cast<int>(info[s]) - 7;
  }
  for (size_t k = 0; k < m; ++k) {
    const auto [s, g] = cells[k];
    const auto signal = msm_signal(system, signal_ids[g]);
    const SignalInfo* signal_info = signal ? find_signal_info(*signal) : nullptr;
    if (!signal || signal_info == nullptr) {
      ++counts_.unknown_signal_cells;
      continue;
    }
    const bool glonass_channel_unknown = system == GnssSystem::kGlonass && info[s] > 13;
    const double wavelength_m =
        constants::kSpeedOfLight_mps / signal_info->carrier_frequency_hz(satellites[s].glonass_channel);
    RtcmSignalObservation o;
    o.signal = *signal;
    if (rough_ms[s] != 255) {
      const double rough_m = (static_cast<double>(rough_ms[s]) + static_cast<double>(rough_mod[s]) / 1024.0) * kLightMs_m;
      if (fine_pr[k] != invalid_pr) o.pseudorange_m = rough_m + static_cast<double>(fine_pr[k]) * pr_scale * kLightMs_m;
      if (fine_ph[k] != invalid_ph && !glonass_channel_unknown) {
        o.phase_cycles = (rough_m + static_cast<double>(fine_ph[k]) * ph_scale * kLightMs_m) / wavelength_m;
      }
    }
    if (rough_rate[s] != -8192 && fine_rate[k] != -16384 && !glonass_channel_unknown) {
      const double rate_mps = static_cast<double>(rough_rate[s]) + static_cast<double>(fine_rate[k]) * 1e-4;
      o.doppler_hz = -rate_mps / wavelength_m;
    }
    o.cn0_dbhz = static_cast<double>(cnr[k]) * cnr_scale;
    o.lock_time_s = extended ? msm_lock_time_min_s(static_cast<int>(lock[k]))
                             : (lock[k] == 0 ? 0.0 : std::ldexp(1.0, static_cast<int>(lock[k]) + 4) * 1e-3);  // DF402
    o.half_cycle = half[k] == 1;
    satellites[s].signals.push_back(std::move(o));
  }
  for (auto& sat : satellites) {
    if (!sat.signals.empty()) current_->satellites.push_back(std::move(sat));
  }
  if (!more_follow) {
    done_.push_back(std::move(*current_));
    current_.reset();
  }
}

positioning::EpochMeasurements RtcmMeasurementConverter::convert(const RtcmEpoch& epoch) {
  positioning::EpochMeasurements out;
  out.receiver_time = epoch.time;
  std::map<std::pair<SatelliteId, Signal>, double> seen;
  for (const auto& sat : epoch.satellites) {
    for (const auto& o : sat.signals) {
      if (!o.pseudorange_m) continue;  // the engines need the code
      const SignalInfo* info = find_signal_info(o.signal);
      if (info == nullptr) continue;
      positioning::SignalMeasurement m;
      m.satellite = sat.satellite;
      m.signal = o.signal;
      m.pseudorange_m = *o.pseudorange_m;
      m.doppler_hz = o.doppler_hz;
      m.carrier_hz = info->carrier_frequency_hz(sat.glonass_channel);
      m.cn0_dbhz = o.cn0_dbhz;
      m.carrier_phase_cycles = o.phase_cycles;
      const auto key = std::make_pair(sat.satellite, o.signal);
      const auto previous = last_lock_time_s_.find(key);
      m.loss_of_lock = previous == last_lock_time_s_.end() || o.lock_time_s < previous->second;
      m.half_cycle_unresolved = o.half_cycle;
      seen[key] = o.lock_time_s;
      out.signals.push_back(std::move(m));
    }
  }
  last_lock_time_s_ = std::move(seen);
  return out;
}

}  // namespace skytrace::io
