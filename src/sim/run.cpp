#include "skytrace/sim/run.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <condition_variable>
#include <deque>
#include <mutex>
#include <thread>
#include <cmath>
#include <complex>
#include <fstream>
#include <random>
#include <set>

#include "skytrace/atmosphere/ionex.hpp"
#include "skytrace/core/cancellation.hpp"
#include "skytrace/core/constants.hpp"
#include "skytrace/core/output_file.hpp"
#include "skytrace/core/text_file.hpp"
#include "skytrace/io/report.hpp"
#include "skytrace/io/rinex_obs.hpp"
#include "skytrace/orbits/broadcast.hpp"
#include "skytrace/orbits/nominal.hpp"
#include "skytrace/orbits/precise.hpp"
#include "skytrace/orbits/rinex_nav.hpp"
#include "skytrace/receiver/observation_generator.hpp"
#include "skytrace/sim/setup.hpp"
#include "skytrace/sim/streams.hpp"
#include "skytrace/sim/trajectory.hpp"
#include "skytrace/sim/world_setup.hpp"
#include "skytrace/world/loaders.hpp"

namespace skytrace::sim {
namespace {

constexpr const char* kVersion = "skytrace 0.1.0";

constexpr std::string_view kStagingPrefix = ".skytrace-staging-";
constexpr const char* kStagingLockName = ".lock";
// A staging folder without a lock file is another run's only in the instant between its mkdir and
// the lock; one older than this is left over from a version without locks.
constexpr auto kUnlockedStagingAge = std::chrono::minutes(10);

// Removes staging folders of runs that are no longer alive: their lock file can be locked (the
// kernel drops a dead process's locks, also after SIGKILL or a crash).
void remove_stale_staging(const std::filesystem::path& out_dir) {
  std::error_code ec;
  for (auto it = std::filesystem::directory_iterator(out_dir, ec); !ec && it != std::filesystem::directory_iterator();
       it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.rfind(kStagingPrefix, 0) != 0 || !it->is_directory(ec)) continue;
    const auto lock_path = it->path() / kStagingLockName;
    bool stale = false;
    const int fd = ::open(lock_path.c_str(), O_RDWR | O_CLOEXEC);
    if (fd >= 0) {
      stale = ::flock(fd, LOCK_EX | LOCK_NB) == 0;
      ::close(fd);
    } else {
      const auto modified = std::filesystem::last_write_time(it->path(), ec);
      stale = !ec && std::filesystem::file_time_type::clock::now() - modified > kUnlockedStagingAge;
    }
    if (stale) {
      std::error_code ignored;
      std::filesystem::remove_all(it->path(), ignored);
    }
  }
}

// A folder inside out_dir that collects the outputs until the run has succeeded. It holds a locked
// file for as long as this process lives, so that a later run can tell it from a live run's.
class StagingDir {
 public:
  static Result<StagingDir> create(const std::filesystem::path& out_dir) {
    std::error_code ec;
    if (std::filesystem::exists(out_dir, ec) && !std::filesystem::is_directory(out_dir, ec)) {
      return make_error(ErrorCode::kOutput, out_dir.string() + ": is not a folder (--out names the output folder)");
    }
    std::filesystem::create_directories(out_dir, ec);
    if (ec) return make_error(ErrorCode::kOutput, out_dir.string() + ": cannot create output folder (" + ec.message() + ")");
    remove_stale_staging(out_dir);
    std::random_device rd;
    const auto path = out_dir / fmt::format("{}{}-{:08x}", kStagingPrefix, ::getpid(), rd());
    std::filesystem::create_directory(path, ec);
    if (ec) return make_error(ErrorCode::kOutput, path.string() + ": cannot create (" + ec.message() + ")");
    // Locked under another name, then renamed: a later run never sees an unlocked `.lock` of a
    // live run (the lock belongs to the open file, not to its name).
    const auto unlocked_name = path / (std::string(kStagingLockName) + ".new");
    const int lock_fd = ::open(unlocked_name.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (lock_fd < 0 || ::flock(lock_fd, LOCK_EX | LOCK_NB) != 0 ||
        ::rename(unlocked_name.c_str(), (path / kStagingLockName).c_str()) != 0) {
      const std::string why = std::strerror(errno);
      if (lock_fd >= 0) ::close(lock_fd);
      std::filesystem::remove_all(path, ec);
      return make_error(ErrorCode::kOutput, path.string() + ": cannot lock the staging folder (" + why + ")");
    }
    return StagingDir(out_dir, path, lock_fd);
  }
  StagingDir(StagingDir&& other) noexcept
      : out_dir_(std::move(other.out_dir_)), path_(std::move(other.path_)), lock_fd_(other.lock_fd_) {
    other.path_.clear();
    other.lock_fd_ = -1;
  }
  StagingDir(const StagingDir&) = delete;
  ~StagingDir() {
    if (!path_.empty()) {
      std::error_code ignored;
      std::filesystem::remove_all(path_, ignored);
    }
    if (lock_fd_ >= 0) ::close(lock_fd_);
  }
  [[nodiscard]] std::filesystem::path file(const std::string& name) const { return path_ / name; }
  // Moves every staged file into the output folder (through links, into devices: install_output_file).
  Result<std::vector<std::filesystem::path>> commit() {
    std::vector<std::filesystem::path> staged;
    for (const auto& entry : std::filesystem::directory_iterator(path_)) {
      if (entry.path().filename() != kStagingLockName) staged.push_back(entry.path());
    }
    std::sort(staged.begin(), staged.end());
    std::vector<std::filesystem::path> moved;
    for (const auto& file : staged) {
      const auto target = out_dir_ / file.filename();
      if (auto st = install_output_file(file, target); !st) return st.error();
      moved.push_back(target);
    }
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
    path_.clear();
    return moved;
  }

 private:
  StagingDir(std::filesystem::path out_dir, std::filesystem::path path, int lock_fd)
      : out_dir_(std::move(out_dir)), path_(std::move(path)), lock_fd_(lock_fd) {}
  std::filesystem::path out_dir_;
  std::filesystem::path path_;
  int lock_fd_ = -1;
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

struct ReceiverRun {
  const ReceiverSettings* settings = nullptr;
  Eigen::Vector3d marker_m = Eigen::Vector3d::Zero();  // first marker position
  std::shared_ptr<const receiver::KinematicsSource> kinematics;
  std::unique_ptr<receiver::ObservationGenerator> generator;
  io::ObservationHeader header;
  std::unique_ptr<RinexRecordMaker> records;
  io::RinexObsWriter writer;
  std::string file_name;
  std::unique_ptr<RunStreams> streams;  // obs.rtcm3 / fix.nmea when output.rtcm3 / output.nmea
  // RTK: the base of this rover (index into the receivers), and for a base its latest epoch.
  std::optional<size_t> base_index;
  bool is_base = false;
  std::optional<positioning::BaseEpoch> base_epoch;
};

constexpr const char* kTruthHeader =
    "time_gpst,receiver,sat,signal,status,az_deg,el_deg,range_m,range_rate_mps,sat_clock_m,relativistic_m,"
    "group_delay_m,iono_m,tropo_m,rx_clock_m,code_noise_m,phase_noise_m,doppler_noise_mps,ambiguity_cycles,"
    "pseudorange_m,carrier_phase_cycles,doppler_hz,cn0_dbhz,rx_x_m,rx_y_m,rx_z_m,rx_vx_mps,rx_vy_mps,rx_vz_mps,"
    "rx_clock_drift_mps,vegetation_attenuation_db,detail,path_type,code_multipath_m,phase_multipath_m,"
    "multipath_power_db\n";

// paths.csv (models.multipath): every path of every satellite-epoch with any path.
constexpr const char* kPathsHeader =
    "time_gpst,receiver,sat,path,type,reflections,excess_delay_m,relative_power_db,rhcp_power_db,lhcp_power_db,"
    "arrival_az_deg,arrival_el_deg,excess_delay_rate_mps,point_x_m,point_y_m,point_z_m,second_x_m,second_y_m,"
    "second_z_m,object,material,diffraction_v,diffraction_loss_db,vegetation_db\n";

std::string_view path_type_name(PathType type) {
  switch (type) {
    case PathType::kDirect: return "direct";
    case PathType::kReflected: return "reflected";
    case PathType::kDiffracted: return "diffracted";
  }
  return "?";
}

double power_db(std::complex<double> amplitude) { return 10.0 * std::log10(std::max(std::norm(amplitude), 1e-30)); }

std::string csv_text(const std::string& text);

void append_paths(std::string& out, const receiver::EpochObservations& epoch, const std::string& receiver_name) {
  const std::string time = epoch.true_time.to_iso8601(TimeScale::kGpst, 6);
  for (const auto& sat : epoch.satellites) {
    for (size_t k = 0; k < sat.paths.size(); ++k) {
      const SignalPath& p = sat.paths[k];
      const bool second = p.reflections >= 2;
      fmt::format_to(std::back_inserter(out),
                     "{},{},{},{},{},{},{:.4f},{:.2f},{:.2f},{:.2f},{:.4f},{:.4f},{:.5f},{:.3f},{:.3f},{:.3f},{},{},{},{},{},{:.3f},{:.2f},{:.2f}\n",
                     time, receiver_name, sat.satellite.to_string(), k, path_type_name(p.type), p.reflections,
                     p.excess_delay_m, p.relative_power_db(), power_db(p.rhcp_amplitude), power_db(p.lhcp_amplitude),
                     sat.path_directions[k].azimuth_deg, sat.path_directions[k].elevation_deg,
                     sat.path_delay_rates_mps[k], p.point_m.x(), p.point_m.y(), p.point_m.z(),
                     second ? fmt::format("{:.3f}", p.second_point_m.x()) : "", second ? fmt::format("{:.3f}", p.second_point_m.y()) : "",
                     second ? fmt::format("{:.3f}", p.second_point_m.z()) : "", csv_text(p.object),
                     p.type == PathType::kDirect ? "" : world::material_class_name(p.material), p.diffraction_v, p.diffraction_loss_db,
                     p.vegetation_attenuation_db);
    }
  }
}

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
    const bool has_geometry = !(sat.status == receiver::SatelliteStatus::kNoEphemeris && !sat.waiting_for_ephemeris);
    // Geometry cells with a satellite clock: the satellite's, and in a signal's row the clock that
    // signal got (the same one unless the generator gave it another: formatted again only then).
    auto geometry_with = [&](double satellite_clock_m) {
      return has_geometry ? fmt::format("{:.4f},{:.4f},{:.4f},{:.5f},{:.4f},{:.4f}", sat.direction.azimuth_deg,
                                        sat.direction.elevation_deg, sat.range_m, sat.range_rate_mps,
                                        satellite_clock_m, sat.relativistic_m)
                          : std::string(kNoGeometry);
    };
    const std::string geometry = geometry_with(sat.satellite_clock_m);
    // A row per signal its navigation record declares unusable (the others may be tracked).
    for (const auto& unhealthy : sat.unhealthy_signals) {
      fmt::format_to(std::back_inserter(out), "{},{},{},{},unhealthy,{},,,{},{},{},{},{:.2f},{},{},,,\n", time,
                     receiver_name, sat_name, unhealthy.signal.to_string(), geometry,
                     fmt::format("{:.4f}", sat.troposphere_m), rx_clock, kNoSignalValues, receiver_part,
                     sat.vegetation_attenuation_db, csv_text(unhealthy.reason), receiver::to_string(sat.path_kind));
    }
    if (sat.signals.empty() && sat.status == receiver::SatelliteStatus::kUnhealthy) continue;  // said above
    if (sat.signals.empty()) {
      // One row for the satellite: why it is not observed, with the geometry when known.
      const std::string atmosphere = sat.status == receiver::SatelliteStatus::kTracked ||
                                             sat.status == receiver::SatelliteStatus::kNoSignal ||
                                             sat.waiting_for_ephemeris
                                         ? fmt::format("{:.4f},{:.4f}", sat.ionosphere_l1_m, sat.troposphere_m)
                                         : std::string(",");
      fmt::format_to(std::back_inserter(out), "{},{},{},,{},{},,{},{},{},{},{:.2f},{},{},,,\n", time, receiver_name, sat_name,
                     status, geometry, atmosphere, rx_clock, kNoSignalValues, receiver_part,
                     sat.vegetation_attenuation_db, csv_text(sat.detail), receiver::to_string(sat.path_kind));
      continue;
    }
    for (const auto& m : sat.signals) {
      fmt::format_to(std::back_inserter(out),
                     "{},{},{},{},{},{},{:.4f},{:.4f},{:.4f},{},{:.4f},{:.5f},{:.5f},{},{:.4f},{:.4f},{:.4f},{:.3f},{},{:.2f},\n",
                     time, receiver_name, sat_name, m.signal.to_string(), status,
                     m.satellite_clock_m == sat.satellite_clock_m ? geometry : geometry_with(m.satellite_clock_m),
                     m.group_delay_m,
                     m.ionosphere_code_m, sat.troposphere_m, rx_clock, m.code_noise_m, m.phase_noise_m,
                     m.doppler_noise_mps, m.ambiguity_cycles, m.pseudorange_m, m.carrier_phase_cycles, m.doppler_hz,
                     m.cn0_dbhz, receiver_part, sat.vegetation_attenuation_db);
      out.pop_back();  // the row's newline: the multipath cells follow
      fmt::format_to(std::back_inserter(out), ",{},{:.4f},{:.4f},{:.2f}\n", receiver::to_string(sat.path_kind),
                     m.code_multipath_m, m.phase_multipath_m, m.multipath_power_db);
    }
  }
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

Result<RunSummary> run_scenario(const Scenario& s, const std::filesystem::path& out_dir, const RunOptions& options) {
  const auto wall_start = std::chrono::steady_clock::now();
  auto resources = prepare_resources(s);
  if (!resources) return resources.error();
  const std::optional<LoadedWorld>& world = resources->world;
  const orbits::BroadcastEphemerides& ephemerides = *resources->ephemerides;

  if (cancellation_requested()) return cancelled_error();
  auto staging = StagingDir::create(out_dir);
  if (!staging) return staging.error();

  std::vector<ReceiverRun> receivers(s.receivers.size());
  for (size_t i = 0; i < s.receivers.size(); ++i) {
    ReceiverRun& rx = receivers[i];
    rx.settings = &s.receivers[i];
    auto kinematics = make_kinematics(s, *rx.settings, world_origin(s, world), rx.marker_m);
    if (!kinematics) return kinematics.error();
    rx.kinematics = *kinematics;
    auto generator = make_generator(s, *resources, i, rx.kinematics);
    if (!generator) return generator.error();
    rx.generator = std::move(*generator);
    rx.file_name = s.receivers.size() == 1 ? "obs.rnx" : "obs_" + rx.settings->name + ".rnx";
    rx.header = make_observation_header(s, *rx.settings, rx.marker_m, ephemerides, resources->left_out_systems);
    rx.records = std::make_unique<RinexRecordMaker>(rx.header);
    if (auto st = rx.writer.open(staging->file(rx.file_name), rx.header); !st) {
      return st.error();
    }
    std::optional<positioning::RtkSettings> rtk;
    if (rx.settings->rtk && (s.output.nmea || s.output.fix)) {
      auto settings = rtk_settings(s, i, ephemerides);
      if (!settings) return settings.error();
      rtk = std::move(*settings);
      for (size_t j = 0; j < s.receivers.size(); ++j) {
        if (s.receivers[j].name == rx.settings->rtk->base) rx.base_index = j;
      }
    }
    if (s.output.rtcm3 || s.output.nmea || s.output.fix) {
      rx.streams = std::make_unique<RunStreams>(ephemerides, *rx.settings, rx.marker_m, s.output.rtcm3, s.output.nmea,
                                                s.output.fix, std::move(rtk));
    }
  }
  for (const ReceiverRun& rx : receivers) {
    if (rx.base_index) receivers[*rx.base_index].is_base = true;
  }

  std::ofstream truth;
  std::string truth_buffer;
  if (options.write_truth) {
    truth.open(staging->file("truth.csv"), std::ios::binary);
    if (!truth) return make_error(ErrorCode::kOutput, staging->file("truth.csv").string() + ": cannot create");
    truth_buffer = kTruthHeader;
  }
  std::ofstream paths_file;
  std::string paths_buffer;
  const bool write_paths = options.write_truth && s.models.multipath;
  if (write_paths) {
    paths_file.open(staging->file("paths.csv"), std::ios::binary);
    if (!paths_file) return make_error(ErrorCode::kOutput, staging->file("paths.csv").string() + ": cannot create");
    paths_buffer = kPathsHeader;
  }

  RunSummary summary;
  const auto epoch_count = static_cast<std::int64_t>(std::floor(s.time.duration_s / s.time.interval_s + 1e-9)) + 1;
  io::ReportBuilder report;  // of the first receiver
  // Writes one computed epoch of one receiver: RINEX, counts, truth, report.
  auto write_epoch = [&](std::int64_t index, size_t receiver_index, const receiver::EpochObservations& epoch) -> Status {
    if (cancellation_requested()) return cancelled_error();
    ReceiverRun& rx = receivers[receiver_index];
    const io::ObservationEpoch record = rx.records->record(epoch);
    if (auto st = rx.writer.write_epoch(record); !st) return st.error();
    if (rx.streams) {
      if (auto st = rx.streams->add(epoch); !st) return st.error();
    }
    if (rx.is_base) {
      // The base's known position: its marker's antenna reference point.
      rx.base_epoch = positioning::BaseEpoch{to_measurements(epoch), antenna_point(rx.marker_m, *rx.settings)};
    }
    if (receiver_index + 1 == receivers.size()) {
      // Every receiver's epoch is in: the rovers' RTK fixes with their bases' epochs of this instant.
      for (ReceiverRun& rover : receivers) {
        if (!rover.base_index || !rover.streams) continue;
        const auto& base = receivers[*rover.base_index].base_epoch;
        if (auto st = rover.streams->add_base(base ? &*base : nullptr); !st) return st.error();
      }
    }
    for (const auto& sat : epoch.satellites) {
      if (sat.status != receiver::SatelliteStatus::kTracked) continue;
      ++summary.satellite_epochs;
      ++summary.satellite_epochs_per_system[std::string(system_name(sat.satellite.system))];
      summary.observations += static_cast<std::int64_t>(sat.signals.size());
    }
    if (options.write_truth) {
      append_truth(truth_buffer, epoch, rx.settings->name);
      if (write_paths) {
        append_paths(paths_buffer, epoch, rx.settings->name);
        if (paths_buffer.size() > (1u << 20)) {
          paths_file.write(paths_buffer.data(), static_cast<std::streamsize>(paths_buffer.size()));
          paths_buffer.clear();
        }
      }
      if (truth_buffer.size() > (1u << 20)) {
        truth.write(truth_buffer.data(), static_cast<std::streamsize>(truth_buffer.size()));
        truth_buffer.clear();
      }
    }
    if (receiver_index == 0) {
      for (const auto& sat : epoch.satellites) {
        if (sat.status == receiver::SatelliteStatus::kNoEphemeris && !sat.waiting_for_ephemeris) continue;
        io::ReportSample sample;
        sample.time = epoch.receiver_time;
        sample.satellite = sat.satellite;
        sample.azimuth_deg = sat.direction.azimuth_deg;
        sample.elevation_deg = sat.direction.elevation_deg;
        sample.status = std::string(receiver::to_string(sat.status));
        if (!sat.signals.empty()) sample.cn0_dbhz = sat.signals.front().cn0_dbhz;
        sample.vegetation_attenuation_db = sat.vegetation_attenuation_db;
        sample.path_kind = std::string(receiver::to_string(sat.path_kind));
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
  // The models of world.moving go where their trajectories say before an epoch's rays are traced.
  auto move_models = [&](std::int64_t k) -> Status {
    if (!resources->world || resources->world->moving.empty()) return Ok{};
    return move_models_to(*resources->world, epoch_tag(k));
  };

  if (!options.write_truth) {
    // Without truth.csv, writing costs a fraction of computing: one thread does both (measured
    // faster than handing epochs between threads, docs/performance.md).
    for (std::int64_t k = 0; k < epoch_count; ++k) {
      if (auto st = move_models(k); !st) return st.error();
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
      for (std::int64_t k = 0; k < epoch_count && !queue.cancelled() && !cancellation_requested(); ++k) {
        if (auto st = move_models(k); !st) {
          producer_error = st.error();
          queue.close();
          return;
        }
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
    if (rx.streams) {
      const std::string suffix = receivers.size() == 1 ? "" : "_" + rx.settings->name;
      if (auto st = rx.streams->write(staging->file(""), suffix); !st) return st.error();
    }
  }
  if (options.write_truth) {
    truth.write(truth_buffer.data(), static_cast<std::streamsize>(truth_buffer.size()));
    truth.close();
    if (!truth) return make_error(ErrorCode::kOutput, staging->file("truth.csv").string() + ": write failed (disk full?)");
  }
  if (write_paths) {
    paths_file.write(paths_buffer.data(), static_cast<std::streamsize>(paths_buffer.size()));
    paths_file.close();
    if (!paths_file) return make_error(ErrorCode::kOutput, staging->file("paths.csv").string() + ": write failed (disk full?)");
  }
  const orbits::NavigationData used = used_navigation(ephemerides.data(), receivers);
  orbits::RinexNavWriteOptions nav_options;
  nav_options.creation_date = rinex_creation_date(s);
  if (auto st = write_file_atomically(staging->file("nav.rnx"), orbits::format_rinex3_nav(used, nav_options)); !st) {
    return st.error();
  }

  {
    io::ReportMeta meta;
    meta.warnings = resources->warnings;
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
    if (world) {
      const LoadedWorld& w = *world;
      meta.summary_rows.emplace_back("world", w.name + " (" + std::to_string(w.objects) + " objects, " +
                                                  std::to_string(w.buildings) + " buildings, " + std::to_string(w.trees) +
                                                  " trees)");
      meta.warnings.insert(meta.warnings.end(), w.warnings.begin(), w.warnings.end());
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
  if (world) {
    const LoadedWorld& w = *world;
    j["world"] = {{"name", w.name},       {"objects", w.objects},     {"buildings", w.buildings},
                  {"trees", w.trees},     {"triangles", w.triangles}, {"warnings", w.warnings},
                  {"origin", {w.frame.origin.latitude_deg, w.frame.origin.longitude_deg, w.frame.origin.height_m}},
                  {"heading_deg", w.frame.heading_deg}};
  }
  summary.warnings = resources->warnings;
  if (world) summary.warnings.insert(summary.warnings.end(), world->warnings.begin(), world->warnings.end());
  if (resources->precise_coverage) {
    nlohmann::json precise = nlohmann::json::parse(resources->precise_coverage->to_json());
    precise["orbits"] = nlohmann::json::array();
    for (const auto& f : s.ephemeris.precise_orbits) precise["orbits"].push_back(f.filename().string());
    precise["clocks"] = nlohmann::json::array();
    for (const auto& f : s.ephemeris.precise_clocks) precise["clocks"].push_back(f.filename().string());
    j["precise_truth"] = precise;
  }
  j["warnings"] = summary.warnings;
  j["configuration"] = nlohmann::json::parse(scenario_to_json(s));
  if (auto st = write_file_atomically(staging->file("summary.json"), j.dump(2) + "\n"); !st) return st.error();

  if (cancellation_requested()) return cancelled_error();
  auto moved = staging->commit();
  if (!moved) return moved.error();
  summary.outputs = *moved;
  return summary;
}

}  // namespace skytrace::sim
