#include "skytrace/sim/ros2_topics.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include "skytrace/core/constants.hpp"
#include "skytrace/io/nmea.hpp"
#include "skytrace/sim/streams.hpp"

namespace skytrace::sim {
namespace {

using ros2::NavSatStatus;

std::uint16_t navsat_service(GnssSystem system) {
  switch (system) {
    case GnssSystem::kGps:
    case GnssSystem::kQzss:  // ranges as a GPS augmentation
    case GnssSystem::kSbas:
      return NavSatStatus::kServiceGps;
    case GnssSystem::kGlonass: return NavSatStatus::kServiceGlonass;
    case GnssSystem::kBeiDou: return NavSatStatus::kServiceCompass;
    case GnssSystem::kGalileo: return NavSatStatus::kServiceGalileo;
    default: return 0;  // NavIC: NavSatStatus has no bit for it
  }
}

std::uint8_t sky_status(receiver::SatelliteStatus status) {
  using S = receiver::SatelliteStatus;
  using M = ros2::SatelliteSky;
  switch (status) {
    case S::kTracked: return M::kTracked;
    case S::kBelowMask: return M::kBelowMask;
    case S::kNoEphemeris: return M::kNoEphemeris;
    case S::kNoSignal: return M::kNoSignal;
    case S::kBlocked: return M::kBlocked;
    case S::kAttenuated: return M::kAttenuated;
    case S::kUnhealthy: return M::kNoSignal;  // the detail names the health word
  }
  return M::kNoSignal;
}

ros2::ColorRGBA rgba(float r, float g, float b) { return ros2::ColorRGBA{r, g, b, 1.0F}; }

ros2::GnssTimeMsg gnss_time(const GnssTime& t) {
  const WeekTow wt = t.to_week_tow(TimeScale::kGpst);
  return ros2::GnssTimeMsg{static_cast<std::uint32_t>(wt.week), wt.tow_s};
}

// RTKLIB's observation code table, which gnss_comm numbers its codes by (index = code).
constexpr std::string_view kRtklibCodes[] = {
    "",   "1C", "1P", "1W", "1Y", "1M", "1N", "1S", "1L", "1E", "1A", "1B", "1X", "1Z", "2C", "2D", "2S",
    "2L", "2X", "2P", "2W", "2Y", "2M", "2N", "5I", "5Q", "5X", "7I", "7Q", "7X", "6A", "6B", "6C", "6X",
    "6Z", "6S", "6L", "8I", "8Q", "8X", "2I", "2Q", "6I", "6Q", "3I", "3Q", "3X", "1I", "1Q"};

// The receiver's own estimate of a measurement's accuracy, as receivers report it (u-blox
// prStdev/cpStdev/doStdev): the profile's thermal noise at the signal's C/N0, floored where a
// noise-free profile would report zero.
constexpr double kMinCodeStd_m = 0.01, kMinPhaseStd_cycles = 0.001, kMinDopplerStd_hz = 0.002;

ros2::GnssEphemMsg to_gnss_comm(const orbits::KeplerEphemeris& e) {
  ros2::GnssEphemMsg m;
  m.sat = gnss_comm_satellite(e.satellite);
  if (auto ttr = orbits::transmission_time(e)) m.ttr = gnss_time(*ttr);
  m.toe = gnss_time(e.toe);
  m.toc = gnss_time(e.toc);
  m.toe_tow = e.toe_sow;  // in the system's own week, as broadcast
  m.week = static_cast<std::uint32_t>(std::max(e.week, 0));
  m.iode = static_cast<std::uint32_t>(std::max(e.iode, 0));
  m.iodc = static_cast<std::uint32_t>(std::max(e.iodc, 0));
  m.health = static_cast<std::uint32_t>(std::max(e.health, 0));
  m.code = e.satellite.system == GnssSystem::kGalileo ? e.data_source : static_cast<std::uint32_t>(std::max(e.codes_on_l2, 0));
  m.ura = e.accuracy_m;
  m.a = e.sqrt_a_sqrtm * e.sqrt_a_sqrtm;
  m.e = e.eccentricity;
  m.i0 = e.i0_rad;
  m.omg = e.omega_rad;
  m.omg0 = e.omega0_rad;
  m.m0 = e.m0_rad;
  m.delta_n = e.delta_n_rad_per_s;
  m.omg_dot = e.omega_dot_rad_per_s;
  m.i_dot = e.idot_rad_per_s;
  m.cuc = e.cuc_rad;
  m.cus = e.cus_rad;
  m.crc = e.crc_m;
  m.crs = e.crs_m;
  m.cic = e.cic_rad;
  m.cis = e.cis_rad;
  m.af0 = e.af0_s;
  m.af1 = e.af1_s_per_s;
  m.af2 = e.af2_s_per_s2;
  // RTKLIB's tgd[0], tgd[1]: GPS/QZSS T_GD; Galileo BGD E1-E5a, E1-E5b; BeiDou TGD1, TGD2.
  switch (e.satellite.system) {
    case GnssSystem::kGalileo:
      m.tgd0 = e.group_delays.bgd_e1e5a_s;
      m.tgd1 = e.group_delays.bgd_e1e5b_s;
      break;
    case GnssSystem::kBeiDou:
      m.tgd0 = e.group_delays.tgd1_s;
      m.tgd1 = e.group_delays.tgd2_s;
      break;
    default: m.tgd0 = e.group_delays.tgd_s; break;
  }
  m.a_dot = e.a_dot_m_per_s;
  m.n_dot = e.delta_n_dot_rad_per_s2;
  return m;
}

ros2::GnssGloEphemMsg to_gnss_comm(const orbits::GlonassEphemeris& e) {
  ros2::GnssGloEphemMsg m;
  m.sat = gnss_comm_satellite(e.satellite);
  if (auto ttr = orbits::transmission_time(e)) m.ttr = gnss_time(*ttr);
  m.toe = gnss_time(e.toe);
  m.freqo = e.frequency_channel;
  // t_b in quarter hours of the Moscow day, as RTKLIB's iode.
  const WeekTow moscow = e.toe.to_week_tow(TimeScale::kGlonasst);
  m.iode = static_cast<std::uint32_t>(std::fmod(moscow.tow_s, 86400.0) / 900.0 + 0.5) % 96;
  m.health = static_cast<std::uint32_t>(std::max(e.health, 0));
  m.age = static_cast<std::uint32_t>(std::max(e.age_days, 0.0));
  m.pos_x = e.position_m.x();
  m.pos_y = e.position_m.y();
  m.pos_z = e.position_m.z();
  m.vel_x = e.velocity_mps.x();
  m.vel_y = e.velocity_mps.y();
  m.vel_z = e.velocity_mps.z();
  m.acc_x = e.acceleration_mps2.x();
  m.acc_y = e.acceleration_mps2.y();
  m.acc_z = e.acceleration_mps2.z();
  m.tau_n = -e.minus_tau_n_s;
  m.gamma = e.gamma_n;
  m.delta_tau_n = e.delta_tau_n_s.value_or(0.0);
  return m;
}

}  // namespace

const std::vector<Ros2Topic>& ros2_receiver_topics() {
  static const std::vector<Ros2Topic> topics = {
      {"fix", ros2::NavSatFix::kType, Ros2Qos::kDefault, 10},
      {"velocity", ros2::TwistWithCovarianceStamped::kType, Ros2Qos::kDefault, 10},
      {"time_reference", ros2::TimeReference::kType, Ros2Qos::kDefault, 10},
      {"nmea", ros2::NmeaSentence::kType, Ros2Qos::kDefault, 100},
      {"rtcm", ros2::RtcmMessage::kType, Ros2Qos::kDefault, 100},
      {"gnss/measurements", ros2::GnssMeasMsg::kType, Ros2Qos::kDefault, 10},
      // A record is published once, when the receiver starts to use it: kept for estimators that
      // start after the node.
      {"gnss/ephemeris", ros2::GnssEphemMsg::kType, Ros2Qos::kLatched, 500},
      {"gnss/glonass_ephemeris", ros2::GnssGloEphemMsg::kType, Ros2Qos::kLatched, 500},
      {"observations", ros2::Observations::kType, Ros2Qos::kDefault, 10},
      {"sky", ros2::Sky::kType, Ros2Qos::kDefault, 10},
      {"rays", ros2::MarkerArray::kType, Ros2Qos::kDefault, 10},
  };
  return topics;
}

ros2::Time unix_utc_time(const GnssTime& time) {
  constexpr std::int64_t kGpsEpochInUnix_s = 315964800;  // 1980-01-06T00:00:00Z
  const std::int64_t whole = time.whole_seconds() - gps_minus_utc_s(time) + kGpsEpochInUnix_s;
  ros2::Time t = ros2::Time::from_seconds(time.fraction_s());
  t.sec += static_cast<std::int32_t>(whole);
  return t;
}

ros2::NavSatFix to_navsat_fix(const positioning::PositionFix* fix, const ros2::Header& header) {
  ros2::NavSatFix msg;
  msg.header = header;
  if (fix == nullptr || fix->type == positioning::FixType::kNone) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    msg.status.status = NavSatStatus::kStatusNoFix;
    msg.latitude = msg.longitude = msg.altitude = nan;
    msg.position_covariance_type = ros2::NavSatFix::kCovarianceUnknown;
    return msg;
  }
  switch (fix->type) {
    case positioning::FixType::kDgnss:
    case positioning::FixType::kRtkFloat:
    case positioning::FixType::kRtkFixed: msg.status.status = NavSatStatus::kStatusGbasFix; break;
    default: msg.status.status = NavSatStatus::kStatusFix; break;
  }
  for (const auto& use : fix->satellites) {
    if (use.used) msg.status.service |= navsat_service(use.satellite.system);
  }
  msg.latitude = fix->position.latitude_deg;
  msg.longitude = fix->position.longitude_deg;
  msg.altitude = fix->position.height_m;  // above the WGS84 ellipsoid, as NavSatFix defines it
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) msg.position_covariance[static_cast<size_t>(3 * r + c)] = fix->covariance_enu_m2(r, c);
  }
  msg.position_covariance_type = ros2::NavSatFix::kCovarianceKnown;
  return msg;
}

