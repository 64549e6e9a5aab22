// The composition root of a run: builds ephemerides, receivers and outputs from a scenario and
// runs the epochs. Writes into a staging folder and moves the finished files into place at the
// end, so a failed run leaves no half-written outputs.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "skytrace/core/error.hpp"
#include "skytrace/orbits/ephemeris.hpp"
#include "skytrace/sim/scenario.hpp"

namespace skytrace::sim {

struct RunOptions {
  bool write_truth = true;
  // Threads the run may use (1-1024); 0: one per hardware thread. 1 computes and writes on the
  // calling thread; from 2 on, the epochs are computed on a thread of their own while the calling
  // thread formats and writes them, and a bag serialises and compresses on threads of its own. The
  // outputs are the same bytes for any number.
  int threads = 0;
  // Called after each epoch with (epochs done, epochs total); the CLI draws a progress bar.
  std::function<void(std::int64_t, std::int64_t)> progress;
};

struct RunSummary {
  std::int64_t epochs = 0;
  std::map<std::string, std::int64_t> satellite_epochs_per_system;  // tracked satellite-epochs
  std::int64_t satellite_epochs = 0;
  std::int64_t observations = 0;  // signal observations (each with code, phase, Doppler, C/N0)
  double wall_time_s = 0.0;
  std::vector<std::filesystem::path> outputs;
  std::vector<std::string> warnings;  // e.g. world models that were skipped
};

// Runs the scenario and writes obs.rnx, nav.rnx, truth.csv.zst (output.truth_format) and summary.json into out_dir.
[[nodiscard]] Result<RunSummary> run_scenario(const Scenario& scenario, const std::filesystem::path& out_dir,
                                              const RunOptions& options = {});

}  // namespace skytrace::sim
