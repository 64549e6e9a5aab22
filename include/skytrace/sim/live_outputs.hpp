// The outputs of a live receiver (the ROS 1 and ROS 2 nodes, the Gazebo bridge) as sinks of its
// epoch stream: the node's own publishers, and the files its parameters ask for, made from one
// table (live_file_table()) with the encoders `skytrace run` uses. A new file output of every node
// is one line of that table: each node reads the table's parameter names.
//
// A file is written into a hidden folder beside its target and moved into place by finish(), so
// that a node stopped early, or a disk that fills up, leaves no partial file: the failing file is
// dropped (and said so) while the node and its other outputs go on.
#pragma once

#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "skytrace/core/error.hpp"
#include "skytrace/sim/live.hpp"
#include "skytrace/sim/sinks.hpp"

namespace skytrace::sim {

// One kind of file a live receiver can write as it runs.
struct LiveFileKind {
  const char* parameter;    // the node parameter (ROS) or option (`skytrace gz --rinex-out`) with its path
  const char* description;  // for help texts: "RINEX 3 observations"
  bool needs_fix;           // written from the receiver's position fix (NMEA, fix CSV)
  // Makes the sink, writing `staged_name` inside context.staging_dir.
  const char* staged_name;
  Result<std::unique_ptr<EpochSink>> (*make)(const RunContext& context);
};
[[nodiscard]] const std::vector<LiveFileKind>& live_file_table();

class LiveOutputs {
 public:
  // `paths`: parameter name -> target path (empty paths are left out); a parameter not in the table
  // is refused. `interval_s` is the receiver's epoch interval (RINEX header). Errors name the parameter.
  [[nodiscard]] static Result<std::unique_ptr<LiveOutputs>> open(
      const LiveSession& session, const std::vector<std::pair<std::string, std::string>>& paths, double interval_s);
  ~LiveOutputs();
  LiveOutputs(const LiveOutputs&) = delete;
  LiveOutputs& operator=(const LiveOutputs&) = delete;

  // A publisher of the node, given every epoch before the files.
  void add_publisher(std::unique_ptr<EpochSink> publisher);
  // True when some output needs the receiver's fix (the session computes one anyway when it solves).
  [[nodiscard]] bool needs_fix() const;

  // Hands the epoch to the publishers, then to the files. Epochs whose time does not advance (a
  // simulation reset) are not written to the files. Problems that do not stop the node (a file
  // dropped, an epoch left out) are returned as messages naming the parameter and path.
  [[nodiscard]] std::vector<std::string> add(const LiveEpoch& epoch);
  // Completes every file and moves it into place. Returns one line per file: "PARAMETER PATH" when
  // written, or the error naming the parameter and path.
  struct Finished {
    std::vector<std::string> written;  // "rinex_out /path/obs.rnx"
    std::vector<std::string> errors;
  };
  [[nodiscard]] Finished finish();

 private:
  LiveOutputs() = default;
  struct File;
  std::vector<std::unique_ptr<EpochSink>> publishers_;
  std::vector<std::unique_ptr<File>> files_;
  std::unique_ptr<io::ObservationHeader> header_;
  std::unique_ptr<RunContext> context_;
  std::int64_t epochs_ = 0;
  std::optional<GnssTime> last_written_;
};

// An EpochSink that calls a function (a node's publishing code).
class CallbackSink final : public EpochSink {
 public:
  explicit CallbackSink(std::function<Status(const SinkEpoch&)> on_epoch) : on_epoch_(std::move(on_epoch)) {}
  Status add(const SinkEpoch& epoch) override { return on_epoch_(epoch); }
  Status finish() override { return Ok{}; }

 private:
  std::function<Status(const SinkEpoch&)> on_epoch_;
};

}  // namespace skytrace::sim
