// `skytrace sweep`: points run on a local process pool and on a one-node Slurm cluster started by
// the test give the same outputs and manifest as each other and as the point run alone; resuming
// skips finished points; failures are listed with their reason and run again; bad sweeps and an
// unreachable Slurm give clear errors.
#include <gtest/gtest.h>
#include <sys/socket.h>
#include <unistd.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "process.hpp"
#include "test_support.hpp"

namespace skytrace {
namespace {

std::string skytrace_cmd() { return test::shell_quote(test::skytrace_executable().string()); }

std::string read_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

nlohmann::json read_json(const std::filesystem::path& path) { return nlohmann::json::parse(read_file(path)); }

// The quick start, 20 s long, with its world by absolute path: the sweep file names it.
std::filesystem::path write_base_scenario(const std::filesystem::path& dir) {
  std::string text = read_file(test::source_dir() / "examples" / "quickstart.yaml");
  const std::string world = "sdf: worlds/courtyard.sdf";
  text.replace(text.find(world), world.size(), "sdf: " + (test::source_dir() / "examples/worlds/courtyard.sdf").string());
  const std::string duration = "duration_s: 3600";
  text.replace(text.find(duration), duration.size(), "duration_s: 20");
  const auto path = dir / "base.yaml";
  std::ofstream(path) << text;
  return path;
}

std::filesystem::path write_sweep(const std::filesystem::path& dir, const std::string& axes, const std::string& extra = "") {
  const auto path = dir / "sweep.yaml";
  std::ofstream(path) << "name: test-sweep\nscenario: base.yaml\nrandom_seed: 3\n" << extra << "axes:\n" << axes;
  return path;
}

// Every file of a point's run but the two that hold times and hosts; summary.json without its wall time.
void expect_same_point_outputs(const std::filesystem::path& a, const std::filesystem::path& b) {
  for (const char* file : {"obs.rnx", "nav.rnx", "fix.csv", "truth.csv.zst", "report.html", "skyplot.svg"}) {
    EXPECT_EQ(read_file(a / file), read_file(b / file)) << file << " differs between " << a << " and " << b;
  }
  auto summary_a = read_json(a / "summary.json");
  auto summary_b = read_json(b / "summary.json");
  summary_a.erase("wall_time_s");
  summary_b.erase("wall_time_s");
  EXPECT_EQ(summary_a, summary_b) << a << " vs " << b;
}

// The manifest's points without what depends on where and when they ran.
nlohmann::json comparable_points(const nlohmann::json& manifest) {
  nlohmann::json points = manifest.at("points");
  for (auto& p : points) {
    p.erase("wall_time_s");
    p.erase("host");
  }
  return points;
}

class Sweep : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = test::make_temp_dir("sweep");
    write_base_scenario(dir_);
  }
  test::ProcessResult sweep(const std::filesystem::path& file, const std::string& options) {
    return test::run_command(skytrace_cmd() + " sweep " + test::shell_quote(file.string()) + " " + options);
  }
  std::string out(const char* name) const { return "--out " + test::shell_quote((dir_ / name).string()); }
  std::filesystem::path dir_;
};

