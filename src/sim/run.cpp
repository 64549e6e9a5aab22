#include "skytrace/sim/run.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <condition_variable>
#include <deque>
#include <mutex>
#include <thread>
#include <cmath>
#include <fstream>
#include <random>
#include <set>

#include "skytrace/atmosphere/ionex.hpp"
#include "skytrace/core/constants.hpp"
#include "skytrace/core/text_file.hpp"
#include "skytrace/io/report.hpp"
#include "skytrace/io/rinex_obs.hpp"
#include "skytrace/orbits/broadcast.hpp"
#include "skytrace/orbits/nominal.hpp"
#include "skytrace/orbits/precise.hpp"
#include "skytrace/orbits/rinex_nav.hpp"
#include "skytrace/receiver/observation_generator.hpp"
#include "skytrace/sim/trajectory.hpp"
#include "skytrace/sim/world_setup.hpp"

namespace skytrace::sim {
namespace {

constexpr const char* kVersion = "skytrace 0.1.0";

// A folder inside out_dir that collects the outputs until the run has succeeded.
class StagingDir {
 public:
  static Result<StagingDir> create(const std::filesystem::path& out_dir) {
    std::error_code ec;
    std::filesystem::create_directories(out_dir, ec);
    if (ec) return make_error(ErrorCode::kIo, out_dir.string() + ": cannot create output folder (" + ec.message() + ")");
    std::random_device rd;
    const auto path = out_dir / fmt::format(".skytrace-staging-{:08x}", rd());
    std::filesystem::create_directories(path, ec);
    if (ec) return make_error(ErrorCode::kIo, path.string() + ": cannot create (" + ec.message() + ")");
    return StagingDir(out_dir, path);
  }
  StagingDir(StagingDir&& other) noexcept : out_dir_(std::move(other.out_dir_)), path_(std::move(other.path_)) {
    other.path_.clear();
  }
  StagingDir(const StagingDir&) = delete;
  ~StagingDir() {
    if (!path_.empty()) {
      std::error_code ignored;
      std::filesystem::remove_all(path_, ignored);
    }
  }
  [[nodiscard]] std::filesystem::path file(const std::string& name) const { return path_ / name; }
  // Moves every staged file into the output folder.
  Result<std::vector<std::filesystem::path>> commit() {
    std::vector<std::filesystem::path> moved;
    for (const auto& entry : std::filesystem::directory_iterator(path_)) {
      const auto target = out_dir_ / entry.path().filename();
      std::error_code ec;
      std::filesystem::rename(entry.path(), target, ec);
      if (ec) return make_error(ErrorCode::kIo, target.string() + ": cannot move into place (" + ec.message() + ")");
      moved.push_back(target);
    }
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
    path_.clear();
    std::sort(moved.begin(), moved.end());
    return moved;
  }

 private:
  StagingDir(std::filesystem::path out_dir, std::filesystem::path path) : out_dir_(std::move(out_dir)), path_(std::move(path)) {}
  std::filesystem::path out_dir_;
  std::filesystem::path path_;
};

struct QueuedEpoch {
  std::int64_t index = 0;
  size_t receiver = 0;
  receiver::EpochObservations epoch;
};
using EpochBatch = std::vector<QueuedEpoch>;

// A bounded single-producer single-consumer queue of computed epochs, in batches. Spent batches go
// back to the producer, which frees them: memory is released by the thread that allocated it, so
// the two threads do not contend for the allocator's locks.
class EpochQueue {
 public:
  explicit EpochQueue(size_t capacity_batches) : capacity_(capacity_batches) {}
  // False when the consumer has cancelled.
  bool push(EpochBatch batch) {
    std::unique_lock lock(mutex_);
    not_full_.wait(lock, [&] { return full_.size() < capacity_ || cancelled_; });
    if (cancelled_) return false;
    full_.push_back(std::move(batch));
    not_empty_.notify_one();
    return true;
  }
  // nullopt once the producer has closed the queue and it is empty.
  std::optional<EpochBatch> pop() {
    std::unique_lock lock(mutex_);
    not_empty_.wait(lock, [&] { return !full_.empty() || closed_; });
    if (full_.empty()) return std::nullopt;
    EpochBatch batch = std::move(full_.front());
    full_.pop_front();
    not_full_.notify_one();
    return batch;
  }
  void give_back(EpochBatch batch) {
    std::lock_guard lock(mutex_);
    spent_.push_back(std::move(batch));
  }
  // The producer frees the spent batches outside the lock.
  void release_spent() {
    std::vector<EpochBatch> spent;
    {
      std::lock_guard lock(mutex_);
      spent.swap(spent_);
    }
  }
  void close() {
    std::lock_guard lock(mutex_);
    closed_ = true;
    not_empty_.notify_all();
  }
  void cancel() {
    std::lock_guard lock(mutex_);
    cancelled_ = true;
    not_full_.notify_all();
  }
  bool cancelled() {
    std::lock_guard lock(mutex_);
    return cancelled_;
  }

