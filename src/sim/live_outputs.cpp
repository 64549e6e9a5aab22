#include "skytrace/sim/live_outputs.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <system_error>

#include "skytrace/core/output_file.hpp"
#include "skytrace/sim/streams.hpp"

namespace skytrace::sim {
namespace {

// A byte stream of the first (only) receiver into a staged file.
Result<std::unique_ptr<EpochSink>> staged_stream(const RunContext& c, const char* name, std::unique_ptr<StreamEncoder> encoder) {
  auto file = StagedFile::create(c.staging_dir / name);
  if (!file) return file.error();
  return std::unique_ptr<EpochSink>(std::make_unique<StreamSink>(0, std::move(encoder), std::move(*file)));
}

}  // namespace

const std::vector<LiveFileKind>& live_file_table() {
  static const std::vector<LiveFileKind> table = {
      {"rinex_out", "RINEX 3 observations", false, "obs.rnx", &make_rinex_obs_sink},
      {"nmea_out", "NMEA 0183 sentences of the fix", true, "fix.nmea",
       [](const RunContext& c) { return staged_stream(c, "fix.nmea", make_nmea_encoder()); }},
      {"fix_csv_out", "the fix as fix.csv rows", true, "fix.csv",
       [](const RunContext& c) { return staged_stream(c, "fix.csv", make_fix_csv_encoder()); }},
      {"rtcm_out", "RTCM 3 MSM7 observations, station and ephemeris messages", false, "obs.rtcm3",
       [](const RunContext& c) {
         const SinkReceiver& rx = c.receivers.front();
         return staged_stream(c, "obs.rtcm3",
                              make_rtcm3_encoder(*c.resources->ephemerides, rtcm_station(rx.marker_m, *rx.settings)));
       }},
  };
  return table;
}

// One file output: its sink writes into a hidden folder beside the target.
struct LiveOutputs::File {
  const LiveFileKind* kind = nullptr;
  std::filesystem::path target;
  std::filesystem::path staging;
  std::unique_ptr<EpochSink> sink;

  [[nodiscard]] std::string name() const { return fmt::format("{} {}", kind->parameter, target.string()); }
  void drop() {
    sink.reset();
    std::error_code ignored;
    std::filesystem::remove_all(staging, ignored);
  }
  ~File() { drop(); }
};

Result<std::unique_ptr<LiveOutputs>> LiveOutputs::open(const LiveSession& session,
                                                       const std::vector<std::pair<std::string, std::string>>& paths,
                                                       double interval_s) {
  std::unique_ptr<LiveOutputs> out(new LiveOutputs());
  out->header_ = std::make_unique<io::ObservationHeader>(session.observation_header());
  out->header_->interval_s = interval_s;
  out->context_ = std::make_unique<RunContext>();
  RunContext& context = *out->context_;
  context.scenario = &session.scenario();
  context.resources = &session.resources();
  context.write_truth = false;
  SinkReceiver& rx = context.receivers.emplace_back();
  rx.settings = &session.receiver();
  rx.marker_m = session.marker_ecef_m();
  rx.header = out->header_.get();

  for (const auto& entry : paths) {
    // Named copies, not structured bindings: clang 14 (the fuzz build) cannot capture those.
    const std::string& parameter = entry.first;
    const std::string& path = entry.second;
    const auto& table = live_file_table();
    const auto kind = std::find_if(table.begin(), table.end(), [&](const LiveFileKind& k) { return parameter == k.parameter; });
    if (kind == table.end()) {
      return make_error(ErrorCode::kInvalidArgument, fmt::format("parameter {}: not a file output of a live receiver", parameter));
    }
    if (path.empty()) continue;
    auto file = std::make_unique<File>();
    file->kind = &*kind;
    file->target = std::filesystem::absolute(path).lexically_normal();
    const auto fail = [&](const std::string& why) {
      return make_error(ErrorCode::kOutput, fmt::format("parameter {} {}: {}", parameter, path, why));
    };
    auto target = resolve_output_target(file->target);
    if (!target) return fail(target.error().message);
    file->staging = temporary_sibling(target->kind == OutputKind::kFile ? target->path : file->target, "partial");
    if (target->kind == OutputKind::kStream) {
      // A device or FIFO is written when the file is complete; its sibling must be a writable folder.
      file->staging = std::filesystem::temp_directory_path() / file->staging.filename();
    }
    std::error_code ec;
    if (!std::filesystem::create_directory(file->staging, ec) || ec) {
      return fail(fmt::format("cannot create the folder it is written in ({})", ec ? ec.message() : "exists"));
    }
    context.staging_dir = file->staging;
    auto sink = kind->make(context);
    if (!sink) return fail(sink.error().message);
    file->sink = std::move(*sink);
    out->files_.push_back(std::move(file));
  }
  context.staging_dir.clear();
  return out;
}

LiveOutputs::~LiveOutputs() = default;

void LiveOutputs::add_publisher(std::unique_ptr<EpochSink> publisher) { publishers_.push_back(std::move(publisher)); }

bool LiveOutputs::needs_fix() const {
  return std::any_of(files_.begin(), files_.end(), [](const auto& f) { return f->kind->needs_fix; });
}

std::vector<std::string> LiveOutputs::add(const LiveEpoch& epoch) {
  std::vector<std::string> problems;
  const SinkEpoch e{epochs_++,
                    0,
                    &context_->receivers.front(),
                    &epoch.observations,
                    epoch.fix ? &*epoch.fix : nullptr,
                    epoch.restarted,
                    epoch.pose_stale};
  for (auto& publisher : publishers_) {
    if (auto st = publisher->add(e); !st) problems.push_back(st.error().message);
  }
  if (files_.empty()) return problems;
  const GnssTime tag = epoch.observations.receiver_time;
  if (last_written_ && !(*last_written_ < tag)) {
    problems.push_back(fmt::format("epoch {} is not after the last one written; left out of the files",
                                   tag.to_iso8601(TimeScale::kGpst)));
    return problems;
  }
  last_written_ = tag;
  for (auto it = files_.begin(); it != files_.end();) {
    if (auto st = (*it)->sink->add(e); !st) {
      problems.push_back(fmt::format("parameter {}: {}; the file is given up, nothing of it is kept", (*it)->name(),
                                     st.error().message));
      it = files_.erase(it);  // File's destructor removes what was written
    } else {
      ++it;
    }
  }
  return problems;
}

LiveOutputs::Finished LiveOutputs::finish() {
  Finished done;
  for (auto& publisher : publishers_) {
    if (auto st = publisher->finish(); !st) done.errors.push_back(st.error().message);
  }
  for (auto& file : files_) {
    Status st = file->sink->finish();
    if (st) st = install_output_file(file->staging / file->kind->staged_name, file->target);
    if (st) {
      done.written.push_back(file->name());
    } else {
      done.errors.push_back(fmt::format("parameter {}: {}; nothing written", file->name(), st.error().message));
    }
    file->drop();
  }
  files_.clear();
  return done;
}

}  // namespace skytrace::sim