TEST_F(Sweep, LocalPoolRunsEveryPointResumesAndMatchesARunAlone) {
  const auto file = write_sweep(dir_, "  seed: {range: [1, 2]}\n  models.multipath: [false, true]\n");
  const auto r = sweep(file, out("out") + " --local -j 2");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto manifest = read_json(dir_ / "out/manifest.json");
  ASSERT_EQ(manifest.at("points_total"), 4);
  EXPECT_EQ(manifest.at("done"), 4);
  // Grid order: the last axis varies fastest.
  const auto& points = manifest.at("points");
  EXPECT_EQ(points[1].at("parameters"), (nlohmann::json{{"seed", 1}, {"models.multipath", true}}));
  EXPECT_EQ(points[2].at("parameters"), (nlohmann::json{{"seed", 2}, {"models.multipath", false}}));
  // The merged table: one row per point and receiver, with the run's figures.
  const std::string summaries = read_file(dir_ / "out/summaries.csv");
  EXPECT_EQ(std::count(summaries.begin(), summaries.end(), '\n'), 5) << summaries;
  EXPECT_NE(summaries.find("p000003,done,2,true,QUICK,21,1,"), std::string::npos) << summaries;
  const auto figures = read_json(dir_ / "out/runs/p000003/summary.json").at("receivers").at(0);
  EXPECT_EQ(figures.at("fix").at("epochs_per_type").at("3d"), 21);
  EXPECT_LT(figures.at("fix").at("horizontal_error_m").at("p95").get<double>(), 3.0);
  EXPECT_GT(figures.at("multipath_share").get<double>(), 0.5);  // the courtyard's ground and walls

  // Point p000002 run alone, as `skytrace run` with its overrides and one thread: the same bytes.
  const auto alone = test::run_command(skytrace_cmd() + " run " + test::shell_quote((dir_ / "base.yaml").string()) +
                                       " --out " + test::shell_quote((dir_ / "alone").string()) +
                                       " --set seed=2 --set models.multipath=false --threads 1 -q");
  ASSERT_EQ(alone.exit_code, 0) << alone.output;
  expect_same_point_outputs(dir_ / "out/runs/p000002", dir_ / "alone");

  // Resuming: nothing to run; a point whose record is gone runs again, alone.
  const auto obs = dir_ / "out/runs/p000001/obs.rnx";
  const auto written = std::filesystem::last_write_time(obs);
  const auto again = sweep(file, out("out"));
  ASSERT_EQ(again.exit_code, 0) << again.output;
  EXPECT_NE(again.output.find("0 to run (4 done before)"), std::string::npos) << again.output;
  EXPECT_EQ(std::filesystem::last_write_time(obs), written);
  std::filesystem::remove(dir_ / "out/runs/p000002/point.json");
  const auto third = sweep(file, out("out"));
  ASSERT_EQ(third.exit_code, 0) << third.output;
  EXPECT_NE(third.output.find("1 to run (3 done before)"), std::string::npos) << third.output;
  EXPECT_EQ(std::filesystem::last_write_time(obs), written);
  expect_same_point_outputs(dir_ / "out/runs/p000002", dir_ / "alone");
}

TEST_F(Sweep, FailedPointsAreListedWithTheirReasonAndRunAgain) {
  // A world file that exists but is not SDF fails when its point runs, not when the sweep is read.
  std::ofstream(dir_ / "broken.sdf") << "<sdf version='1.9'><world name='x'><model>\n";
  const auto file = write_sweep(dir_, "  world.sdf: [" + (test::source_dir() / "examples/worlds/courtyard.sdf").string() + ", " +
                                          (dir_ / "broken.sdf").string() + "]\n");
  const auto r = sweep(file, out("out") + " -j 2");
  EXPECT_EQ(r.exit_code, 7) << r.output;
  EXPECT_NE(r.output.find("1 points failed"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("p000001"), std::string::npos) << r.output;
  const auto manifest = read_json(dir_ / "out/manifest.json");
  EXPECT_EQ(manifest.at("done"), 1);
  EXPECT_EQ(manifest.at("failed"), 1);
  const auto& failed = manifest.at("points").at(1);
  EXPECT_EQ(failed.at("status"), "failed");
  EXPECT_EQ(failed.at("exit_code"), 3);
  EXPECT_NE(failed.at("error").get<std::string>().find("broken.sdf"), std::string::npos) << failed.dump();
  EXPECT_NE(read_file(dir_ / "out/manifest.csv").find("p000001,failed,"), std::string::npos);
  // Fixed, the same command runs only the failed point.
  std::filesystem::copy_file(test::source_dir() / "examples/worlds/courtyard.sdf", dir_ / "broken.sdf",
                             std::filesystem::copy_options::overwrite_existing);
  const auto again = sweep(file, out("out"));
  EXPECT_EQ(again.exit_code, 0) << again.output;
  EXPECT_NE(again.output.find("1 to run (1 done before)"), std::string::npos) << again.output;
}

TEST_F(Sweep, RandomDrawsAndZipAreReproducible) {
  const auto file = write_sweep(dir_,
                                "  receiver.elevation_mask_deg: {uniform: [5, 15], count: 3}\n"
                                "  seed: {integers: [1, 1000000], count: 3}\n",
                                "combine: zip\n");
  const auto r = sweep(file, out("a") + " --plan");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto r2 = sweep(file, out("b") + " --plan");
  ASSERT_EQ(r2.exit_code, 0) << r2.output;
  const auto a = read_json(dir_ / "a/manifest.json");
  EXPECT_EQ(a.at("points_total"), 3);
  EXPECT_EQ(a.at("pending"), 3);
  EXPECT_EQ(a.at("points"), read_json(dir_ / "b/manifest.json").at("points"));
  for (const auto& p : a.at("points")) {
    const double mask = p.at("parameters").at("receiver.elevation_mask_deg").get<double>();
    EXPECT_GE(mask, 5.0);
    EXPECT_LT(mask, 15.0);
  }
  EXPECT_NE(a.at("points")[0].at("parameters"), a.at("points")[1].at("parameters"));
}

TEST_F(Sweep, BadSweepsNameTheKeyAndLine) {
  struct Case {
    std::string axes, extra, message;
  };
  const std::vector<Case> cases = {
      {"  models.ionosfere: [none, klobuchar]\n", "", "models.ionosfere: unknown key"},
      {"  seed: {range: [5, 1]}\n", "", ":5: axes.seed.range: an empty range"},
      {"  seed: []\n", "", "axes.seed: an empty list"},
      {"  seed: {uniform: [1, 2]}\n", "", "needs count"},
      {"  seed: [1, 2]\n  models.multipath: [true]\n", "combine: zip\n", "axes.models.multipath: 1 values, but the axes before it have 2"},
      {"  time.interval_s: [1, 0]\n", "", ":5: axes.time.interval_s: the value 0:"},
      {"  seed: [1]\n", "stray: 1\n", "stray: unknown key"},
  };
  for (const auto& c : cases) {
    const auto file = write_sweep(dir_, c.axes, c.extra);
    const auto r = sweep(file, out("bad"));
    EXPECT_EQ(r.exit_code, 3) << c.axes << r.output;
    EXPECT_NE(r.output.find(c.message), std::string::npos) << "expected '" << c.message << "' in: " << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir_ / "bad/logs")) << c.axes;
  }
  // The stated limit on points.
  const auto file = write_sweep(dir_, "  seed: {range: [1, 1000]}\n  receiver.elevation_mask_deg: {range: [0, 50]}\n");
  const auto r = test::run_command("SKYTRACE_MAX_SWEEP_POINTS=10000 " + skytrace_cmd() + " sweep " +
                                   test::shell_quote(file.string()) + " " + out("bad"));
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("SKYTRACE_MAX_SWEEP_POINTS"), std::string::npos) << r.output;
}

