// Parameter sweeps and Monte Carlo campaigns (`skytrace sweep`): a sweep file names a base scenario
// and axes over any of its keys; every combination (or, zipped, every i-th value) is one point, a
// run of the base scenario with that point's `--set` overrides. This part plans the points, records
// each point's result in its folder and gathers the manifest and the merged table of summaries; the
// command line runs the points on a process pool or as a Slurm array job (docs/sweeps.md).
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "skytrace/core/error.hpp"

namespace skytrace::sim {

struct SweepAxis {
  std::string key;  // scenario key path, as for --set: models.multipath, receivers.1.rtk.latency_s
  int line = 0;     // of the axis in the sweep file
  // Each value as YAML flow text (what --set takes) and as JSON (manifest, tables).
  std::vector<std::string> yaml_values;
  std::vector<nlohmann::json> json_values;
};

struct SweepPlan {
  std::filesystem::path file;           // the sweep file
  std::string name;
  std::filesystem::path scenario;       // the base scenario (absolute)
  std::vector<std::string> fixed_overrides;  // `set:` of the sweep file, KEY=YAML, for every point
  bool zip = false;                     // combine: zip (else grid)
  std::uint64_t random_seed = 0;
  std::vector<SweepAxis> axes;
  std::uint64_t point_count = 0;

  // Point ids are "p" and the index from 0, zero-padded to 6 digits (more beyond 10^6 points).
  [[nodiscard]] std::string point_id(std::uint64_t index) const;
  [[nodiscard]] std::optional<std::uint64_t> point_index(const std::string& id) const;
  // The value index of every axis at a point.
  [[nodiscard]] std::vector<size_t> value_indices(std::uint64_t index) const;
  // The point's overrides: the fixed ones, then one per axis.
  [[nodiscard]] std::vector<std::string> overrides(std::uint64_t index) const;
  [[nodiscard]] nlohmann::json parameters(std::uint64_t index) const;  // {axis key: value}
};

// Reads a sweep file (docs/sweeps.md). Errors name the file, line and key.
[[nodiscard]] Result<SweepPlan> parse_sweep(const std::string& text, const std::filesystem::path& file);
[[nodiscard]] Result<SweepPlan> load_sweep(const std::filesystem::path& file);

// Parses the base scenario with the overrides of the first point and with every value of every
// axis (the other axes at their first value; at most 1000 values per axis): an axis over a key the
// scenario does not have, or a value it refuses, is an error naming the axis before anything runs.
[[nodiscard]] Status check_sweep_against_scenario(const SweepPlan& plan);

// Where a sweep's files go.
struct SweepLayout {
  std::filesystem::path out;
  [[nodiscard]] std::filesystem::path runs() const { return out / "runs"; }
  [[nodiscard]] std::filesystem::path point_dir(const std::string& id) const { return runs() / id; }
  [[nodiscard]] std::filesystem::path point_record(const std::string& id) const { return point_dir(id) / "point.json"; }
  [[nodiscard]] std::filesystem::path logs() const { return out / "logs"; }
  [[nodiscard]] std::filesystem::path slurm() const { return out / "slurm"; }
};

// What became of one point: written by the process that ran it, as the last file of its folder.
struct PointRecord {
  std::string id;
  std::string status;  // "done" or "failed"
  int exit_code = 0;   // skytrace's exit code for the point's run (0 when done)
  std::string error;   // the message when failed
  double wall_time_s = 0.0;
  std::string host;
  std::vector<std::string> overrides;  // to know a record of another sweep definition
  std::string scenario;
};
[[nodiscard]] Status write_point_record(const SweepLayout& layout, const PointRecord& record);
// nullopt when the point has no record (not run, running, or killed before it ended).
[[nodiscard]] std::optional<PointRecord> read_point_record(const SweepLayout& layout, const std::string& id);

// Every point's record, by index: the runs folder is listed once, so that a sweep of 10^5 points
// that has run few of them does not look for 10^5 files.
[[nodiscard]] std::map<std::uint64_t, PointRecord> read_point_records(const SweepPlan& plan, const SweepLayout& layout);

// A record made for this point's overrides and base scenario (not by an earlier definition of the sweep).
[[nodiscard]] bool record_of_this_sweep(const SweepPlan& plan, const PointRecord& record, std::uint64_t index);
// A point counts as done when its record says so for the same overrides and base scenario.
[[nodiscard]] bool point_done(const SweepPlan& plan, const std::optional<PointRecord>& record, std::uint64_t index);

// Gathers every point's record and run summary into manifest.json, manifest.csv and summaries.csv
// in the sweep's folder (atomically). `reasons` gives a failure reason for points without a
// record (from the scheduler's logs), by point index. Returns the counts.
struct SweepCounts {
  std::uint64_t done = 0, failed = 0, pending = 0;
  std::vector<std::string> failed_ids;
};
[[nodiscard]] Result<SweepCounts> write_sweep_manifest(const SweepPlan& plan, const SweepLayout& layout,
                                                       const std::vector<std::pair<std::uint64_t, std::string>>& reasons = {});

}  // namespace skytrace::sim
