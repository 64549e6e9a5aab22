#include "skytrace/sim/run.hpp"
#include "skytrace/sim/run_figures.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstring>
#include <condition_variable>
#include <deque>
#include <mutex>
#include <future>
#include <functional>
#include <thread>
#include <cmath>
#include <random>
#include <set>

#include "skytrace/atmosphere/ionex.hpp"
#include "skytrace/core/cancellation.hpp"
#include "skytrace/core/constants.hpp"
#include "skytrace/core/geoid.hpp"
#include "skytrace/core/output_file.hpp"
#include "skytrace/core/text_file.hpp"
#include "skytrace/core/version.hpp"
#include "skytrace/io/rinex_obs.hpp"
#include "skytrace/orbits/broadcast.hpp"
#include "skytrace/orbits/nominal.hpp"
#include "skytrace/orbits/precise.hpp"
#include "skytrace/orbits/rinex_nav.hpp"
#include "skytrace/receiver/observation_generator.hpp"
#include "skytrace/sim/setup.hpp"
#include "skytrace/sim/sinks.hpp"
#include "skytrace/sim/streams.hpp"
#include "skytrace/sim/trajectory.hpp"
#include "skytrace/sim/world_setup.hpp"
#include "skytrace/world/loaders.hpp"

namespace skytrace::sim {
namespace {


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
    if (out_dir.empty()) return make_error(ErrorCode::kOutput, "the output folder is an empty path (--out names it)");
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

constexpr int kMaxThreads = 1024;

// Every receiver's epoch of one instant, with its fix when the run computes fixes.
struct QueuedEpoch {
  std::int64_t index = 0;
  std::vector<receiver::EpochObservations> receivers;
  // What the fix engine reads of each receiver's epoch (empty for a receiver without fixes), taken
  // where the observations were made, while they are in that core's cache.
  std::vector<positioning::EpochMeasurements> measurements;
  std::vector<std::optional<positioning::PositionFix>> fixes;
};
using EpochBatch = std::vector<QueuedEpoch>;

// A bounded single-producer single-consumer queue of computed epochs, in batches. Spent batches go
// back to the producer, which fills them again: their storage is allocated once, by the thread that
// uses it, and no thread contends for the allocator's locks.
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
  // nullopt once the producer has closed the queue and it is empty, or once it is cancelled.
  std::optional<EpochBatch> pop() {
    std::unique_lock lock(mutex_);
    not_empty_.wait(lock, [&] { return !full_.empty() || closed_ || cancelled_; });
    if (full_.empty() || cancelled_) return std::nullopt;
    EpochBatch batch = std::move(full_.front());
    full_.pop_front();
    not_full_.notify_one();
    return batch;
  }
  void give_back(EpochBatch batch) {
    std::lock_guard lock(mutex_);
    spent_.push_back(std::move(batch));
  }
  // A spent batch for the producer to fill again (empty when none is back yet).
  EpochBatch reuse_spent() {
    std::lock_guard lock(mutex_);
    if (spent_.empty()) return {};
    EpochBatch batch = std::move(spent_.back());
    spent_.pop_back();
    return batch;
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
    not_empty_.notify_all();
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

// Threads that stay for the run and do their share of each batch of work: share 0 on the caller's
// thread, shares 1 .. size - 1 on their own (long-lived threads are spread over the cores by the
// scheduler, where threads started for each batch were measured sharing the caller's core).
class ObserverCrew {
 public:
  explicit ObserverCrew(size_t size) {
    for (size_t share = 1; share < size; ++share) threads_.emplace_back([this, share] { serve(share); });
  }
  ObserverCrew(const ObserverCrew&) = delete;
  ObserverCrew& operator=(const ObserverCrew&) = delete;
  ~ObserverCrew() {
    {
      std::lock_guard lock(mutex_);
      stopping_ = true;
    }
    start_.notify_all();
    for (std::thread& t : threads_) t.join();
  }
  // Runs work(share) for every share, returning when all are done.
  void run(const std::function<void(size_t)>& work) {
    {
      std::lock_guard lock(mutex_);
      work_ = &work;
      pending_ = threads_.size();
      ++generation_;
    }
    start_.notify_all();
    work(0);
    std::unique_lock lock(mutex_);
    done_.wait(lock, [&] { return pending_ == 0; });
    work_ = nullptr;
  }

 private:
  void serve(size_t share) {
    std::uint64_t seen = 0;
    for (;;) {
      const std::function<void(size_t)>* work = nullptr;
      {
        std::unique_lock lock(mutex_);
        start_.wait(lock, [&] { return stopping_ || generation_ != seen; });
        if (stopping_) return;
        seen = generation_;
        work = work_;
      }
      (*work)(share);
      std::lock_guard lock(mutex_);
      if (--pending_ == 0) done_.notify_one();
    }
  }

  std::vector<std::thread> threads_;
  std::mutex mutex_;
  std::condition_variable start_, done_;
  const std::function<void(size_t)>* work_ = nullptr;
  size_t pending_ = 0;
  std::uint64_t generation_ = 0;
  bool stopping_ = false;
};

struct ReceiverRun {
  const ReceiverSettings* settings = nullptr;
  Eigen::Vector3d marker_m = Eigen::Vector3d::Zero();  // first marker position
  std::shared_ptr<const receiver::KinematicsSource> kinematics;
  std::unique_ptr<receiver::ObservationGenerator> generator;
  io::ObservationHeader header;
  std::unique_ptr<FixStage> fixes;  // when a sink needs position fixes
  // RTK: the base of this rover (index into the receivers), and whether this one is a base.
  std::optional<size_t> base_index;
  bool is_base = false;
};


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
  if (options.threads < 0 || options.threads > kMaxThreads) {
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("threads {}: expected 1 to {} (0: one per hardware thread)", options.threads, kMaxThreads));
  }
  const int threads = options.threads > 0 ? options.threads : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
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
    rx.header = make_observation_header(s, *rx.settings, rx.marker_m, ephemerides, resources->left_out_systems,
                                        rx.generator->settings().profile.antenna_rinex_type);
  }