TEST_F(Sweep, SlurmThatCannotBeReachedIsSaidPlainly) {
  const auto file = write_sweep(dir_, "  seed: [1, 2]\n");
  // No Slurm client on PATH.
  const auto missing = test::run_command("PATH=/nonexistent " + skytrace_cmd() + " sweep " + test::shell_quote(file.string()) +
                                         " " + out("none") + " --slurm");
  EXPECT_EQ(missing.exit_code, 6) << missing.output;
  EXPECT_NE(missing.output.find("sbatch and squeue are not on PATH"), std::string::npos) << missing.output;
  if (!test::program_available("sbatch")) GTEST_SKIP() << "Slurm's client commands are not installed (scripts/setup installs them)";
  // A controller that does not answer: a configuration pointing at a closed port.
  const int port = test::free_loopback_port(SOCK_STREAM);
  std::ofstream(dir_ / "slurm.conf") << "ClusterName=nowhere\nSlurmctldHost=localhost(127.0.0.1)\nSlurmctldPort=" << port
                                     << "\nAuthType=auth/munge\nAuthInfo=socket=" << (dir_ / "no-munge.socket").string()
                                     << "\nNodeName=localhost CPUs=1\nPartitionName=p Nodes=ALL Default=YES\n";
  const auto r = test::run_command("SLURM_CONF=" + test::shell_quote((dir_ / "slurm.conf").string()) + " " + skytrace_cmd() +
                                   " sweep " + test::shell_quote(file.string()) + " " + out("unreachable") + " --slurm");
  EXPECT_EQ(r.exit_code, 6) << r.output;
  EXPECT_NE(r.output.find("sbatch refused the sweep's array job"), std::string::npos) << r.output;
}

// A one-node Slurm cluster (scripts/slurm-local-cluster) for the test's lifetime.
class SlurmCluster {
 public:
  SlurmCluster() : dir_(std::filesystem::temp_directory_path() / ("skytrace-slurm-" + std::to_string(getpid()))) {
    const int port = test::free_loopback_port(SOCK_STREAM);
    const auto r = test::run_command(test::shell_quote((test::source_dir() / "scripts/slurm-local-cluster").string()) +
                                     " start " + test::shell_quote(dir_.string()) + " " + std::to_string(port));
    started_ = r.exit_code == 0;
    output_ = r.output;
  }
  ~SlurmCluster() {
    (void)test::run_command(test::shell_quote((test::source_dir() / "scripts/slurm-local-cluster").string()) + " stop " +
                            test::shell_quote(dir_.string()));
    std::error_code ec;
    std::filesystem::remove_all(dir_, ec);
  }
  [[nodiscard]] bool started() const { return started_; }
  [[nodiscard]] const std::string& output() const { return output_; }
  [[nodiscard]] std::string env() const { return "SLURM_CONF=" + test::shell_quote((dir_ / "slurm.conf").string()) + " "; }

