// Outputs as sinks of one epoch stream. A run computes, per instant, every receiver's observations
// and (when some sink wants it) its position fix, and hands each receiver's epoch to every sink in
// order; a sink writes its file (or stream) as epochs come, so memory does not grow with the run's
// length, and completes it in finish(). The outputs of `skytrace run` are the lines of
// run_sink_table() (src/sim/sinks.cpp): a new output is one sink class and one line there.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "skytrace/core/error.hpp"
#include "skytrace/io/rinex_obs.hpp"
#include "skytrace/io/rtcm3.hpp"
#include "skytrace/orbits/broadcast.hpp"
#include "skytrace/positioning/spp.hpp"
#include "skytrace/receiver/observation_generator.hpp"
#include "skytrace/sim/scenario.hpp"
#include "skytrace/sim/setup.hpp"

namespace skytrace::sim {

struct RunSummary;

// A receiver of the run as the sinks know it.
struct SinkReceiver {
  const ReceiverSettings* settings = nullptr;
  Eigen::Vector3d marker_m = Eigen::Vector3d::Zero();  // first marker position, ECEF
  const io::ObservationHeader* header = nullptr;       // of its RINEX observations
  std::shared_ptr<const receiver::KinematicsSource> kinematics;
  // Inserted before the extension of its files: "" when the run has one receiver, else "_NAME".
  std::string file_suffix;
};

// A run's epoch tags: first, last and the step between them.
struct EpochGrid {
  GnssTime first;
  GnssTime last;
  double interval_s = 0.0;
};

// What every sink may use: the scenario, what was loaded for it, the receivers, and where files go.
struct RunContext {
  const Scenario* scenario = nullptr;
  const ScenarioResources* resources = nullptr;
  std::filesystem::path staging_dir;  // files written here are moved into --out when the run succeeds
  std::vector<SinkReceiver> receivers;
  bool write_truth = true;
  int threads = 1;  // threads the run may use: a sink starts threads of its own only from 2 on
  const RunSummary* summary = nullptr;  // the run's counts, complete when finish() is called
  std::optional<EpochGrid> epoch_grid;  // known before a run over a scenario's time (none when live)
};

// One receiver's epoch.
struct SinkEpoch {
  std::int64_t index = 0;  // epoch number from the start
  size_t receiver_index = 0;
  const SinkReceiver* receiver = nullptr;
  const receiver::EpochObservations* observations = nullptr;
  // The receiver's fix at this epoch (an RTK rover's with its base's corrections); nullptr when
  // no sink of the run asked for fixes.
  const positioning::PositionFix* fix = nullptr;
  // Live receivers only (a run never has them): the time went back and tracking restarted; the
  // external pose had timed out.
  bool restarted = false;
  bool pose_stale = false;
};

class EpochSink {
 public:
  virtual ~EpochSink() = default;
  [[nodiscard]] virtual Status add(const SinkEpoch& epoch) = 0;
  // Completes the outputs (after the last epoch of every receiver).
  [[nodiscard]] virtual Status finish() = 0;
};

// One kind of output of `skytrace run`.
struct SinkKind {
  const char* name;  // for messages and docs: "obs.rnx", "truth.csv", ...
  bool (*wanted)(const RunContext& context);
  bool needs_fixes;  // the run computes position fixes only when a wanted sink needs them
  Result<std::unique_ptr<EpochSink>> (*make)(const RunContext& context);
};
[[nodiscard]] const std::vector<SinkKind>& run_sink_table();

// The sinks the scenario's output keys ask for, in table order.
[[nodiscard]] Result<std::vector<std::unique_ptr<EpochSink>>> make_run_sinks(const RunContext& context);
[[nodiscard]] bool run_needs_fixes(const RunContext& context);

// obs.rnx (or obs_NAME.rnx per receiver) in the staging folder: RINEX 3 observations.
[[nodiscard]] Result<std::unique_ptr<EpochSink>> make_rinex_obs_sink(const RunContext& context);

// Byte-stream outputs are an encoding (NMEA, RTCM 3, fix CSV) of one receiver's epochs sent to a
// destination (a file, TCP clients, a pseudo-terminal): StreamSink joins one of each.
class StreamEncoder {
 public:
  virtual ~StreamEncoder() = default;
  [[nodiscard]] virtual std::string header() const { return {}; }  // sent once, before the first epoch
  [[nodiscard]] virtual Result<std::string> encode(const SinkEpoch& epoch) = 0;
};
class ByteStream {
 public:
  virtual ~ByteStream() = default;
  [[nodiscard]] virtual Status write(std::string_view bytes) = 0;
  [[nodiscard]] virtual Status close() { return Ok{}; }
  // A buffer the caller may append to in place instead of write() (nullptr: none), and the call
  // that takes what was appended.
  [[nodiscard]] virtual std::string* append_buffer() { return nullptr; }
  [[nodiscard]] virtual Status commit_appended() { return Ok{}; }
};

// NMEA 0183 sentences of the epoch's fix (none without a fix).
[[nodiscard]] std::unique_ptr<StreamEncoder> make_nmea_encoder();
// fix.csv rows (io/fix_csv), with the header.
[[nodiscard]] std::unique_ptr<StreamEncoder> make_fix_csv_encoder();
// The RTCM 3 stream of the receiver as a reference station: MSM7 observations, 1006, and the
// ephemeris messages of the records in use.
[[nodiscard]] std::unique_ptr<StreamEncoder> make_rtcm3_encoder(const orbits::BroadcastEphemerides& ephemerides,
                                                                const io::RtcmStation& station);

class StreamSink final : public EpochSink {
 public:
  StreamSink(size_t receiver_index, std::unique_ptr<StreamEncoder> encoder, std::unique_ptr<ByteStream> stream)
      : receiver_index_(receiver_index), encoder_(std::move(encoder)), stream_(std::move(stream)) {}
  Status add(const SinkEpoch& epoch) override;
  Status finish() override;