  if (world && world->has_objects) {
    // A receiver the world cannot touch (above every roof, below every base, beyond its extent) is
    // most often a height or origin given wrongly (OSM and footprints have no terrain heights).
    for (const ReceiverRun& rx : receivers) {
      const auto start = rx.kinematics->at(s.time.start);
      if (!start) continue;
      const Eigen::Vector3d p = world->frame.from_ecef(start->position_m);
      const double ground_m = world->frame.origin.height_m;
      const std::string who = "receiver '" + rx.settings->name + "'";
      // High above the ground with no object below it: hovering over a street (a rooftop antenna
      // stands over its building's footprint).
      constexpr double kHigh_m = 10.0;
      const auto over = [&](const world::Footprint& f) {
        for (size_t i = 0; i < f.outline_m.size(); ++i) {
          const Eigen::Vector2d& a = f.outline_m[i];
          const Eigen::Vector2d& b = f.outline_m[(i + 1) % f.outline_m.size()];
          if ((b - a).x() * (p.y() - a.y()) - (b - a).y() * (p.x() - a.x()) < 0.0) return false;  // counter-clockwise hull
        }
        return true;
      };
      if (p.z() > kHigh_m && std::none_of(world->footprints.begin(), world->footprints.end(), over)) {
        resources->warnings.push_back(fmt::format(
            "{} starts {:.1f} m above the world's ground ({:.1f} m above the ellipsoid) over no object{}: is the "
            "receiver's height or world.elevation_m (the ground's ellipsoidal height) right?",
            who, p.z(), ground_m,
            p.z() > world->high_m.z() ? fmt::format(", above every object (the tallest reaches {:.1f} m)", world->high_m.z())
                                      : std::string()));
      } else if (p.z() < world->low_m.z() - 2.0) {
        resources->warnings.push_back(fmt::format(
            "{} starts {:.1f} m below the world's ground ({:.1f} m above the ellipsoid), below the base of every "
            "object ({:.1f} m): is the receiver's height or world.elevation_m right?",
            who, -p.z(), ground_m, world->low_m.z()));
      }
      constexpr double kBeyond_m = 100.0;
      if (p.x() < world->low_m.x() - kBeyond_m || p.x() > world->high_m.x() + kBeyond_m ||
          p.y() < world->low_m.y() - kBeyond_m || p.y() > world->high_m.y() + kBeyond_m) {
        resources->warnings.push_back(fmt::format(
            "{} starts at ({:.0f}, {:.0f}) m in the world frame, more than {:.0f} m outside the world's objects "
            "(x {:.0f} to {:.0f}, y {:.0f} to {:.0f} m): the world has little to block there",
            who, p.x(), p.y(), kBeyond_m, world->low_m.x(), world->high_m.x(), world->low_m.y(), world->high_m.y()));
      }
    }
  }

