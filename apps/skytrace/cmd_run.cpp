// `skytrace run SCENARIO --out DIR`: simulates what the scenario's receivers record.
#include <fmt/format.h>
#include <unistd.h>

#include <cstdio>
#include <iostream>
#include <memory>

#include "commands.hpp"
#include "skytrace/sim/run.hpp"
#include "skytrace/sim/scenario.hpp"

namespace skytrace::cli {
namespace {

struct RunArgs {
  std::string scenario;
  std::string out_dir;
  bool no_truth = false;
  std::string truth_format;  // --truth-format: output.truth_format
  bool quiet = false;
  std::vector<std::string> overrides;              // --set
  std::vector<sim::ScenarioOverride> from_options;  // keys set by other options (skytrace iq's)
  std::optional<int> threads;                       // --threads; default: one per hardware thread
};

int run(const RunArgs& args) {
  if (args.threads && (*args.threads < 1 || *args.threads > 1024)) {
    return report_error(make_error(ErrorCode::kInvalidArgument,
                                   fmt::format("--threads {}: expected 1 to 1024 (default: one per hardware thread)", *args.threads)));
  }
  std::vector<sim::ScenarioOverride> overrides = sim::overrides_given_with_set(args.overrides);
  overrides.insert(overrides.end(), args.from_options.begin(), args.from_options.end());
  if (!args.truth_format.empty()) {
    overrides.push_back({"output.truth_format=" + args.truth_format, "--truth-format " + args.truth_format});
  }
  auto scenario = sim::load_scenario_with_options(args.scenario, overrides);
  if (!scenario) return report_error(scenario.error());
  sim::RunOptions options;
  options.write_truth = !args.no_truth;
  options.threads = args.threads.value_or(0);
  const bool terminal = isatty(fileno(stderr)) != 0 && !args.quiet;
  if (terminal) {
    options.progress = [last_percent = -1](std::int64_t done, std::int64_t total) mutable {
      const int percent = static_cast<int>(100 * done / std::max<std::int64_t>(total, 1));
      if (percent == last_percent) return;
      last_percent = percent;
      const int filled = percent / 2;
      std::fprintf(stderr, "\r[%-50s] %3d%% epoch %lld/%lld", std::string(static_cast<size_t>(filled), '#').c_str(),
                   percent, static_cast<long long>(done), static_cast<long long>(total));
      if (done == total) std::fputc('\n', stderr);
      std::fflush(stderr);
    };
  }
  auto summary = sim::run_scenario(*scenario, args.out_dir, options);
  if (!summary) return report_error(summary.error());
  for (const auto& warning : summary->warnings) std::cerr << "skytrace run: warning: " << warning << "\n";
  if (!args.quiet) {
    std::cout << fmt::format("skytrace run: {} epochs, {} satellite-epochs, {} signal observations in {:.2f} s\n",
                             summary->epochs, summary->satellite_epochs, summary->observations, summary->wall_time_s);
    for (const auto& path : summary->outputs) std::cout << "  wrote " << path.string() << "\n";
  }
  return kExitOk;
}

}  // namespace

// `skytrace iq SCENARIO --out DIR`: the run with output.iq set from the options (docs/iq.md).
void register_iq_command(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<RunArgs>();
  auto sample_rate = std::make_shared<double>(4e6);
  auto format = std::make_shared<std::string>("sc8");
  auto bands = std::make_shared<std::vector<std::string>>();
  CLI::App* cmd = app.add_subcommand(
      "iq", "Write complex baseband samples of the scenario's first receiver (GPS L1 C/A, Galileo E1, GLONASS L1OF, BeiDou B1I) with a GNSS-SDR "
            "configuration, beside obs.rnx and truth of the same run");
  cmd->add_option("scenario", args->scenario, "Scenario YAML file (see docs/scenario.md)")->required();
  cmd->add_option("--out", args->out_dir, "Output folder (created if missing)")->required();
  cmd->add_option("--sample-rate", *sample_rate, "Complex samples per second (at least 2.046e6 for L1 C/A, 4.092e6 for E1 and B1, 8.9e6 for G1)")
      ->capture_default_str();
  cmd->add_option("--format", *format, "sc8 (int8 I/Q), sc16 (int16 I/Q) or gr_complex (float32 I/Q)")
      ->capture_default_str();
  cmd->add_option("--band", *bands, "Band to write (repeatable): L1 (GPS L1 C/A; the default), E1 (Galileo E1 OS), G1 (GLONASS L1OF), B1 (BeiDou B1I)");
  cmd->add_flag("--no-truth", args->no_truth, "Do not write truth.csv.zst (nor paths.csv.zst)");
  cmd->add_option("--truth-format", args->truth_format, "csv.zst (default) or csv, as for skytrace run");
  cmd->add_flag("-q,--quiet", args->quiet, "No progress bar and no summary lines");
  cmd->add_option("--threads", args->threads, "Threads to use, 1-1024 (default: one per hardware thread)");
  cmd->add_option("--set", args->overrides, "Override a scenario key, KEY.PATH=YAML_VALUE (repeatable)");
  cmd->callback([args, sample_rate, format, bands, &exit_code]() {
    RunArgs with_iq = *args;
    std::string band_list, band_options;
    for (const auto& band : bands->empty() ? std::vector<std::string>{"L1"} : *bands) {
      band_list += (band_list.empty() ? "" : ", ") + band;
      band_options += " --band " + band;
    }
    with_iq.from_options.push_back(
        {fmt::format("output.iq={{sample_rate_hz: {:.17g}, format: \"{}\", bands: [{}]}}", *sample_rate, *format, band_list),
         fmt::format("--sample-rate {:g} --format {}{}", *sample_rate, *format, band_options)});
    exit_code = run(with_iq);
  });
}

void register_run_command(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<RunArgs>();
  CLI::App* cmd = app.add_subcommand("run", "Simulate a scenario: writes obs.rnx, nav.rnx, truth.csv.zst and summary.json");
  cmd->add_option("scenario", args->scenario, "Scenario YAML file (see docs/scenario.md)")->required();
  cmd->add_option("--out", args->out_dir, "Output folder (created if missing)")->required();
  cmd->add_flag("--no-truth", args->no_truth, "Do not write truth.csv.zst (nor paths.csv.zst)");
  cmd->add_option("--truth-format", args->truth_format,
                  "csv.zst (default: truth.csv.zst, paths.csv.zst) or csv (plain truth.csv, paths.csv); "
                  "the same as --set output.truth_format=FORMAT");
  cmd->add_flag("-q,--quiet", args->quiet, "No progress bar and no summary lines");
  cmd->add_option("--threads", args->threads,
                  "Computing threads, 1-1024 (default: one per hardware thread); the outputs are the same for any "
                  "number. 1 computes and writes on one thread; from 2 on, the writing and the truth's compression "
                  "run on threads of their own beside them, and a scenario's receivers are observed side by side on "
                  "the threads the fixes leave (docs/performance.md)");
  cmd->add_option("--set", args->overrides,
                  "Override a scenario key, KEY.PATH=YAML_VALUE (repeatable), e.g. --set models.ionosphere=none "
                  "--set ephemeris.precise_orbits=[]");
  cmd->callback([args, &exit_code]() { exit_code = run(*args); });
}

}  // namespace skytrace::cli