std::uint32_t gnss_comm_satellite(const SatelliteId& satellite) {
  constexpr int kGps = 32, kGlonass = 27, kGalileo = 38, kBeidou = 63;
  const int prn = satellite.prn();
  auto in = [&](int count, int offset) -> std::uint32_t {
    return prn >= 1 && prn <= count ? static_cast<std::uint32_t>(offset + prn) : 0;
  };
  switch (satellite.system) {
    case GnssSystem::kGps: return in(kGps, 0);
    case GnssSystem::kGlonass: return in(kGlonass, kGps);
    case GnssSystem::kGalileo: return in(kGalileo, kGps + kGlonass);
    case GnssSystem::kBeiDou: return in(kBeidou, kGps + kGlonass + kGalileo);
    default: return 0;
  }
}

std::uint8_t gnss_comm_code(const Signal& signal) {
  const std::string code = signal.code();
  for (size_t i = 1; i < std::size(kRtklibCodes); ++i) {
    if (kRtklibCodes[i] == code) return static_cast<std::uint8_t>(i);
  }
  return 0;
}

std::vector<std::vector<std::uint8_t>> split_rtcm3_frames(const std::vector<std::uint8_t>& stream) {
  std::vector<std::vector<std::uint8_t>> frames;
  size_t i = 0;
  while (i + 6 <= stream.size()) {
    if (stream[i] != 0xD3) {
      ++i;
      continue;
    }
    const size_t length = (static_cast<size_t>(stream[i + 1] & 0x03) << 8) | stream[i + 2];
    const size_t total = 3 + length + 3;
    if (i + total > stream.size()) break;
    frames.emplace_back(stream.begin() + static_cast<std::ptrdiff_t>(i), stream.begin() + static_cast<std::ptrdiff_t>(i + total));
    i += total;
  }
  return frames;
}

