// `skytrace fetch`: downloads a day's broadcast and precise products into the local cache and
// prints one line per file: product, whether it was downloaded or already cached, local path.
#include <fmt/format.h>
#include <iostream>
#include <memory>
#include <string>

#include "commands.hpp"
#include "skytrace/orbits/fetch.hpp"

namespace skytrace::cli {

namespace {

struct FetchOptions {
  std::string date;
  std::string products = "brdc";
  std::string cache_dir;
  std::string base_url{orbits::kDefaultArchiveBaseUrl};
  std::string analysis_center = "GRG";
  std::string orbit_sample;
  std::string clock_sample;
  double timeout_s = 300.0;
  int retries = 3;
  double retry_delay_s = 2.0;
  bool force = false;
  bool quiet = false;
};

int run_fetch(const FetchOptions& options) {
  // Named as given, before anything is fetched (CLI11's range checks let NaN through).
  if (!(options.timeout_s > 0.0)) {
    return report_error(make_error(ErrorCode::kInvalidArgument,
                                   fmt::format("--timeout-s {}: expected a positive number of seconds", options.timeout_s)));
  }
  if (!(options.retry_delay_s >= 0.0 && options.retry_delay_s <= 60.0)) {
    return report_error(make_error(ErrorCode::kInvalidArgument,
                                   fmt::format("--retry-delay-s {}: expected 0 to 60", options.retry_delay_s)));
  }
  auto day = orbits::parse_archive_day(options.date);
  if (!day.ok()) return report_error(day.error());
  auto kinds = orbits::parse_product_list(options.products);
  if (!kinds.ok()) return report_error(kinds.error());

  orbits::FetchRequest request;
  request.day = *day;
  request.products = *kinds;
  request.cache_dir = options.cache_dir;
  request.base_url = options.base_url;
  request.options.analysis_center = options.analysis_center;
  request.options.orbit_sample = options.orbit_sample;
  request.options.clock_sample = options.clock_sample;
  request.timeout_s = options.timeout_s;
  request.retries = options.retries;
  request.retry_delay_s = options.retry_delay_s;
  request.force = options.force;
  if (!options.quiet) {
    request.on_note = [](const std::string& note) { std::cerr << "skytrace: fetch: " << note << "\n"; };
  }

  // A product missing from the archive does not hide the others; an unreachable or failing
  // server ends the run (each further product would only wait through the same retries).
  int exit_code = kExitOk;
  for (size_t i = 0; i < request.products.size(); ++i) {
    auto fetched = orbits::fetch_product(request, request.products[i]);
    if (!fetched.ok()) {
      const Error& error = fetched.error();
      int code = report_error(error);
      if (error.code == ErrorCode::kNotFound) code = kExitNetwork;  // HTTP 404: a download failed
      if (error.code == ErrorCode::kIo) code = kExitOutput;         // the cache could not be written
      if (exit_code == kExitOk) exit_code = code;
      if (error.code == ErrorCode::kNetwork && i + 1 < request.products.size()) {
        std::cerr << "skytrace: error: remaining products not attempted\n";
        break;
      }
      continue;
    }
    for (const auto& product : *fetched) {
      std::cout << orbits::to_string(product.kind) << ' ' << (product.from_cache ? "cached" : "downloaded") << ' '
                << product.path.string() << '\n';
    }
  }
  std::cout.flush();
  return exit_code;
}

}  // namespace

void register_fetch_command(CLI::App& app, int& exit_code) {
  auto options = std::make_shared<FetchOptions>();
  CLI::App* cmd = app.add_subcommand(
      "fetch", "Download a day's broadcast navigation file and precise products (SP3, clock, IONEX) into the cache");
  cmd->add_option("--date", options->date, "Day to fetch, YYYY-MM-DD (GPS time)")->required();
  cmd->add_option("--products", options->products, "Comma-separated list of brdc, sp3, clk, ionex")
      ->capture_default_str();
  cmd->add_option("--cache", options->cache_dir, "Cache folder (default $XDG_CACHE_HOME/skytrace or ~/.cache/skytrace)");
  cmd->add_option("--base-url", options->base_url, "Root of the IGS archive mirror")->capture_default_str();
  cmd->add_option("--analysis-center", options->analysis_center,
                  "Precise products: IGS, GRG, COD, GFZ, WUM, ESA, JAX or a full prefix such as GRG0MGXFIN")
      ->capture_default_str();
  cmd->add_option("--orbit-sample", options->orbit_sample, "SP3 interval in the file name, e.g. 05M (default: centre's)");
  cmd->add_option("--clock-sample", options->clock_sample, "Clock interval in the file name, e.g. 30S (default: centre's)");
  cmd->add_option("--timeout-s", options->timeout_s, "Time limit of one download attempt, seconds")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--retries", options->retries, "Extra attempts after a transient failure")
      ->check(CLI::Range(0, 10))
      ->capture_default_str();
  cmd->add_option("--retry-delay-s", options->retry_delay_s, "First back-off delay, doubled per attempt (max 60 s)")
      ->check(CLI::Range(0.0, 60.0))
      ->capture_default_str();
  cmd->add_flag("--force", options->force, "Download again even when the file is in the cache");
  cmd->add_flag("--quiet", options->quiet, "No progress notes on stderr");
  cmd->callback([options, &exit_code]() { exit_code = run_fetch(*options); });
}

}  // namespace skytrace::cli