  RunSummary summary;
  RunContext context;
  context.scenario = &s;
  context.resources = &*resources;
  context.staging_dir = staging->file("");
  context.write_truth = options.write_truth;
  context.threads = threads;
  context.summary = &summary;
  const auto epoch_count = static_cast<std::int64_t>(std::floor(s.time.duration_s / s.time.interval_s + 1e-9)) + 1;
  const auto epoch_tag = [&](std::int64_t k) { return s.time.start + static_cast<double>(k) * s.time.interval_s; };
  context.epoch_grid = EpochGrid{epoch_tag(0), epoch_tag(epoch_count - 1), s.time.interval_s};
  for (const ReceiverRun& rx : receivers) {
    context.receivers.push_back(SinkReceiver{rx.settings, rx.marker_m, &rx.header, rx.kinematics,
                                             receivers.size() == 1 ? "" : "_" + rx.settings->name});
  }
  if (run_needs_fixes(context)) {
    for (size_t i = 0; i < receivers.size(); ++i) {
      ReceiverRun& rx = receivers[i];
      std::optional<positioning::RtkSettings> rtk;
      if (rx.settings->rtk) {
        auto settings = rtk_settings(s, i, ephemerides);
        if (!settings) return settings.error();
        rtk = std::move(*settings);
        for (size_t j = 0; j < s.receivers.size(); ++j) {
          if (s.receivers[j].name == rx.settings->rtk->base) rx.base_index = j;
        }
      }
      rx.fixes = std::make_unique<FixStage>(ephemerides, *rx.settings, std::move(rtk));
    }
    for (const ReceiverRun& rx : receivers) {
      if (rx.base_index) receivers[*rx.base_index].is_base = true;
    }
  }
  auto sinks = make_run_sinks(context);
  if (!sinks) return sinks.error();
  auto figures_sink = std::make_unique<RunFigures>(context.receivers);
  const RunFigures& figures = *figures_sink;
  sinks->push_back(std::move(figures_sink));