 private:
  size_t receiver_index_;
  std::unique_ptr<StreamEncoder> encoder_;
  std::unique_ptr<ByteStream> stream_;
  bool started_ = false;
};

// Several sinks as one (one per receiver, say).
class SinkGroup final : public EpochSink {
 public:
  void add_sink(std::unique_ptr<EpochSink> sink) { sinks_.push_back(std::move(sink)); }
  Status add(const SinkEpoch& epoch) override;
  Status finish() override;

 private:
  std::vector<std::unique_ptr<EpochSink>> sinks_;
};

// A file written as it grows (through a 1 MiB buffer); errors name the file.
class StagedFile final : public ByteStream {
 public:
  [[nodiscard]] static Result<std::unique_ptr<StagedFile>> create(const std::filesystem::path& path);
  ~StagedFile() override;
  [[nodiscard]] Status write(std::string_view bytes) override;
  [[nodiscard]] Status close() override;
  [[nodiscard]] const std::filesystem::path& path() const { return path_; }

 private:
  StagedFile(std::filesystem::path path, std::FILE* file) : path_(std::move(path)), file_(file) {}
  [[nodiscard]] Status flush();
  std::filesystem::path path_;
  std::FILE* file_ = nullptr;
  std::string buffer_;
};

// IQ samples of the first receiver's antenna and a GNSS-SDR configuration (output.iq; src/sim/iq_sink.cpp).
[[nodiscard]] Result<std::unique_ptr<EpochSink>> make_iq_sink(const RunContext& context);

// The McapSink of output.mcap (src/sim/mcap_sink.cpp): a rosbag2 folder with the ROS 2 topics.
[[nodiscard]] Result<std::unique_ptr<EpochSink>> make_mcap_sink(const RunContext& context);

}  // namespace skytrace::sim
