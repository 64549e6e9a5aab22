#include "live_receiver.hpp"

#include <fmt/format.h>

#include <set>

#include "skytrace/core/allocator.hpp"
#include "skytrace/core/cancellation.hpp"
#include "skytrace/core/frames.hpp"
#include "skytrace/io/nmea.hpp"
#include "skytrace/sim/live.hpp"
#include "skytrace/sim/live_outputs.hpp"
#include "skytrace/sim/rtk_base_link.hpp"
#include "skytrace/sim/scenario.hpp"

namespace skytrace::live {
namespace {

Eigen::Vector3d to_eigen(const Vec3& v) { return {v[0], v[1], v[2]}; }
Vec3 to_array(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }
Mat3 to_array(const Eigen::Matrix3d& m) {
  Mat3 out{};
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) out[static_cast<size_t>(3 * r + c)] = m(r, c);
  }
  return out;
}

SkyStatus to_view(receiver::SatelliteStatus status) {
  switch (status) {
    case receiver::SatelliteStatus::kTracked: return SkyStatus::kTracked;
    case receiver::SatelliteStatus::kBelowMask: return SkyStatus::kBelowMask;
    case receiver::SatelliteStatus::kNoEphemeris: return SkyStatus::kNoEphemeris;
    case receiver::SatelliteStatus::kNoSignal: return SkyStatus::kNoSignal;
    case receiver::SatelliteStatus::kBlocked: return SkyStatus::kBlocked;
    case receiver::SatelliteStatus::kAttenuated: return SkyStatus::kAttenuated;
    // The sky message has no status of its own for it; the detail names the health word.
    case receiver::SatelliteStatus::kUnhealthy: return SkyStatus::kNoSignal;
  }
  return SkyStatus::kNoSignal;
}

}  // namespace

void install_stop_handlers() { install_live_stop_handlers(); }
bool stop_requested() { return cancellation_requested(); }
void disarm_stop_watchdog() { skytrace::disarm_stop_watchdog(); }

struct Receiver::Impl {
  std::unique_ptr<sim::LiveSession> session;
  GnssTime start;
  std::optional<sim::LiveEpoch> last;
  double last_time_s = 0.0;
  std::unique_ptr<sim::LiveOutputs> outputs;
  std::optional<sim::RtcmBaseDecoder> base_decoder;  // RTK: the base's stream given as bytes
  std::unique_ptr<sim::RtkBaseLink> base_link;       // RTK: the base's stream read from the network
};