struct Ros2EpochBuilder::Impl {
  const orbits::BroadcastEphemerides& ephemerides;
  receiver::ReceiverProfile profile;
  LocalFrame world;
  io::RtcmStation station;
  Ros2TopicSettings settings;
  std::optional<io::Rtcm3Stream> rtcm;
  std::set<const void*> published_records;
  // Without RTCM the records in use are looked up only when a tracked satellite has none published
  // yet, and every kRecordCheck_s otherwise (a new record replaces the old one every 1-2 h).
  std::set<SatelliteId> satellites_with_records;
  std::optional<GnssTime> last_record_check;
  std::map<Signal, const SignalInfo*> signal_infos;
  // The profile's noise at a C/N0, cached per signal and 0.05 dB-Hz step (C/N0 changes slowly).
  std::map<std::pair<Signal, int>, receiver::TrackingNoise> noise_cache;
};

Ros2EpochBuilder::Ros2EpochBuilder(const orbits::BroadcastEphemerides& ephemerides, receiver::ReceiverProfile profile,
                                   LocalFrame world, io::RtcmStation station, Ros2TopicSettings settings)
    : impl_(new Impl{ephemerides, std::move(profile), world, std::move(station), std::move(settings), {}, {}, {}, {}, {}, {}}) {
  reset();
}