  // The bases' recent epochs: a rover takes the latest one that has reached it (rtk.latency_s,
  // rtk.interval_s, rtk.outages_s); older than the engine's age limit is never used.
  constexpr double kBaseHistory_s = 90.0;
  std::vector<std::deque<positioning::BaseEpoch>> base_history(receivers.size());
  auto base_for = [&](size_t rover, const GnssTime& rover_time) -> const positioning::BaseEpoch* {
    const RtkSettings& link = *receivers[rover].settings->rtk;
    const auto& history = base_history[*receivers[rover].base_index];
    for (auto it = history.rbegin(); it != history.rend(); ++it) {
      const GnssTime sent = it->measurements.receiver_time;
      if (link.interval_s > 0.0) {
        const double since_start_s = sent - s.time.start;
        const double phase_s = since_start_s - link.interval_s * std::round(since_start_s / link.interval_s);
        if (std::abs(phase_s) > 1e-3) continue;  // the base does not send this epoch
      }
      const GnssTime arrival = sent + link.latency_s;
      if (arrival - rover_time > 1e-3) continue;  // not here yet
      const double arrival_s = arrival - s.time.start;
      const bool lost = std::any_of(link.outages_s.begin(), link.outages_s.end(), [&](const auto& outage) {
        return arrival_s >= outage.first && arrival_s < outage.second;
      });
      if (lost) continue;
      return &*it;
    }
    return nullptr;
  };
  // The receivers' fixes of one instant: the bases' epochs first, so that their rovers' RTK fixes
  // have this instant's corrections. Computed where the observations are (the worker thread when
  // there is one), which balances the two threads.
  auto solve_instant = [&](QueuedEpoch& instant) -> Status {
    const auto& epochs = instant.receivers;
    instant.fixes.assign(receivers.size(), std::nullopt);
    // Receivers that are not RTK rovers first (the bases among them), then the rovers.
    for (const bool rovers : {false, true}) {
      for (size_t i = 0; i < receivers.size(); ++i) {
        ReceiverRun& rx = receivers[i];
        if (!rx.fixes || rx.base_index.has_value() != rovers) continue;
        const positioning::BaseEpoch* base = rx.base_index ? base_for(i, epochs[i].receiver_time) : nullptr;
        std::optional<positioning::BaseEpoch> moving;
        if (base != nullptr && rx.settings->rtk->moving_base) {
          // A moving base knows where it is only from its own fix of that epoch.
          const auto& base_fix = instant.fixes[*rx.base_index];
          if (base_fix && base_fix->type != positioning::FixType::kNone &&
              std::abs(base->measurements.receiver_time - epochs[*rx.base_index].receiver_time) < 1e-3) {
            moving = positioning::BaseEpoch{base->measurements, base_fix->position_ecef_m};
          }
          base = moving ? &*moving : nullptr;
        }
        auto fix = rx.fixes->solve(instant.measurements[i], base);
        if (!fix) return fix.error();
        if (moving) positioning::add_baseline_heading(*fix);
        instant.fixes[i] = std::move(*fix);
      }
      if (rovers) break;
      for (size_t i = 0; i < receivers.size(); ++i) {
        if (!receivers[i].is_base) continue;
        // The base's known position: its marker's antenna reference point.
        auto& history = base_history[i];
        history.push_back(positioning::BaseEpoch{instant.measurements[i],
                                                 antenna_point(receivers[i].marker_m, *receivers[i].settings)});
        while (history.back().measurements.receiver_time - history.front().measurements.receiver_time > kBaseHistory_s) {
          history.pop_front();
        }
      }
    }
    return Ok{};
  };
  // Tracked satellite-epochs per system, counted by index (summary.satellite_epochs_per_system is
  // filled from them once the epochs are written, before the sinks end their files).
  std::array<std::int64_t, kAllSystems.size()> tracked_per_system{};
  std::vector<std::int64_t> tracked_per_receiver(receivers.size(), 0);
  // Hands every receiver's epoch of one instant to the sinks.
  auto write_instant = [&](const QueuedEpoch& instant) -> Status {
    if (cancellation_requested()) return cancelled_error();
    const std::int64_t index = instant.index;
    const auto& epochs = instant.receivers;
    for (size_t i = 0; i < receivers.size(); ++i) {
      const receiver::EpochObservations& epoch = epochs[i];
      for (const auto& sat : epoch.satellites) {
        if (sat.status != receiver::SatelliteStatus::kTracked) continue;
        ++summary.satellite_epochs;
        ++tracked_per_system[static_cast<size_t>(sat.satellite.system)];
        ++tracked_per_receiver[i];
        summary.observations += static_cast<std::int64_t>(sat.signals.size());
      }
      const auto& fix = instant.fixes[i];
      const SinkEpoch sink_epoch{index, i, &context.receivers[i], &epoch, fix ? &*fix : nullptr};
      for (auto& sink : *sinks) {
        if (auto st = sink->add(sink_epoch); !st) return st;
      }
    }
    ++summary.epochs;
    if (options.progress) options.progress(index + 1, epoch_count);
    return Ok{};
  };
  // The models of world.moving go where their trajectories say before an epoch's rays are traced.
  auto move_models = [&](std::int64_t k) -> Status {
    if (!resources->world || resources->world->moving.empty()) return Ok{};
    return move_models_to(*resources->world, epoch_tag(k));
  };
  // What the fix engine reads of receiver i's epoch: receivers with fixes, and RTK bases (their
  // rovers' corrections), need it.
  auto measure = [&](size_t i, QueuedEpoch& item) {
    if (receivers[i].fixes != nullptr || receivers[i].is_base) {
      to_measurements(item.receivers[i], item.measurements[i]);
    } else {
      item.measurements[i] = positioning::EpochMeasurements{};
    }
  };
  // Every receiver's observations at epoch k.
  auto observe_only = [&](std::int64_t k, QueuedEpoch& out) -> Status {
    if (auto st = move_models(k); !st) return st;
    out.index = k;
    // The storage of an earlier epoch is reused (the generator overwrites every field).
    out.receivers.resize(receivers.size());
    out.measurements.resize(receivers.size());
    for (size_t i = 0; i < receivers.size(); ++i) {
      ReceiverRun& rx = receivers[i];
      if (auto st = rx.generator->observe(epoch_tag(k), out.receivers[i]); !st) return st;
      measure(i, out);
    }
    return Ok{};
  };
  auto observe_instant = [&](std::int64_t k, QueuedEpoch& out) -> Status {
    if (auto st = observe_only(k, out); !st) return st;
    return solve_instant(out);
  };
  const bool computes_fixes = std::any_of(receivers.begin(), receivers.end(), [](const ReceiverRun& rx) { return rx.fixes != nullptr; });
  const bool pipeline = threads > 1 && (options.write_truth || computes_fixes);
  // Receivers observed side by side: each receiver's generator keeps its state from epoch to
  // epoch and shares nothing that changes with the others (the world's path caches give the same
  // paths whoever fills them), so a batch of epochs can be split by receiver among threads, every
  // receiver's epochs in order, and the outputs are the same bytes for any split. The computing
  // threads beyond the fix stage's observe; models that move with the epochs (world.moving) keep
  // one thread, as they are placed for one epoch at a time.
  const bool models_move = resources->world && !resources->world->moving.empty();
  const size_t observers =
      models_move ? 1
                  : std::min(receivers.size(),
                             static_cast<size_t>(std::max(1, pipeline && computes_fixes ? threads - 1 : threads)));
  ObserverCrew observer_crew(observers);
  // Observes the instants k0 .. k0 + count - 1 into batch[0 .. count) (every receiver: the
  // observations and what the fix engine reads of them), the receivers dealt in turn to
  // `observers` threads. The error of the earliest epoch (then receiver) is the one returned.
  auto observe_batch = [&](std::int64_t k0, EpochBatch& batch, size_t count) -> Status {
    for (size_t j = 0; j < count; ++j) {
      batch[j].index = k0 + static_cast<std::int64_t>(j);
      batch[j].receivers.resize(receivers.size());
      batch[j].measurements.resize(receivers.size());
    }
    std::vector<std::optional<std::pair<std::pair<std::int64_t, size_t>, Error>>> errors(observers);
    const std::function<void(size_t)> observe_share = [&](size_t share) {
      for (size_t i = share; i < receivers.size(); i += observers) {
        ReceiverRun& rx = receivers[i];
        for (size_t j = 0; j < count; ++j) {
          QueuedEpoch& item = batch[j];
          if (auto st = rx.generator->observe(epoch_tag(item.index), item.receivers[i]); !st) {
            auto& first = errors[share];
            if (!first || std::pair{item.index, i} < first->first) first.emplace(std::pair{item.index, i}, st.error());
            break;  // its later epochs need this one's state
          }
          measure(i, item);
        }
      }
    };
    observer_crew.run(observe_share);
    const std::pair<std::pair<std::int64_t, size_t>, Error>* earliest = nullptr;
    for (const auto& e : errors) {
      if (e && (earliest == nullptr || e->first < earliest->first)) earliest = &*e;
    }
    if (earliest != nullptr) return earliest->second;
    return Ok{};
  };
  // Receiver-epochs per batch: 64 per observing thread.
  const size_t batch_receiver_epochs = 64 * observers;