Receiver::Receiver(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Receiver::~Receiver() = default;

std::unique_ptr<Receiver> Receiver::create(const ReceiverOptions& options, std::string& error) {
  tune_allocator_for_epochs();  // the nodes' epochs allocate as a run's do
  auto scenario = sim::load_scenario(options.scenario_path);
  if (!scenario) {
    error = scenario.error().message;
    return nullptr;
  }
  auto impl = std::make_unique<Impl>();
  impl->start = scenario->time.start;
  if (!options.start_time.empty()) {
    auto scale = parse_time_scale(options.start_time_scale);
    if (!scale) {
      error = fmt::format("start time scale '{}': {}", options.start_time_scale, scale.error().message);
      return nullptr;
    }
    auto t = GnssTime::parse_iso8601(options.start_time, *scale);
    if (!t) {
      error = fmt::format("start time '{}': expected YYYY-MM-DDThh:mm:ss[.fff] ({})", options.start_time, t.error().message);
      return nullptr;
    }
    impl->start = *t;
  }
  sim::LiveOptions live_options;
  live_options.pose_timeout_s = options.pose_timeout_s;
  if (!options.receiver_name.empty()) {
    auto index = sim::find_receiver(*scenario, options.receiver_name);
    if (!index) {
      error = index.error().message;
      return nullptr;
    }
    live_options.receiver_index = *index;
  }
  live_options.rtk = options.rtk || !options.rtk_base.empty();
  if (options.rtk) impl->base_decoder.emplace(impl->start);
  if (!options.rtk_base.empty()) {
    auto log = options.log;
    auto link = sim::RtkBaseLink::create(options.rtk_base, impl->start, [log](sim::RtkBaseLink::Note kind, const std::string& text) {
      if (log) log(kind == sim::RtkBaseLink::Note::kInfo ? 0 : kind == sim::RtkBaseLink::Note::kWarning ? 1 : 2, text);
    });
    if (!link) {
      error = link.error().message;
      return nullptr;
    }
    impl->base_link = std::move(*link);
  }
  auto session = sim::LiveSession::create(*scenario, live_options);
  if (!session) {
    error = session.error().message;
    return nullptr;
  }
  impl->session = std::move(*session);
  return std::unique_ptr<Receiver>(new Receiver(std::move(impl)));
}

std::string Receiver::set_antenna_pose_world(double time_s, const Vec3& position_m, const std::optional<Vec3>& velocity_mps) {
  std::optional<Eigen::Vector3d> velocity;
  if (velocity_mps) velocity = to_eigen(*velocity_mps);
  auto st = impl_->session->set_antenna_pose_world(impl_->start + time_s, to_eigen(position_m), velocity);
  return st ? std::string() : st.error().message;
}

std::string Receiver::set_base_antenna_pose_world(double time_s, const Vec3& position_m,
                                                  const std::optional<Vec3>& velocity_mps) {
  std::optional<Eigen::Vector3d> velocity;
  if (velocity_mps) velocity = to_eigen(*velocity_mps);
  auto st = impl_->session->set_base_antenna_pose_world(impl_->start + time_s, to_eigen(position_m), velocity);
  return st ? std::string() : st.error().message;
}

bool Receiver::has_moving_base() const { return impl_->session->has_moving_base(); }

std::string Receiver::set_object_pose(const std::string& name, const Vec3& position_m, const std::array<double, 4>& rotation_wxyz) {
  const Eigen::Quaterniond q(rotation_wxyz[0], rotation_wxyz[1], rotation_wxyz[2], rotation_wxyz[3]);
  if (!q.coeffs().allFinite() || q.norm() < 1e-6) return "pose of '" + name + "' without a valid rotation ignored";
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = q.normalized().toRotationMatrix();
  pose.translation() = to_eigen(position_m);
  auto st = impl_->session->set_object_pose(name, pose);
  return st ? std::string() : st.error().message;
}

bool Receiver::step(double time_s, std::string& error) {
  if (impl_->base_link) impl_->base_link->service(*impl_->session);
  auto result = impl_->session->step(impl_->start + time_s);
  if (!result) {
    error = result.error().message;
    return false;
  }
  impl_->last = std::move(*result);
  impl_->last_time_s = time_s;
  if (impl_->base_link && impl_->last->fix) impl_->base_link->send_position(*impl_->last->fix);
  return true;
}

const sim::LiveSession& Receiver::session() const { return *impl_->session; }
const sim::LiveEpoch* Receiver::last_epoch() const { return impl_->last ? &*impl_->last : nullptr; }

namespace {
// The view of a live epoch at `time_s` after the start time `start`.
void fill_view(const sim::LiveSession& session, const GnssTime& start, double time_s, const sim::LiveEpoch& e, EpochView& out) {
  const GnssTime tag = start + time_s;
  const LocalFrame& world = session.world_frame();
  const Eigen::Matrix3d to_world = world.ecef_to_local_rotation();
  const Eigen::Vector3d antenna_ecef = e.observations.receiver.position_m;

  out = EpochView{};
  out.time_s = time_s;
  const WeekTow wt = tag.to_week_tow(TimeScale::kGpst);
  out.gps_week = wt.week;
  out.gps_tow_s = wt.tow_s;
  out.time_iso = tag.to_iso8601(TimeScale::kGpst);
  out.restarted = e.restarted;
  out.pose_stale = e.pose_stale;
  out.antenna_world_m = to_array(world.from_ecef(antenna_ecef));

  std::set<SatelliteId> used;
  if (e.fix) {
    const positioning::PositionFix& f = *e.fix;
    out.fix.type = positioning::is_3d(f.type) ? 3 : f.type == positioning::FixType::kFix2D ? 2 : 0;
    out.fix.solution = std::string(positioning::to_string(f.type));
    out.fix.differential = f.type == positioning::FixType::kDgnss || f.type == positioning::FixType::kRtkFloat ||
                           f.type == positioning::FixType::kRtkFixed;
    out.fix.message = f.message;
    out.fix.latitude_deg = f.position.latitude_deg;
    out.fix.longitude_deg = f.position.longitude_deg;
    out.fix.height_m = f.position.height_m;
    out.fix.covariance_enu_m2 = to_array(f.covariance_enu_m2);
    out.fix.velocity_valid = f.velocity_valid;
    out.fix.velocity_enu_mps = to_array(f.velocity_enu_mps);
    out.fix.velocity_covariance_enu_m2ps2 = to_array(f.velocity_covariance_enu_m2ps2);
    out.fix.satellites_used = f.satellites_used;
    std::set<char> systems;
    for (const auto& use : f.satellites) {
      if (!use.used) continue;
      used.insert(use.satellite);
      systems.insert(system_letter(use.satellite.system));
    }
    out.fix.systems_used.assign(systems.begin(), systems.end());
    for (std::string& sentence : io::nmea_epoch(f)) {
      while (!sentence.empty() && (sentence.back() == '\n' || sentence.back() == '\r')) sentence.pop_back();
      out.nmea.push_back(std::move(sentence));
    }
  }

  out.satellites.reserve(e.observations.satellites.size());
  for (const auto& sat : e.observations.satellites) {
    SatelliteView s;
    s.id = sat.satellite.to_string();
    s.system = system_letter(sat.satellite.system);
    s.prn = sat.satellite.prn();
    s.glonass_channel = sat.glonass_channel;
    s.status = to_view(sat.status);
    s.detail = sat.detail;
    s.azimuth_deg = sat.direction.azimuth_deg;
    s.elevation_deg = sat.direction.elevation_deg;
    s.vegetation_path_m = sat.vegetation_path_m;
    s.vegetation_attenuation_db = sat.vegetation_attenuation_db;
    s.nlos = sat.path_kind == receiver::PathKind::kNlos;
    s.multipath = sat.path_kind == receiver::PathKind::kMultipath;
    s.used_in_fix = used.count(sat.satellite) > 0;
    if (sat.status != receiver::SatelliteStatus::kNoEphemeris || sat.waiting_for_ephemeris) {
      s.direction_world = to_array((to_world * (sat.satellite_position_m - antenna_ecef)).normalized());
    }
    for (const auto& m : sat.signals) {
      SignalView v;
      v.code = m.signal.code();
      v.carrier_hz = m.carrier_hz;
      v.pseudorange_m = m.pseudorange_m;
      v.carrier_phase_cycles = m.carrier_phase_cycles;
      v.doppler_hz = m.doppler_hz;
      v.cn0_dbhz = m.cn0_dbhz;
      v.loss_of_lock = m.loss_of_lock;
      v.half_cycle_unresolved = m.half_cycle_unresolved;
      v.lock_time_s = m.lock_time_s;
      s.signals.push_back(std::move(v));
    }
    out.satellites.push_back(std::move(s));
  }
}
}  // namespace

bool Receiver::step(double time_s, EpochView& out, std::string& error) {
  if (!step(time_s, error)) return false;
  fill_view(*impl_->session, impl_->start, time_s, *impl_->last, out);
  return true;
}

std::string Receiver::add_base_rtcm3(const std::uint8_t* bytes, size_t size) {
  if (!impl_->base_decoder) return "RTCM 3 of a base given to a receiver without RTK";
  if (!impl_->base_decoder->feed(std::span<const std::uint8_t>(bytes, size), *impl_->session)) {
    return "base epochs wait for the station's position (RTCM 1005/1006)";
  }
  return {};
}

std::vector<std::pair<std::string, std::string>> Receiver::file_parameters() {
  std::vector<std::pair<std::string, std::string>> out;
  for (const auto& kind : sim::live_file_table()) out.emplace_back(kind.parameter, kind.description);
  return out;
}

std::string Receiver::open_outputs(const std::vector<std::pair<std::string, std::string>>& parameter_paths, double interval_s) {
  if (impl_->outputs) return "the outputs are already open";
  auto outputs = sim::LiveOutputs::open(*impl_->session, parameter_paths, interval_s);
  if (!outputs) return outputs.error().message;
  impl_->outputs = std::move(*outputs);
  return {};
}

void Receiver::add_publisher(std::function<void(const EpochView&)> publish) {
  // One view per epoch, reused: the ROS 1 node converts it into its messages.
  auto view = std::make_shared<EpochView>();
  Impl* impl = impl_.get();
  impl_->outputs->add_publisher(std::make_unique<sim::CallbackSink>([impl, view, publish = std::move(publish)](const sim::SinkEpoch&) -> Status {
    fill_view(*impl->session, impl->start, impl->last_time_s, *impl->last, *view);
    publish(*view);
    return Ok{};
  }));
}

void Receiver::add_publisher(std::unique_ptr<sim::EpochSink> publisher) { impl_->outputs->add_publisher(std::move(publisher)); }

bool Receiver::step_outputs(double time_s, std::string& error, std::vector<std::string>& notes) {
  if (!step(time_s, error)) return false;
  if (impl_->outputs) notes = impl_->outputs->add(*impl_->last);
  return true;
}

Receiver::FinishedOutputs Receiver::finish_outputs() {
  if (!impl_->outputs) return {};
  auto finished = impl_->outputs->finish();
  return FinishedOutputs{std::move(finished.written), std::move(finished.errors)};
}

Vec3 Receiver::world_from_geodetic(double latitude_deg, double longitude_deg, double height_m) const {
  return to_array(impl_->session->world_frame().from_ecef(geodetic_to_ecef(Geodetic{latitude_deg, longitude_deg, height_m})));
}

Vec3 Receiver::world_from_ecef(const Vec3& ecef_m) const {
  return to_array(impl_->session->world_frame().from_ecef(to_eigen(ecef_m)));
}

double Receiver::time_s_of_gps(int gps_week, double gps_tow_s) const {
  return GnssTime::from_week_tow(TimeScale::kGpst, gps_week, gps_tow_s) - impl_->start;
}

std::string Receiver::scenario_name() const { return impl_->session->scenario().name; }
std::vector<std::string> Receiver::warnings() const { return impl_->session->resources().warnings; }
double Receiver::scenario_duration_s() const { return impl_->session->scenario().time.duration_s; }

}  // namespace skytrace::live