Ros2EpochBuilder::~Ros2EpochBuilder() = default;

void Ros2EpochBuilder::reset() {
  impl_->published_records.clear();
  impl_->satellites_with_records.clear();
  impl_->last_record_check.reset();
  impl_->rtcm.reset();
  if (impl_->settings.rtcm) impl_->rtcm.emplace(io::Rtcm3StreamSettings{}, impl_->station);
}

Result<Ros2Epoch> Ros2EpochBuilder::build(const receiver::EpochObservations& epoch, const positioning::PositionFix* fix,
                                          const ros2::Time& stamp, bool restarted, bool pose_stale) {
  Ros2Epoch out;
  if (auto st = build_into(out, epoch, fix, stamp, restarted, pose_stale); !st) return st.error();
  return out;
}

namespace {
// The i-th element of a reused vector, grown when needed (the caller trims it at the end).
template <typename T>
T& slot(std::vector<T>& items, size_t i) {
  if (i == items.size()) items.emplace_back();
  return items[i];
}
}  // namespace

Status Ros2EpochBuilder::build_into(Ros2Epoch& out, const receiver::EpochObservations& epoch,
                                    const positioning::PositionFix* fix, const ros2::Time& stamp, bool restarted,
                                    bool pose_stale) {
  Impl& s = *impl_;
  const ros2::Header header{stamp, s.settings.frame_id};
  const WeekTow tag = epoch.receiver_time.to_week_tow(TimeScale::kGpst);

  out.fix = to_navsat_fix(fix, header);
  out.velocity.reset();
  if (fix != nullptr && fix->velocity_valid) {
    ros2::TwistWithCovarianceStamped v;
    v.header = header;
    v.twist.twist.linear = {fix->velocity_enu_mps.x(), fix->velocity_enu_mps.y(), fix->velocity_enu_mps.z()};
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) {
        v.twist.covariance[static_cast<size_t>(6 * r + c)] = fix->velocity_covariance_enu_m2ps2(r, c);
      }
    }
    for (size_t k = 3; k < 6; ++k) v.twist.covariance[6 * k + k] = 1e9;  // GNSS gives no angular rate
    out.velocity = std::move(v);
  }
  // The receiver's time: its solution's when it has one, else its own tag.
  out.time_reference.header = header;
  out.time_reference.time_ref =
      unix_utc_time(fix != nullptr && fix->type != positioning::FixType::kNone ? fix->time : epoch.receiver_time);
  out.time_reference.source = s.settings.time_source;
  out.nmea.clear();
  if (fix != nullptr && s.settings.nmea) {
    for (std::string& sentence : io::nmea_epoch(*fix)) {
      while (!sentence.empty() && (sentence.back() == '\n' || sentence.back() == '\r')) sentence.pop_back();
      out.nmea.push_back(ros2::NmeaSentence{header, std::move(sentence)});
    }
  }

  constexpr double kRecordCheck_s = 30.0;
  bool check_records = s.rtcm.has_value() || !s.last_record_check ||
                       std::abs(epoch.receiver_time - *s.last_record_check) >= kRecordCheck_s;
  for (size_t i = 0; i < epoch.satellites.size() && !check_records; ++i) {
    const auto& sat = epoch.satellites[i];
    check_records = !sat.signals.empty() && !s.satellites_with_records.contains(sat.satellite);
  }
  out.rtcm.clear();
  out.ephemerides.clear();
  out.glonass_ephemerides.clear();
  if (check_records) {
    s.last_record_check = epoch.receiver_time;
    const RecordsInUse records = records_in_use(s.ephemerides, epoch);
    if (s.rtcm) {
      auto bytes = rtcm3_epoch_bytes(*s.rtcm, epoch, records);
      if (!bytes) return bytes.error();
      for (auto& frame : split_rtcm3_frames(*bytes)) out.rtcm.push_back(ros2::RtcmMessage{header, std::move(frame)});
    }
    for (const auto* e : records.kepler) {
      s.satellites_with_records.insert(e->satellite);
      if (gnss_comm_satellite(e->satellite) == 0 || !s.published_records.insert(e).second) continue;
      out.ephemerides.push_back(to_gnss_comm(*e));
    }
    for (const auto* e : records.glonass) {
      s.satellites_with_records.insert(e->satellite);
      if (gnss_comm_satellite(e->satellite) == 0 || !s.published_records.insert(e).second) continue;
      out.glonass_ephemerides.push_back(to_gnss_comm(*e));
    }
  }

  std::set<SatelliteId> used;
  if (fix != nullptr) {
    for (const auto& use : fix->satellites) {
      if (use.used) used.insert(use.satellite);
    }
  }
  out.observations.header = header;
  out.observations.gps_week = static_cast<std::uint32_t>(tag.week);
  out.observations.gps_tow_s = tag.tow_s;
  out.observations.restarted = restarted;
  out.observations.pose_stale = pose_stale;
  out.sky.header = header;
  out.sky.gps_week = out.observations.gps_week;
  out.sky.gps_tow_s = tag.tow_s;

  if (out.rays.markers.size() != 1) out.rays.markers.resize(1);
  ros2::Marker& rays = out.rays.markers.front();
  rays.header = ros2::Header{stamp, s.settings.world_frame};
  rays.ns = "skytrace_rays";
  rays.type = ros2::Marker::kLineList;
  rays.pose.orientation.w = 1.0;
  rays.scale.x = 0.05;  // line width, m
  rays.points.clear();
  rays.colors.clear();
  const Eigen::Vector3d antenna_ecef = epoch.receiver.position_m;
  const Eigen::Vector3d antenna_world = s.world.from_ecef(antenna_ecef);
  const Eigen::Matrix3d to_world = s.world.ecef_to_local_rotation();

  const ros2::GnssTimeMsg meas_time = gnss_time(epoch.receiver_time);
  size_t n_observations = 0, n_meas = 0, n_sky = 0;
  for (const auto& sat : epoch.satellites) {
    const bool has_position = sat.status != receiver::SatelliteStatus::kNoEphemeris || sat.waiting_for_ephemeris;
    const bool vegetation = sat.vegetation_path_m > 0.0;
    const bool nlos = sat.path_kind == receiver::PathKind::kNlos;
    const char system = system_letter(sat.satellite.system);
    const auto prn = static_cast<std::uint16_t>(sat.satellite.prn());
    const std::uint32_t gnss_comm_sat = gnss_comm_satellite(sat.satellite);
    const bool tracked = !sat.signals.empty();
    if (!tracked && !(has_position && sat.direction.elevation_deg >= 0.0)) continue;
    const std::string id = sat.satellite.to_string();

    ros2::GnssObsMsg* obs = nullptr;
    if (gnss_comm_sat != 0 && tracked) {
      obs = &slot(out.measurements.meas, n_meas++);
      obs->time = meas_time;
      obs->sat = gnss_comm_sat;
      for (auto* values : {&obs->freqs, &obs->cn0, &obs->psr, &obs->psr_std, &obs->cp, &obs->cp_std, &obs->dopp,
                           &obs->dopp_std}) {
        values->clear();
      }
      obs->lli.clear();
      obs->code.clear();
      obs->status.clear();
    }
    double best_cn0 = 0.0;
    for (const auto& m : sat.signals) {
      best_cn0 = std::max(best_cn0, m.cn0_dbhz);
      ros2::Observation& o = slot(out.observations.observations, n_observations++);
      o.satellite = id;
      o.system.assign(1, system);
      o.prn = prn;
      o.glonass_channel = static_cast<std::int8_t>(sat.glonass_channel);
      o.signal.assign({m.signal.band, m.signal.attribute});
      o.carrier_frequency_hz = m.carrier_hz;
      o.pseudorange_m = m.pseudorange_m;
      o.carrier_phase_cycles = m.carrier_phase_cycles;
      o.doppler_hz = m.doppler_hz;
      o.cn0_dbhz = m.cn0_dbhz;
      o.loss_of_lock = m.loss_of_lock;
      o.half_cycle_unresolved = m.half_cycle_unresolved;
      o.lock_time_s = m.lock_time_s;
      o.azimuth_deg = sat.direction.azimuth_deg;
      o.elevation_deg = sat.direction.elevation_deg;
      o.los = !vegetation && !nlos;
      o.nlos = nlos;
      o.vegetation = vegetation;
      o.blocked = false;  // blocked satellites are not tracked (they are on `sky`)
      o.vegetation_path_m = sat.vegetation_path_m;
      o.vegetation_attenuation_db = sat.vegetation_attenuation_db;

      if (obs != nullptr) {
        const auto key = std::make_pair(m.signal, static_cast<int>(std::lround(m.cn0_dbhz * 20.0)));
        auto cached = s.noise_cache.find(key);
        if (cached == s.noise_cache.end()) {
          const SignalInfo*& info = s.signal_infos[m.signal];
          if (info == nullptr) info = find_signal_info(m.signal);
          receiver::TrackingNoise computed;
          if (info != nullptr) computed = receiver::tracking_noise(s.profile, *info, m.carrier_hz, key.second / 20.0);
          cached = s.noise_cache.emplace(key, computed).first;
        }
        const receiver::TrackingNoise& noise = cached->second;
        const double wavelength_m = constants::kSpeedOfLight_mps / m.carrier_hz;
        obs->freqs.push_back(m.carrier_hz);
        obs->cn0.push_back(m.cn0_dbhz);
        obs->lli.push_back(static_cast<std::uint8_t>((m.loss_of_lock ? 1 : 0) | (m.half_cycle_unresolved ? 2 : 0)));
        obs->code.push_back(gnss_comm_code(m.signal));
        obs->psr.push_back(m.pseudorange_m);
        obs->psr_std.push_back(std::max(noise.code_m, kMinCodeStd_m));
        obs->cp.push_back(m.carrier_phase_cycles);
        obs->cp_std.push_back(std::max(noise.phase_m / wavelength_m, kMinPhaseStd_cycles));
        obs->dopp.push_back(m.doppler_hz);
        obs->dopp_std.push_back(std::max(noise.doppler_mps / wavelength_m, kMinDopplerStd_hz));
        // bit 0 pseudorange valid, 1 phase valid, 2 half cycle valid, 3 half cycle subtracted
        obs->status.push_back(static_cast<std::uint8_t>(0x1 | 0x2 | (m.half_cycle_unresolved ? 0 : 0x4)));
      }
    }

    // The sky: every satellite with a position above the horizon.
    if (has_position && sat.direction.elevation_deg >= 0.0) {
      ros2::SatelliteSky& sky = slot(out.sky.satellites, n_sky++);
      sky.satellite = id;
      sky.system.assign(1, system);
      sky.prn = prn;
      sky.azimuth_deg = sat.direction.azimuth_deg;
      sky.elevation_deg = sat.direction.elevation_deg;
      sky.status = sky_status(sat.status);
      sky.used_in_fix = used.contains(sat.satellite);
      sky.cn0_dbhz = best_cn0;
      sky.vegetation_path_m = sat.vegetation_path_m;
      sky.vegetation_attenuation_db = sat.vegetation_attenuation_db;
      sky.detail = sat.detail;
      if (sat.status != receiver::SatelliteStatus::kNoSignal && sat.status != receiver::SatelliteStatus::kUnhealthy) {
        ros2::ColorRGBA colour;
        switch (sat.status) {
          case receiver::SatelliteStatus::kTracked:
            colour = vegetation ? rgba(0.9F, 0.8F, 0.1F) : nlos ? rgba(0.6F, 0.2F, 0.8F) : rgba(0.1F, 0.8F, 0.2F);
            break;
          case receiver::SatelliteStatus::kAttenuated: colour = rgba(0.9F, 0.45F, 0.1F); break;
          case receiver::SatelliteStatus::kBlocked: colour = rgba(0.9F, 0.1F, 0.1F); break;
          default: colour = rgba(0.5F, 0.5F, 0.5F); break;
        }
        const Eigen::Vector3d direction = (to_world * (sat.satellite_position_m - antenna_ecef)).normalized();
        const Eigen::Vector3d end = antenna_world + s.settings.ray_length_m * direction;
        rays.points.push_back(ros2::Point{antenna_world.x(), antenna_world.y(), antenna_world.z()});
        rays.points.push_back(ros2::Point{end.x(), end.y(), end.z()});
        rays.colors.push_back(colour);
        rays.colors.push_back(colour);
      }
    }
  }
  out.observations.observations.resize(n_observations);
  out.measurements.meas.resize(n_meas);
  out.sky.satellites.resize(n_sky);
  rays.action = rays.points.empty() ? ros2::Marker::kActionDeleteAll : ros2::Marker::kActionAdd;
  return Ok{};
}

}  // namespace skytrace::sim