  if (!pipeline) {
    // One thread writes: a run given one thread, and one without truth or fixes, where writing
    // costs a fraction of computing (measured faster than handing epochs between threads,
    // docs/performance.md); it also computes, unless several receivers are observed side by side.
    if (observers == 1) {
      QueuedEpoch instant;
      for (std::int64_t k = 0; k < epoch_count; ++k) {
        if (auto st = observe_instant(k, instant); !st) return st.error();
        if (auto st = write_instant(instant); !st) return st.error();
      }
    } else {
      EpochBatch batch(std::max<size_t>(1, batch_receiver_epochs / receivers.size()));
      for (std::int64_t k0 = 0; k0 < epoch_count; k0 += static_cast<std::int64_t>(batch.size())) {
        const auto count = static_cast<size_t>(std::min<std::int64_t>(static_cast<std::int64_t>(batch.size()), epoch_count - k0));
        if (cancellation_requested()) return cancelled_error();
        if (auto st = observe_batch(k0, batch, count); !st) return st.error();
        for (size_t j = 0; j < count; ++j) {
          if (auto st = solve_instant(batch[j]); !st) return st.error();
          if (auto st = write_instant(batch[j]); !st) return st.error();
        }
      }
    }
  } else {
    // With truth or fixes, the epochs are computed on threads of their own while this thread formats
    // and writes them: a pipeline of stages, each keeping its order (the generators and the fix
    // engines keep state from epoch to epoch): the observations, then (when a sink wants them) the
    // fixes, then the writing. The stages share the cores; three of them on two cores measured
    // faster than two (docs/performance.md).
    // Small batches and short queues: the epochs in flight (8 x 16 per queue, about 50 kB each with
    // truth) stay within the shared cache between the core that makes them and the one that reads
    // them; 64 x 8 went through memory and cost 8 % more CPU than one thread (docs/performance.md).
    constexpr size_t kBatchEpochs = 8;
    constexpr size_t kQueuedBatches = 16;
    EpochQueue observed(kQueuedBatches), solved(kQueuedBatches);
    const bool fix_stage = computes_fixes;
    EpochQueue& to_writer = fix_stage ? solved : observed;
    std::optional<Error> producer_error, fixer_error;
    std::thread producer([&] {
      EpochBatch batch;
      if (observers > 1) {
        // Several receivers side by side: whole batches at once.
        const size_t epochs_per_batch = std::max<size_t>(1, batch_receiver_epochs / receivers.size());
        for (std::int64_t k0 = 0; k0 < epoch_count && !observed.cancelled() && !cancellation_requested();
             k0 += static_cast<std::int64_t>(epochs_per_batch)) {
          const auto count = static_cast<size_t>(std::min<std::int64_t>(static_cast<std::int64_t>(epochs_per_batch), epoch_count - k0));
          batch.resize(count);
          Status st = observe_batch(k0, batch, count);
          for (size_t j = 0; st && !fix_stage && j < count; ++j) st = solve_instant(batch[j]);
          if (!st) {
            producer_error = st.error();
            observed.close();
            return;
          }
          if (!observed.push(std::move(batch))) return;
          batch = observed.reuse_spent();
        }
        observed.close();
        return;
      }
      size_t filled = 0;  // items of `batch` holding this batch's epochs (a reused batch has more)
      size_t receiver_epochs = 0;
      for (std::int64_t k = 0; k < epoch_count && !observed.cancelled() && !cancellation_requested(); ++k) {
        QueuedEpoch& item = filled < batch.size() ? batch[filled] : batch.emplace_back();
        ++filled;
        if (auto st = fix_stage ? observe_only(k, item) : observe_instant(k, item); !st) {
          producer_error = st.error();
          observed.close();
          return;
        }
        receiver_epochs += receivers.size();
        if (receiver_epochs >= kBatchEpochs) {
          batch.resize(filled);
          if (!observed.push(std::move(batch))) return;
          batch = observed.reuse_spent();
          filled = 0;
          receiver_epochs = 0;
        }
      }
      batch.resize(filled);
      if (!batch.empty()) observed.push(std::move(batch));
      observed.close();
    });
    std::thread fixer;
    if (fix_stage) {
      fixer = std::thread([&] {
        while (auto batch = observed.pop()) {
          for (QueuedEpoch& item : *batch) {
            if (auto st = solve_instant(item); !st) {
              fixer_error = st.error();
              observed.cancel();
              solved.close();
              return;
            }
          }
          if (!solved.push(std::move(*batch))) {
            observed.cancel();
            return;
          }
        }
        solved.close();
      });
    }
    Status consumed = Ok{};
    while (auto batch = to_writer.pop()) {
      for (const QueuedEpoch& item : *batch) {
        consumed = write_instant(item);
        if (!consumed) break;
      }
      if (!consumed) break;
      observed.give_back(std::move(*batch));  // filled again by the producer, which allocated it
    }
    if (!consumed) {
      to_writer.cancel();
      observed.cancel();
    }
    if (fixer.joinable()) fixer.join();
    producer.join();
    if (producer_error) return *producer_error;
    if (fixer_error) return *fixer_error;
    if (!consumed) return consumed.error();
  }
  for (const GnssSystem system : kAllSystems) {
    const std::int64_t count = tracked_per_system[static_cast<size_t>(system)];
    if (count > 0) summary.satellite_epochs_per_system[std::string(system_name(system))] = count;
  }
  // A receiver that tracked nothing would leave files without an observation and no word why (in
  // the report too: the sinks read the warnings when they end, below).
  for (size_t i = 0; i < receivers.size(); ++i) {
    if (tracked_per_receiver[i] > 0) continue;
    const ReceiverSettings& rx = *context.receivers[i].settings;
    std::string signals;
    for (const Signal& signal : rx.signals) signals += (signals.empty() ? "" : ", ") + signal.to_string();
    resources->warnings.push_back(fmt::format(
        "receiver '{}' tracked no signal in the whole run (signals {}; elevation mask {:g} deg): check the mask, "
        "which of these signals the satellites transmit at this date, and whether the world hides the antenna",
        rx.name, signals, rx.elevation_mask_deg));
  }
  // The sinks end their files (the report draws its pages then, the bag and the compressed truth
  // write their last blocks): side by side when threads allow; errors in the sinks' order.
  if (threads >= 2 && sinks->size() > 1) {
    std::vector<std::future<Status>> finishing;
    finishing.reserve(sinks->size());
    for (auto& sink : *sinks) finishing.push_back(std::async(std::launch::async, [&sink] { return sink->finish(); }));
    std::optional<Error> first_error;
    for (auto& f : finishing) {
      Status st = f.get();
      if (!st && !first_error) first_error = st.error();
    }
    if (first_error) return *first_error;
  } else {
    for (auto& sink : *sinks) {
      if (auto st = sink->finish(); !st) return st.error();
    }
  }
  const orbits::NavigationData used = used_navigation(ephemerides.data(), receivers);
  orbits::RinexNavWriteOptions nav_options;
  nav_options.creation_date = rinex_creation_date(s);
  if (auto st = write_file_atomically(staging->file("nav.rnx"), orbits::format_rinex3_nav(used, nav_options)); !st) {
    return st.error();
  }

  summary.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  nlohmann::json j;
  j["skytrace_version"] = std::string("skytrace ") + version();
  j["scenario"] = s.name;
  j["epochs"] = summary.epochs;
  j["satellite_epochs"] = summary.satellite_epochs;
  j["satellite_epochs_per_system"] = summary.satellite_epochs_per_system;
  j["signal_observations"] = summary.observations;
  j["navigation_records_used"] = used.record_count();
  j["wall_time_s"] = summary.wall_time_s;
  j["receivers"] = figures.to_json();
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
  // Which heights fix.nmea's GGA gives (above mean sea level with a geoid model, or ellipsoidal).
  if (s.output.fix && s.output.nmea) j["nmea_heights"] = default_geoid_note();
  j["configuration"] = nlohmann::json::parse(scenario_to_json(s));
  if (auto st = write_file_atomically(staging->file("summary.json"), j.dump(2) + "\n"); !st) return st.error();

  if (cancellation_requested()) return cancelled_error();
  auto moved = staging->commit();
  if (!moved) return moved.error();
  summary.outputs = *moved;
  return summary;
}

}  // namespace skytrace::sim