 private:
  std::filesystem::path dir_;
  bool started_ = false;
  std::string output_;
};

TEST_F(Sweep, SlurmArrayJobGivesTheSameManifestAndOutputsAsTheLocalPool) {
  for (const char* program : {"sbatch", "munged", "slurmctld", "slurmd"}) {
    if (!test::program_available(program) && !std::filesystem::exists(std::string("/usr/sbin/") + program)) {
      GTEST_SKIP() << program << " is not installed (scripts/setup installs Slurm and munge)";
    }
  }
  SlurmCluster cluster;
  ASSERT_TRUE(cluster.started()) << cluster.output();
  // 20 points: 5 seeds x 2 multipath settings x 2 elevation masks.
  const auto file = write_sweep(dir_,
                                "  seed: {range: [11, 15]}\n  models.multipath: [false, true]\n"
                                "  receiver.elevation_mask_deg: [5, 15]\n",
                                "set:\n  time.duration_s: 10\n");
  const auto local = sweep(file, out("local") + " --local -j 2");
  ASSERT_EQ(local.exit_code, 0) << local.output;
  const auto slurm = test::run_command(cluster.env() + skytrace_cmd() + " sweep " + test::shell_quote(file.string()) + " " +
                                       out("slurm") + " --slurm --chunk 2 --poll-s 0.5 --time 10 --mem 500M");
  ASSERT_EQ(slurm.exit_code, 0) << slurm.output;
  EXPECT_NE(slurm.output.find("10 tasks for 20 points"), std::string::npos) << slurm.output;
  const auto local_manifest = read_json(dir_ / "local/manifest.json");
  const auto slurm_manifest = read_json(dir_ / "slurm/manifest.json");
  EXPECT_EQ(slurm_manifest.at("done"), 20);
  EXPECT_EQ(comparable_points(local_manifest), comparable_points(slurm_manifest));
  for (const char* id : {"p000000", "p000007", "p000019"}) {
    expect_same_point_outputs(dir_ / "local/runs" / id, dir_ / "slurm/runs" / id);
  }
  EXPECT_TRUE(std::filesystem::exists(dir_ / "slurm/slurm/submit-1.sh"));
  EXPECT_TRUE(std::filesystem::exists(dir_ / "slurm/slurm/logs"));

  // A task the scheduler kills: submitted without waiting, cancelled, then gathered.
  const auto long_file = write_sweep(dir_, "  seed: [1, 2]\n", "set:\n  time.duration_s: 86400\n  time.interval_s: 0.1\n");
  const auto submitted = test::run_command(cluster.env() + skytrace_cmd() + " sweep " + test::shell_quote(long_file.string()) +
                                           " " + out("killed") + " --slurm --no-wait");
  ASSERT_EQ(submitted.exit_code, 0) << submitted.output;
  const auto job = read_json(dir_ / "killed/slurm/submissions.json").at(0).at("job_id").get<std::string>();
  // Let the tasks start, then cancel the array.
  for (int i = 0; i < 100; ++i) {
    const auto q = test::run_command(cluster.env() + "squeue -h -j " + job + " -o %T");
    if (q.output.find("RUNNING") != std::string::npos) break;
    usleep(100'000);
  }
  ASSERT_EQ(test::run_command(cluster.env() + "scancel " + job).exit_code, 0);
  for (int i = 0; i < 200; ++i) {
    if (test::run_command(cluster.env() + "squeue -h -j " + job + " -o %T").output.find_first_not_of(" \n") == std::string::npos) break;
    usleep(100'000);
  }
  const auto gathered = test::run_command(cluster.env() + skytrace_cmd() + " sweep " + test::shell_quote(long_file.string()) +
                                          " " + out("killed") + " --gather");
  EXPECT_EQ(gathered.exit_code, 7) << gathered.output;
  const auto manifest = read_json(dir_ / "killed/manifest.json");
  EXPECT_EQ(manifest.at("failed"), 2) << manifest.dump(1);
  for (const auto& p : manifest.at("points")) {
    const std::string error = p.value("error", "");
    EXPECT_TRUE(error.find("SIGTERM") != std::string::npos || error.find("cancelled by Slurm") != std::string::npos) << error;
  }
}

}  // namespace
}  // namespace skytrace