 private:
  size_t capacity_;
  std::deque<EpochBatch> full_;
  std::vector<EpochBatch> spent_;
  bool closed_ = false;
  bool cancelled_ = false;
  std::mutex mutex_;
  std::condition_variable not_full_, not_empty_;
};

// Marker position and the antenna reference point (marker + antenna height up + offsets east/north).
Eigen::Vector3d antenna_point(const Eigen::Vector3d& marker_m, const ReceiverSettings& r) {
  const Geodetic g = ecef_to_geodetic(marker_m);
  const Eigen::Matrix3d to_enu = ecef_to_enu_rotation(g);
  const Eigen::Vector3d offset_enu(r.antenna_offset_en_m.x(), r.antenna_offset_en_m.y(), r.antenna_height_m);
  return marker_m + to_enu.transpose() * offset_enu;
}

// The frame of world_enu_m coordinates: the loaded world's, else the scenario's origin keys.
std::optional<WorldOrigin> world_origin(const Scenario& s, const std::optional<LoadedWorld>& world) {
  if (world) return world->frame;
  if (s.world.latitude_deg && s.world.longitude_deg) {
    return WorldOrigin{Geodetic{*s.world.latitude_deg, *s.world.longitude_deg, s.world.elevation_m.value_or(0.0)},
                       s.world.heading_deg.value_or(0.0)};
  }
  return std::nullopt;
}

// Column of a signal's code observation in its system's list (phase, Doppler, C/N0 follow it).
using SignalColumns = std::map<Signal, size_t>;

struct ReceiverRun {
  const ReceiverSettings* settings = nullptr;
  Eigen::Vector3d marker_m = Eigen::Vector3d::Zero();  // first marker position
  std::shared_ptr<const receiver::KinematicsSource> kinematics;
  std::unique_ptr<receiver::ObservationGenerator> generator;
  io::ObservationHeader header;
  SignalColumns columns;
  io::RinexObsWriter writer;
  std::string file_name;
};

Result<std::shared_ptr<const receiver::KinematicsSource>> make_kinematics(const Scenario& s, const ReceiverSettings& r,
                                                                          const std::optional<WorldOrigin>& world,
                                                                          Eigen::Vector3d& marker_m) {
  if (r.position) {
    auto ecef = position_to_ecef(*r.position, world);
    if (!ecef) {
      return ecef.error().with_context(s.source.string() + ": receiver '" + r.name + "'");
    }
    marker_m = *ecef;
    return std::shared_ptr<const receiver::KinematicsSource>(std::make_shared<StaticPosition>(antenna_point(*ecef, r)));
  }
  auto samples = read_trajectory_csv(*r.trajectory, s.time.start, world);
  if (!samples) return samples.error();
  if (samples->empty()) return make_error(ErrorCode::kParse, r.trajectory->file.string() + ": no trajectory samples");
  marker_m = samples->front().position_m;
  for (auto& sample : *samples) sample.position_m = antenna_point(sample.position_m, r);
  auto trajectory = InterpolatedTrajectory::create(std::move(*samples), r.trajectory->file.string());
  if (!trajectory) return trajectory.error();
  return std::shared_ptr<const receiver::KinematicsSource>(*trajectory);
}

io::ObservationHeader make_header(const Scenario& s, const ReceiverRun& rx, const orbits::BroadcastEphemerides& eph,
                                  const std::string& rinex_version) {
  io::ObservationHeader h;
  h.version = rinex_version == "4.00" ? 4.00 : 3.04;
  h.program = "skytrace 0.1.0";
  h.run_by = "skytrace";
  h.comments.push_back("Simulated by skytrace from scenario " + s.name);
  h.comments.push_back("Profile " + rx.settings->profile + ", seed " + std::to_string(s.seed));
  h.marker_name = rx.settings->name;
  h.marker_type = rx.settings->trajectory ? "NON_GEODETIC" : "GEODETIC";
  h.observer = "skytrace";
  h.agency = "skytrace";
  h.receiver_number = "1";
  h.receiver_type = rx.settings->receiver_type;
  h.receiver_version = "0.1.0";
  h.antenna_number = "1";
  h.antenna_type = rx.settings->antenna_type;
  h.approx_position_ecef_m = {rx.marker_m.x(), rx.marker_m.y(), rx.marker_m.z()};
  h.antenna_delta_hen_m = {rx.settings->antenna_height_m, rx.settings->antenna_offset_en_m.x(),
                           rx.settings->antenna_offset_en_m.y()};
  for (const Signal& signal : rx.settings->signals) {
    auto& types = h.observation_types[signal.system];
    for (char kind : {'C', 'L', 'D', 'S'}) types.push_back(io::ObservationType{std::string{kind} + signal.code(), ""});
  }
  h.signal_strength_unit = "DBHZ";
  h.interval_s = s.time.interval_s;
  h.time_system = TimeScale::kGpst;
  h.leap_seconds = gps_minus_utc_s(s.time.start);
  if (h.observation_types.count(GnssSystem::kGlonass) != 0) {
    for (const SatelliteId& sat : eph.satellites()) {
      if (sat.system != GnssSystem::kGlonass) continue;
      if (auto k = eph.glonass_channel(sat)) h.glonass_slots.push_back({sat.number, *k});
    }
    for (const char* code : {"C1C", "C1P", "C2C", "C2P"}) h.glonass_code_phase_biases.push_back({code, 0.0});
  }
  return h;
}

int signal_strength_indicator(double cn0_dbhz) {
  return std::clamp(static_cast<int>(std::floor(cn0_dbhz / 6.0)), 1, 9);
}

SignalColumns signal_columns(const io::ObservationHeader& header) {
  SignalColumns columns;
  for (const auto& [system, types] : header.observation_types) {
    for (size_t i = 0; i < types.size(); ++i) {
      const std::string& code = types[i].code;
      if (code.size() == 3 && code[0] == 'C') columns[Signal{system, code[1], code[2]}] = i;
    }
  }
  return columns;
}

io::ObservationEpoch to_rinex(const receiver::EpochObservations& epoch, const io::ObservationHeader& header,
                              const SignalColumns& columns) {
  io::ObservationEpoch out;
  out.time = epoch.receiver_time;
  for (const auto& sat : epoch.satellites) {
    if (sat.status != receiver::SatelliteStatus::kTracked) continue;
    const auto& types = header.observation_types.at(sat.satellite.system);
    io::SatelliteObservations record;
    record.satellite = sat.satellite;
    record.values.resize(types.size());
    for (const auto& m : sat.signals) {
      const auto column = columns.find(m.signal);
      if (column == columns.end()) continue;
      const size_t* index = &column->second;
      const auto ssi = static_cast<std::uint8_t>(signal_strength_indicator(m.cn0_dbhz));
      record.values[*index] = {m.pseudorange_m, 0, ssi};
      record.values[*index + 1] = {m.carrier_phase_cycles, static_cast<std::uint8_t>(m.loss_of_lock ? 1 : 0), ssi};
      record.values[*index + 2] = {m.doppler_hz, 0, 0};
      record.values[*index + 3] = {m.cn0_dbhz, 0, 0};
    }
    out.satellites.push_back(std::move(record));
  }
  return out;
}

constexpr const char* kTruthHeader =
    "time_gpst,receiver,sat,signal,status,az_deg,el_deg,range_m,range_rate_mps,sat_clock_m,relativistic_m,"
    "group_delay_m,iono_m,tropo_m,rx_clock_m,code_noise_m,phase_noise_m,doppler_noise_mps,ambiguity_cycles,"
    "pseudorange_m,carrier_phase_cycles,doppler_hz,cn0_dbhz,rx_x_m,rx_y_m,rx_z_m,rx_vx_mps,rx_vy_mps,rx_vz_mps,"
    "rx_clock_drift_mps,vegetation_attenuation_db,detail\n";

// A CSV cell: quoted when it holds a comma or a quote.
std::string csv_text(const std::string& text) {
  if (text.find_first_of(",\"") == std::string::npos) return text;
  std::string quoted = "\"";
  for (char c : text) {
    if (c == '"') quoted += '"';
    quoted += c;
  }
  return quoted + "\"";
}

void append_truth(std::string& out, const receiver::EpochObservations& epoch, const std::string& receiver_name) {
  const double c = constants::kSpeedOfLight_mps;
  const std::string time = epoch.true_time.to_iso8601(TimeScale::kGpst, 6);
  const auto& rx = epoch.receiver;
  const std::string rx_clock = fmt::format("{:.4f}", c * epoch.receiver_clock.bias_s);
  const std::string receiver_part =
      fmt::format("{:.4f},{:.4f},{:.4f},{:.5f},{:.5f},{:.5f},{:.6f}", rx.position_m.x(), rx.position_m.y(), rx.position_m.z(),
                  rx.velocity_mps.x(), rx.velocity_mps.y(), rx.velocity_mps.z(), c * epoch.receiver_clock.drift_s_per_s);
  constexpr const char* kNoGeometry = ",,,,,";          // 6 empty geometry cells
  constexpr const char* kNoSignalValues = ",,,,,,,";     // 8 empty cells from code noise to C/N0
  for (const auto& sat : epoch.satellites) {
    const std::string status(receiver::to_string(sat.status));
    const std::string sat_name = sat.satellite.to_string();
    const std::string geometry =
        sat.status == receiver::SatelliteStatus::kNoEphemeris
            ? std::string(kNoGeometry)
            : fmt::format("{:.4f},{:.4f},{:.4f},{:.5f},{:.4f},{:.4f}", sat.direction.azimuth_deg,
                          sat.direction.elevation_deg, sat.range_m, sat.range_rate_mps, sat.satellite_clock_m,
                          sat.relativistic_m);
    if (sat.signals.empty()) {
      // One row for the satellite: why it is not observed, with the geometry when known.
      const std::string atmosphere = sat.status == receiver::SatelliteStatus::kTracked ||
                                             sat.status == receiver::SatelliteStatus::kNoSignal
                                         ? fmt::format("{:.4f},{:.4f}", sat.ionosphere_l1_m, sat.troposphere_m)
                                         : std::string(",");
      fmt::format_to(std::back_inserter(out), "{},{},{},,{},{},,{},{},{},{},{:.2f},{}\n", time, receiver_name, sat_name,
                     status, geometry, atmosphere, rx_clock, kNoSignalValues, receiver_part,
                     sat.vegetation_attenuation_db, csv_text(sat.detail));
      continue;
    }
    for (const auto& m : sat.signals) {
      fmt::format_to(std::back_inserter(out),
                     "{},{},{},{},{},{},{:.4f},{:.4f},{:.4f},{},{:.4f},{:.5f},{:.5f},{},{:.4f},{:.4f},{:.4f},{:.3f},{},{:.2f},\n",
                     time, receiver_name, sat_name, m.signal.to_string(), status, geometry, m.group_delay_m,
                     m.ionosphere_code_m, sat.troposphere_m, rx_clock, m.code_noise_m, m.phase_noise_m,
                     m.doppler_noise_mps, m.ambiguity_cycles, m.pseudorange_m, m.carrier_phase_cycles, m.doppler_hz,
                     m.cn0_dbhz, receiver_part, sat.vegetation_attenuation_db);
    }
  }
}

// The span the navigation data can serve, for a plain message when a scenario is outside it.
std::pair<GnssTime, GnssTime> navigation_span(const orbits::NavigationData& nav) {
  std::optional<GnssTime> first, last;
  auto extend = [&](const GnssTime& toe, double half_window_s) {
    const GnssTime a = toe - half_window_s, b = toe + half_window_s;
    if (!first || a < *first) first = a;
    if (!last || *last < b) last = b;
  };
  for (const auto& e : nav.kepler) extend(e.toe, orbits::validity_half_window_s(e));
  for (const auto& e : nav.glonass) extend(e.toe, orbits::glonass_validity_half_window_s());
  for (const auto& e : nav.sbas) extend(e.toe, orbits::sbas_validity_half_window_s());
  return {first.value_or(GnssTime{}), last.value_or(GnssTime{})};
}

Status check_coverage(const Scenario& s, const orbits::BroadcastEphemerides& eph) {
  std::set<GnssSystem> systems;
  for (const auto& r : s.receivers) {
    for (const auto& signal : r.signals) systems.insert(signal.system);
  }
  const GnssTime end = s.time.start + s.time.duration_s;
  for (GnssSystem system : systems) {
    bool at_start = false, at_end = false;
    for (const SatelliteId& sat : eph.satellites()) {
      if (sat.system != system) continue;
      at_start = at_start || eph.state(sat, s.time.start).ok();
      at_end = at_end || eph.state(sat, end).ok();
      if (at_start && at_end) break;
    }
    if (!at_start || !at_end) {
      const auto [first, last] = navigation_span(eph.data());
      return make_error(ErrorCode::kOutOfRange,
                        fmt::format("the navigation data has no valid {} ephemeris at the scenario's {} ({} GPST); the "
                                    "navigation files cover {} to {} GPST",
                                    system_name(system), at_start ? "end" : "start",
                                    (at_start ? end : s.time.start).to_iso8601(TimeScale::kGpst, 0),
                                    first.to_iso8601(TimeScale::kGpst, 0), last.to_iso8601(TimeScale::kGpst, 0)));
    }
  }
  return Ok{};
}

orbits::NavigationData used_navigation(const orbits::NavigationData& all, const std::vector<ReceiverRun>& receivers) {
  orbits::NavigationData used;
  used.ionosphere = all.ionosphere;
  used.time_corrections = all.time_corrections;
  used.leap_seconds = all.leap_seconds;
  std::set<const orbits::KeplerEphemeris*> kepler;
  std::set<const orbits::GlonassEphemeris*> glonass;
  std::set<const orbits::SbasEphemeris*> sbas;
  for (const auto& rx : receivers) {
    kepler.insert(rx.generator->used_kepler().begin(), rx.generator->used_kepler().end());
    glonass.insert(rx.generator->used_glonass().begin(), rx.generator->used_glonass().end());
    sbas.insert(rx.generator->used_sbas().begin(), rx.generator->used_sbas().end());
  }
  for (const auto* e : kepler) used.kepler.push_back(*e);
  for (const auto* e : glonass) used.glonass.push_back(*e);
  for (const auto* e : sbas) used.sbas.push_back(*e);
  return used;
}

}  // namespace

Result<orbits::NavigationData> load_navigation(const Scenario& s) {
  if (s.ephemeris.nominal) {
    // Margin on both sides so the light-time iteration and the validity windows have records.
    return orbits::make_nominal_constellation(s.time.start, s.time.duration_s);
  }
  orbits::NavigationData all;
  for (const auto& path : s.ephemeris.navigation) {
    auto data = orbits::read_rinex_nav(path);
    if (!data) return data.error();
    all.merge(std::move(*data));
  }
  return all;
}

Result<RunSummary> run_scenario(const Scenario& s, const std::filesystem::path& out_dir, const RunOptions& options) {
  const auto wall_start = std::chrono::steady_clock::now();
  auto world = load_world(s);
  if (!world) return world.error();
  auto navigation = load_navigation(s);
  if (!navigation) return navigation.error();
  std::shared_ptr<const atmosphere::IonosphereModel> ionosphere;
  if (s.models.ionosphere == "ionex") {
    auto maps = atmosphere::read_ionex(*s.models.ionex_file);
    if (!maps) return maps.error();
    ionosphere = std::make_shared<atmosphere::IonexIonosphere>(std::move(*maps));
  } else if (s.models.ionosphere == "klobuchar" && navigation->ionosphere.gps) {
    ionosphere = std::make_shared<atmosphere::KlobucharIonosphere>(*navigation->ionosphere.gps);
  }
  if (s.models.ionosphere == "klobuchar" && !navigation->ionosphere.gps) {
    return make_error(ErrorCode::kNotFound,
                      "models.ionosphere is klobuchar but no navigation file has GPS Klobuchar coefficients "
                      "(IONOSPHERIC CORR GPSA/GPSB or ION ALPHA/BETA)");
  }
  const orbits::BroadcastEphemerides ephemerides(std::move(*navigation));
  std::optional<orbits::PreciseEphemerides> precise;
  if (!s.ephemeris.precise_orbits.empty()) {
    auto orbits_data = orbits::read_sp3(s.ephemeris.precise_orbits);
    if (!orbits_data) return orbits_data.error();
    std::optional<orbits::RinexClockData> clocks;
    if (!s.ephemeris.precise_clocks.empty()) {
      auto clock_data = orbits::read_rinex_clock(s.ephemeris.precise_clocks);
      if (!clock_data) return clock_data.error();
      clocks = std::move(*clock_data);
    }
    auto created = orbits::PreciseEphemerides::create(std::move(*orbits_data), std::move(clocks));
    if (!created) return created.error();
    precise.emplace(std::move(*created));
  }
  if (auto coverage = check_coverage(s, ephemerides); !coverage) return coverage.error();

  auto staging = StagingDir::create(out_dir);
  if (!staging) return staging.error();

  std::vector<ReceiverRun> receivers(s.receivers.size());
  for (size_t i = 0; i < s.receivers.size(); ++i) {
    ReceiverRun& rx = receivers[i];
    rx.settings = &s.receivers[i];
    auto kinematics = make_kinematics(s, *rx.settings, world_origin(s, *world), rx.marker_m);
    if (!kinematics) return kinematics.error();
    if (*world) {
      auto start_position = (*kinematics)->at(s.time.start);
      if (start_position) {
        if (auto inside = check_outside_objects(**world, start_position->position_m, rx.settings->name); !inside) {
          return inside.error().with_context(s.source.string());
        }
      }
    }
    rx.kinematics = *kinematics;
    auto profile = receiver::builtin_profile(rx.settings->profile);
    if (!profile) return profile.error().with_context(s.source.string() + ": receiver.profile");
    receiver::GeneratorSettings g;
    g.signals = rx.settings->signals;
    g.elevation_mask_deg = rx.settings->elevation_mask_deg;
    g.profile = *profile;
    g.ionosphere = ionosphere;
    g.troposphere_saastamoinen = s.models.troposphere == "saastamoinen";
    g.noise = s.models.noise;
    g.ideal_clock = s.models.receiver_clock == "ideal";
    g.seed = s.seed;
    g.receiver_index = static_cast<int>(i);
    rx.generator = std::make_unique<receiver::ObservationGenerator>(std::move(g), ephemerides, rx.kinematics,
                                                                     precise ? &*precise : nullptr);
    if (*world) rx.generator->set_world((*world)->scene.get(), (*world)->frame);
    rx.file_name = s.receivers.size() == 1 ? "obs.rnx" : "obs_" + rx.settings->name + ".rnx";
    rx.header = make_header(s, rx, ephemerides, s.output.rinex_version);
    rx.columns = signal_columns(rx.header);
    if (auto st = rx.writer.open(staging->file(rx.file_name), rx.header); !st) {
      return st.error();
    }
  }

  std::ofstream truth;
  std::string truth_buffer;
  if (options.write_truth) {
    truth.open(staging->file("truth.csv"), std::ios::binary);
    if (!truth) return make_error(ErrorCode::kIo, staging->file("truth.csv").string() + ": cannot create");
    truth_buffer = kTruthHeader;
  }

  RunSummary summary;
  const auto epoch_count = static_cast<std::int64_t>(std::floor(s.time.duration_s / s.time.interval_s + 1e-9)) + 1;
  io::ReportBuilder report;  // of the first receiver
  // Writes one computed epoch of one receiver: RINEX, counts, truth, report.
  auto write_epoch = [&](std::int64_t index, size_t receiver_index, const receiver::EpochObservations& epoch) -> Status {
    ReceiverRun& rx = receivers[receiver_index];
    const io::ObservationEpoch record = to_rinex(epoch, rx.header, rx.columns);
    if (auto st = rx.writer.write_epoch(record); !st) return st.error();
    for (const auto& sat : epoch.satellites) {
      if (sat.status != receiver::SatelliteStatus::kTracked) continue;
      ++summary.satellite_epochs;
      ++summary.satellite_epochs_per_system[std::string(system_name(sat.satellite.system))];
      summary.observations += static_cast<std::int64_t>(sat.signals.size());
    }
    if (options.write_truth) {
      append_truth(truth_buffer, epoch, rx.settings->name);
      if (truth_buffer.size() > (1u << 20)) {
        truth.write(truth_buffer.data(), static_cast<std::streamsize>(truth_buffer.size()));
        truth_buffer.clear();
      }
    }
    if (receiver_index == 0) {
      for (const auto& sat : epoch.satellites) {
        if (sat.status == receiver::SatelliteStatus::kNoEphemeris) continue;
        io::ReportSample sample;
        sample.time = epoch.receiver_time;
        sample.satellite = sat.satellite;
        sample.azimuth_deg = sat.direction.azimuth_deg;
        sample.elevation_deg = sat.direction.elevation_deg;
        sample.status = std::string(receiver::to_string(sat.status));
        if (!sat.signals.empty()) sample.cn0_dbhz = sat.signals.front().cn0_dbhz;
        sample.vegetation_attenuation_db = sat.vegetation_attenuation_db;
        report.add(sample);
      }
    }
    if (receiver_index + 1 == receivers.size()) {
      ++summary.epochs;
      if (options.progress) options.progress(index + 1, epoch_count);
    }
    return Ok{};
  };
  auto epoch_tag = [&](std::int64_t k) { return s.time.start + static_cast<double>(k) * s.time.interval_s; };

  if (!options.write_truth) {
    // Without truth.csv, writing costs a fraction of computing: one thread does both (measured
    // faster than handing epochs between threads, docs/performance.md).
    for (std::int64_t k = 0; k < epoch_count; ++k) {
      for (size_t i = 0; i < receivers.size(); ++i) {
        auto epoch = receivers[i].generator->observe(epoch_tag(k));
        if (!epoch) return epoch.error();
        if (auto st = write_epoch(k, i, *epoch); !st) return st.error();
      }
    }
  } else {
    // With truth.csv, formatting costs as much as computing: a worker computes the epochs (the
    // generators keep state from epoch to epoch, so they stay on one thread) while this thread
    // formats and writes them.
    constexpr size_t kBatchEpochs = 64;
    EpochQueue queue(8);
    std::optional<Error> producer_error;
    std::thread producer([&] {
      EpochBatch batch;
      for (std::int64_t k = 0; k < epoch_count && !queue.cancelled(); ++k) {
        for (size_t i = 0; i < receivers.size(); ++i) {
          auto epoch = receivers[i].generator->observe(epoch_tag(k));
          if (!epoch) {
            producer_error = epoch.error();
            queue.close();
            return;
          }
          batch.push_back(QueuedEpoch{k, i, std::move(*epoch)});
        }
        if (batch.size() >= kBatchEpochs) {
          if (!queue.push(std::move(batch))) return;
          batch = EpochBatch();
          queue.release_spent();
        }
      }
      if (!batch.empty()) queue.push(std::move(batch));
      queue.close();
    });
    Status consumed = Ok{};
    while (auto batch = queue.pop()) {
      for (const QueuedEpoch& item : *batch) {
        consumed = write_epoch(item.index, item.receiver, item.epoch);
        if (!consumed) break;
      }
      if (!consumed) break;
      queue.give_back(std::move(*batch));
    }
    if (!consumed) queue.cancel();
    producer.join();
    if (producer_error) return *producer_error;
    if (!consumed) return consumed.error();
  }
  for (ReceiverRun& rx : receivers) {
    if (auto st = rx.writer.finish(); !st) return st.error();
  }
  if (options.write_truth) {
    truth.write(truth_buffer.data(), static_cast<std::streamsize>(truth_buffer.size()));
    truth.close();
    if (!truth) return make_error(ErrorCode::kIo, staging->file("truth.csv").string() + ": write failed");
  }
  const orbits::NavigationData used = used_navigation(ephemerides.data(), receivers);
  if (auto st = write_file_atomically(staging->file("nav.rnx"), orbits::format_rinex3_nav(used)); !st) return st.error();

  {
    io::ReportMeta meta;
    meta.scenario_name = s.name;
    meta.receiver_name = receivers.front().settings->name;
    meta.start = s.time.start;
    meta.end = s.time.start + s.time.duration_s;
    meta.interval_s = s.time.interval_s;
    meta.summary_rows = {{"epochs", std::to_string(summary.epochs)},
                         {"tracked satellite-epochs", std::to_string(summary.satellite_epochs)},
                         {"signal observations", std::to_string(summary.observations)},
                         {"receiver profile", receivers.front().settings->profile},
                         {"ionosphere", s.models.ionosphere},
                         {"troposphere", s.models.troposphere},
                         {"seed", std::to_string(s.seed)}};
    for (const auto& [system, count] : summary.satellite_epochs_per_system) {
      meta.summary_rows.emplace_back(system + " satellite-epochs", std::to_string(count));
    }
    if (*world) {
      const LoadedWorld& w = **world;
      meta.summary_rows.emplace_back("world", w.name + " (" + std::to_string(w.objects) + " objects, " +
                                                  std::to_string(w.buildings) + " buildings, " + std::to_string(w.trees) +
                                                  " trees)");
      meta.warnings = w.warnings;
      auto start_position = receivers.front().kinematics->at(s.time.start);
      if (start_position) {
        constexpr double kMaskStep_deg = 2.0;
        if (auto mask = world_sky_mask_deg(w, start_position->position_m, kMaskStep_deg)) {
          meta.sky_mask_elevation_deg = *mask;
          meta.sky_mask_azimuth_step_deg = kMaskStep_deg;
        }
      }
    }
    if (auto st = write_file_atomically(staging->file("report.html"), report.html(meta)); !st) return st.error();
    if (auto st = write_file_atomically(staging->file("skyplot.svg"), report.sky_plot_svg(meta)); !st) return st.error();
  }
  summary.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  nlohmann::json j;
  j["skytrace_version"] = kVersion;
  j["scenario"] = s.name;
  j["epochs"] = summary.epochs;
  j["satellite_epochs"] = summary.satellite_epochs;
  j["satellite_epochs_per_system"] = summary.satellite_epochs_per_system;
  j["signal_observations"] = summary.observations;
  j["navigation_records_used"] = used.record_count();
  j["wall_time_s"] = summary.wall_time_s;
  if (*world) {
    const LoadedWorld& w = **world;
    j["world"] = {{"name", w.name},       {"objects", w.objects},     {"buildings", w.buildings},
                  {"trees", w.trees},     {"triangles", w.triangles}, {"warnings", w.warnings},
                  {"origin", {w.frame.origin.latitude_deg, w.frame.origin.longitude_deg, w.frame.origin.height_m}},
                  {"heading_deg", w.frame.heading_deg}};
    summary.warnings = w.warnings;
  }
  j["configuration"] = nlohmann::json::parse(scenario_to_json(s));
  if (auto st = write_file_atomically(staging->file("summary.json"), j.dump(2) + "\n"); !st) return st.error();

  auto moved = staging->commit();
  if (!moved) return moved.error();
  summary.outputs = *moved;
  return summary;
}

}  // namespace skytrace::sim
