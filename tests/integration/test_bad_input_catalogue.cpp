// The bad-input catalogue: every hostile or careless input found by probing the command line, each
// with the exit code and message it must give, in bounded time and memory (60 s, 1.5 GB per case),
// leaving nothing half-written and never replacing what an output path is. Needs no shared data:
// the inputs are cut from a run of the nominal constellation.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>
#include <zlib.h>

#include <chrono>
#include <fstream>
#include <regex>
#include <sstream>
#include <thread>

#include "process.hpp"
#include "test_support.hpp"

namespace skytrace {
namespace {

namespace fs = std::filesystem;

constexpr double kTimeLimit_s = 60.0;
constexpr long kMemoryLimit_kib = 1536L * 1024L;

std::string skytrace_cmd() { return test::shell_quote(test::skytrace_executable().string()); }
std::string q(const fs::path& p) { return test::shell_quote(p.string()); }

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

void write_text(const fs::path& path, const std::string& text) { std::ofstream(path, std::ios::binary) << text; }

// A scenario of the nominal constellation (no data needed), ten minutes at 30 s.
std::string nominal_scenario(const std::string& receiver_block = "") {
  return "name: catalogue\n"
         "time:\n  start: 2026-03-01T12:00:00\n  scale: GPST\n  duration_s: 600\n  interval_s: 30\n" +
         (receiver_block.empty()
              ? std::string("receiver:\n  name: CATA\n  position:\n    lla_deg_m: [48.1, 11.6, 520.0]\n"
                            "  signals: [G1C, R1C, E1C]\n")
              : receiver_block) +
         "ephemeris:\n  nominal: true\n";
}

// Line index (0-based) of the first line holding `needle` at or after `from`.
size_t find_line(const std::vector<std::string>& lines, const std::string& needle, size_t from = 0) {
  for (size_t i = from; i < lines.size(); ++i) {
    if (lines[i].find(needle) != std::string::npos) return i;
  }
  return lines.size();
}

std::vector<std::string> split_lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

std::string join_lines(const std::vector<std::string>& lines) {
  std::string text;
  for (const auto& l : lines) text += l + "\n";
  return text;
}

// A minimal valid IONEX file (one global map) with header records replaced as given.
std::string ionex_text(const std::string& lon_record, const std::string& exponent_record) {
  return "     1.1            IONOSPHERE MAPS     MIX                 IONEX VERSION / TYPE\n"
         "  2026     3     1    12     0     0                        EPOCH OF FIRST MAP\n"
         "  2026     3     1    12     0     0                        EPOCH OF LAST MAP\n"
         "     0                                                      INTERVAL\n"
         "     1                                                      # OF MAPS IN FILE\n"
         "  NONE                                                      MAPPING FUNCTION\n"
         "  6371.0                                                    BASE RADIUS\n"
         "     2                                                      MAP DIMENSION\n"
         "   350.0 350.0   0.0                                        HGT1 / HGT2 / DHGT\n"
         "    87.5 -87.5 -87.5                                        LAT1 / LAT2 / DLAT\n" +
         lon_record + exponent_record +
         "                                                            END OF HEADER\n"
         "     1                                                      START OF TEC MAP\n"
         "  2026     3     1    12     0     0                        EPOCH OF CURRENT MAP\n"
         "    87.5-180.0 180.0 120.0 350.0                            LAT/LON1/LON2/DLON/H\n"
         "    1    2    3    1\n"
         "     0.0-180.0 180.0 120.0 350.0                            LAT/LON1/LON2/DLON/H\n"
         "   10   20   30   10\n"
         "   -87.5-180.0 180.0 120.0 350.0                            LAT/LON1/LON2/DLON/H\n"
         "    5    5    5    5\n"
         "     1                                                      END OF TEC MAP\n";
}
const std::string kGoodLon = "  -180.0 180.0 120.0                                        LON1 / LON2 / DLON\n";
const std::string kGoodExponent = "     0                                                      EXPONENT\n";

bool has_staging_folder(const fs::path& dir) {
  std::error_code ec;
  for (auto it = fs::directory_iterator(dir, ec); !ec && it != fs::directory_iterator(); it.increment(ec)) {
    if (it->path().filename().string().rfind(".skytrace-staging-", 0) == 0) return true;
  }
  return false;
}

class BadInputCatalogue : public ::testing::Test {
 protected:
  // One run of the nominal constellation gives the observation and navigation files to spoil.
  static void SetUpTestSuite() {
    // Per process: ctest runs each case as its own process, in parallel.
    base_ = test::make_temp_dir("bad_input_catalogue_base_" + std::to_string(getpid()));
    write_text(base_ / "scenario.yaml", nominal_scenario());
    const auto r = test::run_command(skytrace_cmd() + " run " + q(base_ / "scenario.yaml") + " --out " + q(base_ / "out") +
                                     " --quiet --no-truth");
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  static void TearDownTestSuite() {
    std::error_code ignored;
    fs::remove_all(base_, ignored);
  }
  void SetUp() override {
    ASSERT_TRUE(fs::exists(base_ / "out" / "obs.rnx")) << "the base run failed";
    dir_ = test::make_temp_dir(std::string("bad_input_") + ::testing::UnitTest::GetInstance()->current_test_info()->name());
  }
  static fs::path obs() { return base_ / "out" / "obs.rnx"; }
  static fs::path nav() { return base_ / "out" / "nav.rnx"; }

  // Runs a case and checks the bounds every case shares.
  test::MeasuredProcess run_case(const std::string& command, int expected_exit, const std::string& expected_message) {
    auto r = test::run_measured(command, kTimeLimit_s);
    EXPECT_FALSE(r.timed_out) << command << " ran past " << kTimeLimit_s << " s";
    EXPECT_LE(r.max_rss_kib, kMemoryLimit_kib) << command << " took " << r.max_rss_kib / 1024 << " MiB";
    EXPECT_EQ(r.exit_code, expected_exit) << command << "\n" << r.output;
    if (!expected_message.empty()) {
      EXPECT_TRUE(std::regex_search(r.output, std::regex(expected_message)))
          << "expected /" << expected_message << "/ in:\n" << r.output;
    }
    return r;
  }
  // A copy of obs.rnx at `copy` whose first GLONASS observation value (an F14.3 field) is `text`;
  // returns its 1-based line.
  static size_t spoil_first_glonass_value(const fs::path& copy, const std::string& text) {
    auto lines = split_lines(read_text(obs()));
    const size_t line = find_line(lines, "R", find_line(lines, "END OF HEADER") + 2);
    EXPECT_LT(line, lines.size());
    if (line < lines.size()) lines[line].replace(3, 14, text);
    write_text(copy, join_lines(lines));
    return line + 1;
  }
  // A copy of nav.rnx at `copy` whose first GPS record has `text` (D19.12) in broadcast-orbit row
  // `row`, slot `slot`; returns the 1-based line.
  static size_t spoil_first_gps_field(const fs::path& copy, size_t row, size_t slot, const std::string& text) {
    auto lines = split_lines(read_text(nav()));
    const size_t record = find_line(lines, "G", find_line(lines, "END OF HEADER") + 1);
    EXPECT_LT(record + row, lines.size());
    if (record + row < lines.size()) lines[record + row].replace(4 + slot * 19, 19, text);
    write_text(copy, join_lines(lines));
    return record + row + 1;
  }
  std::string run_cmd(const fs::path& scenario, const fs::path& out) {
    return skytrace_cmd() + " run " + q(scenario) + " --out " + q(out) + " --quiet";
  }

  static inline fs::path base_;
  fs::path dir_;
};

// ---------------------------------------------------------------- outputs never replace the path

TEST_F(BadInputCatalogue, PositionIntoDevNullKeepsTheDevice) {
  run_case(skytrace_cmd() + " position " + q(obs()) + " --nav " + q(nav()) + " --out /dev/null", 0, "");
  struct stat info {};
  ASSERT_EQ(stat("/dev/null", &info), 0);
  EXPECT_TRUE(S_ISCHR(info.st_mode)) << "/dev/null is no longer a character device";
}

TEST_F(BadInputCatalogue, PositionThroughSymlinkWritesItsTarget) {
  const fs::path target = dir_ / "real.csv";
  const fs::path link = dir_ / "link.csv";
  fs::create_symlink(target, link);
  run_case(skytrace_cmd() + " position " + q(obs()) + " --nav " + q(nav()) + " --out " + q(link), 0, "");
  EXPECT_TRUE(fs::is_symlink(link));
  EXPECT_GT(fs::file_size(target), 100u);
}

TEST_F(BadInputCatalogue, PositionIntoFifoWritesThrough) {
  const fs::path fifo = dir_ / "fix.fifo";
  ASSERT_EQ(mkfifo(fifo.c_str(), 0644), 0);
  const fs::path copy = dir_ / "copy.csv";
  // A reader on the FIFO, as a pipeline would have.
  test::Background reader("cat " + q(fifo), copy);
  run_case(skytrace_cmd() + " position " + q(obs()) + " --nav " + q(nav()) + " --out " + q(fifo), 0, "");
  for (int i = 0; i < 500 && reader.running(); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  EXPECT_FALSE(reader.running()) << "the reader never saw the end of the file";
  struct stat info {};
  ASSERT_EQ(stat(fifo.c_str(), &info), 0);
  EXPECT_TRUE(S_ISFIFO(info.st_mode));
  EXPECT_NE(read_text(copy).find("time"), std::string::npos);
}

TEST_F(BadInputCatalogue, PositionIntoDevFullIsAFullDisk) {
  run_case(skytrace_cmd() + " position " + q(obs()) + " --nav " + q(nav()) + " --out /dev/full", 5,
           "/dev/full: write failed \\(no space left on the device\\)");
}

TEST_F(BadInputCatalogue, PositionIntoAFolderIsRefused) {
  run_case(skytrace_cmd() + " position " + q(obs()) + " --nav " + q(nav()) + " --out " + q(dir_), 5, "is a folder");
}

TEST_F(BadInputCatalogue, RunIntoARegularFileIsRefused) {
  write_text(dir_ / "taken", "a file, not a folder\n");
  run_case(run_cmd(base_ / "scenario.yaml", dir_ / "taken"), 5, "is not a folder");
  EXPECT_EQ(read_text(dir_ / "taken"), "a file, not a folder\n");
}

// Inputs are read only from regular files: a device or a pipe could block or never end. Before,
// each of these was "no such file".
TEST_F(BadInputCatalogue, InputsThatAreNoRegularFilesSayWhatTheyAre) {
  run_case(skytrace_cmd() + " position /dev/zero --nav " + q(nav()), 3, "/dev/zero: not a regular file \\(a device, pipe or socket\\)");
  run_case(skytrace_cmd() + " compare " + q(dir_) + " " + q(obs()), 3, "REAL: .*: is a folder, expected a file");
  run_case(skytrace_cmd() + " run '' --out " + q(dir_ / "out"), 3, "an empty path was given for a file");
}

TEST_F(BadInputCatalogue, RunAndSweepIntoAnEmptyPathAreExit5) {
  run_case(skytrace_cmd() + " run " + q(base_ / "scenario.yaml") + " --out ''", 5, "the output folder is an empty path");
  // sweep ended in "internal error: filesystem error: cannot make absolute path" (exit 1).
  write_text(dir_ / "sweep.yaml", "scenario: " + (base_ / "scenario.yaml").string() + "\naxes:\n  seed: [1, 2]\n");
  run_case(skytrace_cmd() + " sweep " + q(dir_ / "sweep.yaml") + " --out ''", 5, "the output folder is an empty path");
}

TEST_F(BadInputCatalogue, RunIntoAnUncreatableFolderIsExit5) {
  run_case(run_cmd(base_ / "scenario.yaml", "/proc/skytrace-cannot-be-here/out"), 5, "cannot create output folder");
}

TEST_F(BadInputCatalogue, RunOutputsThroughSymlinksKeepTheLinks) {
  const fs::path out = dir_ / "out";
  fs::create_directories(out);
  fs::create_symlink(dir_ / "elsewhere.rnx", out / "obs.rnx");
  run_case(run_cmd(base_ / "scenario.yaml", out), 0, "");
  EXPECT_TRUE(fs::is_symlink(out / "obs.rnx"));
  EXPECT_NE(read_text(dir_ / "elsewhere.rnx").find("END OF HEADER"), std::string::npos);
}

TEST_F(BadInputCatalogue, BagFillingTheDiskLeavesNothingBehind) {
  // A file size limit makes the MCAP file the first output to fail, as a full disk would.
  const fs::path out = dir_ / "out";
  const std::string run = skytrace_cmd() + " run " + q(test::source_dir() / "examples" / "quickstart.yaml") + " --out " +
                          q(out) + " --quiet --no-truth --set output.mcap=true --set output.mcap_compression=none" +
                          " --set time.duration_s=600";
  run_case("bash -c " + test::shell_quote("ulimit -f 1024; exec " + run), 5, "bag_0.mcap: write failed \\(file size limit exceeded\\)");
  EXPECT_TRUE(fs::is_empty(out)) << "a failed run left files in " << out;
}

// ---------------------------------------------------------------- absurd numbers

TEST_F(BadInputCatalogue, NanObservationNamesItsLine) {
  const size_t line = spoil_first_glonass_value(dir_ / "nan.rnx", "           nan");
  run_case(skytrace_cmd() + " position " + q(dir_ / "nan.rnx") + " --nav " + q(nav()) + " --out " + q(dir_ / "fix.csv"),
           3, "nan.rnx:" + std::to_string(line) + ":.*not a");
  EXPECT_FALSE(fs::exists(dir_ / "fix.csv"));
}

TEST_F(BadInputCatalogue, GlonassPseudorangeOf1e308IsMalformed) {
  const size_t line = spoil_first_glonass_value(dir_ / "huge.rnx", "        1e+308");
  run_case(skytrace_cmd() + " position " + q(dir_ / "huge.rnx") + " --nav " + q(nav()), 3,
           "huge.rnx:" + std::to_string(line) + ":.*does not fit the F14.3 field");
}

TEST_F(BadInputCatalogue, NavRecordWithSqrtAZeroNamesTheField) {
  const size_t line = spoil_first_gps_field(dir_ / "sqrta.rnx", 2, 3, " 0.000000000000E+00");  // sqrt(A)
  run_case(skytrace_cmd() + " orbits --nav " + q(dir_ / "sqrta.rnx") +
               " --start 2026-03-01T12:00:00 --duration-s 600 --interval-s 300 --csv " + q(dir_ / "o.csv"),
           3, "sqrta.rnx:" + std::to_string(line) + ":.*sqrt\\(A\\)");
  EXPECT_FALSE(fs::exists(dir_ / "o.csv"));
}

// Observations of one day against another day's navigation file: said plainly, with both spans.
TEST_F(BadInputCatalogue, NavigationOfAnotherDayIsNamedWithBothSpans) {
  write_text(dir_ / "s.yaml", nominal_scenario());
  run_case(run_cmd(dir_ / "s.yaml", dir_ / "later") + " --set time.start=2026-03-20T12:00:00 --set time.duration_s=60 --no-truth",
           0, "");
  run_case(skytrace_cmd() + " position " + q(obs()) + " --nav " + q(dir_ / "later" / "nav.rnx"), 4,
           "the navigation data does not cover .*obs.rnx: its records serve 2026-03-20.* the observations run from "
           "2026-03-01T12:00:00.0");
}

TEST_F(BadInputCatalogue, RinexVersion2E11IsRefused) {
  auto lines = split_lines(read_text(obs()));
  lines[0].replace(0, 9, "     2E11");
  write_text(dir_ / "version.rnx", join_lines(lines));
  run_case(skytrace_cmd() + " position " + q(dir_ / "version.rnx") + " --nav " + q(nav()), 3, "version.rnx:1:");
}

TEST_F(BadInputCatalogue, ToeOf1e40IsRefused) {
  const size_t line = spoil_first_gps_field(dir_ / "toe.rnx", 3, 0, " 1.000000000000E+40");  // Toe
  run_case(skytrace_cmd() + " orbits --nav " + q(dir_ / "toe.rnx") +
               " --start 2026-03-01T12:00:00 --duration-s 600 --interval-s 300 --csv " + q(dir_ / "o.csv"),
           3, "toe.rnx:" + std::to_string(line) + ": field 'Toe': out of range");
}

TEST_F(BadInputCatalogue, OrbitsWithANanosecondStepIsRefusedAtOnce) {
  run_case(skytrace_cmd() + " orbits --start 2026-03-01T12:00:00 --duration-s 3600 --interval-s 1e-9 --csv " +
               q(dir_ / "o.csv"),
           2, "rows .* more than a table may have");
}

TEST_F(BadInputCatalogue, TrajectoryGoingBackInTimeNamesItsLine) {
  write_text(dir_ / "track.csv", "t_s,x,y,z\n0,4400000,800000,4500000\n10,4400001,800000,4500000\n5,4400002,800000,4500000\n");
  write_text(dir_ / "s.yaml", nominal_scenario("receiver:\n  trajectory:\n    file: track.csv\n    frame: ecef\n"
                                                "  signals: [G1C]\n"));
  run_case(run_cmd(dir_ / "s.yaml", dir_ / "out"), 3, "track.csv:4: time is not later than the previous sample");
}

// 1,000 km in 10 s: a typo, not a motion (live poses have the same bound, 20 km/s).
TEST_F(BadInputCatalogue, TrajectoryFasterThanAnyVehicleNamesItsLine) {
  write_text(dir_ / "track.csv", "t_s,x,y,z\n0,4400000,800000,4500000\n10,4400010,800000,4500000\n20,4400010,1800000,4500000\n");
  write_text(dir_ / "s.yaml", nominal_scenario("receiver:\n  trajectory:\n    file: track.csv\n    frame: ecef\n"
                                                "  signals: [G1C]\n"));
  run_case(run_cmd(dir_ / "s.yaml", dir_ / "out"), 3, "track.csv:4: 100 km/s from the previous sample \\(line 3\\), more than 20 km/s");
}

// A moving model's pose far outside any world (the world frame is a tangent plane).
TEST_F(BadInputCatalogue, MovingModelFarOutsideTheWorldNamesItsLine) {
  write_text(dir_ / "van.csv", "t,x,y,z,yaw\n0,0,0,0,0\n10,1e300,0,0,0\n");
  run_case(skytrace_cmd() + " run " + q(test::source_dir() / "examples" / "quickstart.yaml") + " --out " + q(dir_ / "out") +
               " --set time.duration_s=5 --set 'world.moving=[{model: east_wing, trajectory: " + (dir_ / "van.csv").string() + "}]'",
           3, "van.csv:3: position \\(1e\\+300, 0, 0\\) m: expected within 1000 km of the world's origin");
}

// ---------------------------------------------------------------- small inputs, large allocations

TEST_F(BadInputCatalogue, SdfWorldIncludingItselfIsACycle) {
  write_text(dir_ / "loop.sdf",
             "<?xml version='1.0'?>\n<sdf version='1.6'>\n  <world name='loop'>\n"
             "    <include>\n      <uri>file://" + (dir_ / "loop.sdf").string() + "</uri>\n    </include>\n"
             "  </world>\n</sdf>\n");
  write_text(dir_ / "s.yaml", nominal_scenario() + "world:\n  sdf: loop.sdf\n  latitude_deg: 48.1\n  longitude_deg: 11.6\n");
  run_case(run_cmd(dir_ / "s.yaml", dir_ / "out"), 3, "loop.sdf:5: .*closes a cycle");
}

TEST_F(BadInputCatalogue, SdfModelsIncludingEachOtherAreACycle) {
  for (const char* name : {"a", "b"}) {
    fs::create_directories(dir_ / "models" / name);
    const std::string other = std::string(name) == "a" ? "b" : "a";
    write_text(dir_ / "models" / name / "model.config",
               "<?xml version='1.0'?>\n<model>\n  <name>" + std::string(name) + "</name>\n  <sdf version='1.6'>model.sdf</sdf>\n</model>\n");
    write_text(dir_ / "models" / name / "model.sdf",
               "<?xml version='1.0'?>\n<sdf version='1.6'>\n  <model name='" + std::string(name) +
                   "'>\n    <include>\n      <uri>model://" + other + "</uri>\n    </include>\n  </model>\n</sdf>\n");
  }
  write_text(dir_ / "w.sdf", "<?xml version='1.0'?>\n<sdf version='1.6'>\n  <world name='w'>\n"
                             "    <include>\n      <uri>model://a</uri>\n    </include>\n  </world>\n</sdf>\n");
  write_text(dir_ / "s.yaml", nominal_scenario() + "world:\n  sdf: w.sdf\n  model_paths: [models]\n  latitude_deg: 48.1\n  longitude_deg: 11.6\n");
  run_case(run_cmd(dir_ / "s.yaml", dir_ / "out"), 3, "closes a cycle");
}

TEST_F(BadInputCatalogue, IonexStepOfATenThousandthDegreeIsRefused) {
  // F6.1 cannot hold 0.0001: the step reads as 0, which is no grid.
  write_text(dir_ / "tiny.26i",
             ionex_text("  -180.0 180.0 0.0001                                       LON1 / LON2 / DLON\n", kGoodExponent));
  write_text(dir_ / "s.yaml", nominal_scenario() + "models:\n  ionosphere: ionex\n  ionex_file: tiny.26i\n");
  run_case(run_cmd(dir_ / "s.yaml", dir_ / "out"), 3, "tiny.26i:11: field LON1 / LON2 / DLON: invalid grid");
}

TEST_F(BadInputCatalogue, IonexGridBeyondTheLimitIsRefusedBeforeAllocation) {
  // The 3 x 4 grid of the file against a limit lowered to 10 points.
  write_text(dir_ / "grid.26i", ionex_text(kGoodLon, kGoodExponent));
  write_text(dir_ / "s.yaml", nominal_scenario() + "models:\n  ionosphere: ionex\n  ionex_file: grid.26i\n");
  run_case("SKYTRACE_MAX_GRID_POINTS=10 " + run_cmd(dir_ / "s.yaml", dir_ / "out"), 3,
           "grid.26i: LAT1 / LAT2 / DLAT and LON1 / LON2 / DLON give 12 grid points per map \\(limit 10");
}

TEST_F(BadInputCatalogue, IonexExponentOf400BlamesTheIonexFile) {
  write_text(dir_ / "exp.26i",
             ionex_text(kGoodLon, "   400                                                      EXPONENT\n"));
  write_text(dir_ / "s.yaml", nominal_scenario() + "models:\n  ionosphere: ionex\n  ionex_file: exp.26i\n");
  run_case(run_cmd(dir_ / "s.yaml", dir_ / "out"), 3, "exp.26i:12: field EXPONENT: expected an integer from -9 to 9");
}

// An ANTEX file with one receiver antenna, TEST0 NONE (G01 only), its G01 offsets record as given.
std::string antex_text(const std::string& offsets_record) {
  auto record = [](std::string content, const std::string& label) {
    content.resize(60, ' ');
    return content + label + "\n";
  };
  return record("     1.4            M", "ANTEX VERSION / SYST") + record("A", "PCV TYPE / REFANT") +
         record("", "END OF HEADER") + record("", "START OF ANTENNA") + record("TEST0           NONE", "TYPE / SERIAL NO") +
         record("     0.0", "DAZI") + record("     0.0  90.0  45.0", "ZEN1 / ZEN2 / DZEN") +
         record("   G01", "START OF FREQUENCY") + offsets_record + "   NOAZI    0.00    0.00    0.00\n" +
         record("   G01", "END OF FREQUENCY") + record("", "END OF ANTENNA");
}

std::string antex_receiver(const std::string& antenna_type) {
  return "receiver:\n  name: CATA\n  position:\n    lla_deg_m: [48.1, 11.6, 520.0]\n  signals: [G1C]\n"
         "  antenna_type: \"" + antenna_type + "\"\n  antex: ant.atx\n";
}

TEST_F(BadInputCatalogue, AntexWithoutTheNamedAntennaNamesFileAntennaAndClosest) {
  write_text(dir_ / "ant.atx",
             antex_text("      0.00      0.00     90.00                              NORTH / EAST / UP\n"));
  write_text(dir_ / "s.yaml", nominal_scenario(antex_receiver("TEST1           NONE")));
  run_case(run_cmd(dir_ / "s.yaml", dir_ / "out"), 3,
           "ant.atx: no receiver antenna 'TEST1           NONE'.*closest: 'TEST0           NONE'");
  EXPECT_TRUE(!fs::exists(dir_ / "out") || fs::is_empty(dir_ / "out")) << "a failed run left files";
}

TEST_F(BadInputCatalogue, AntexOffsetThatIsNoNumberNamesItsLine) {
  write_text(dir_ / "ant.atx",
             antex_text("      0.00      0.00       NaN                              NORTH / EAST / UP\n"));
  write_text(dir_ / "s.yaml", nominal_scenario(antex_receiver("TEST0           NONE")));
  run_case(run_cmd(dir_ / "s.yaml", dir_ / "out"), 3,
           "ant.atx:9: expected a phase centre offset in mm \\(3F10.2\\) in columns 21-30, got 'NaN'");
  EXPECT_TRUE(!fs::exists(dir_ / "out") || fs::is_empty(dir_ / "out")) << "a failed run left files";
}

TEST_F(BadInputCatalogue, GzipBombStopsAtTheDecompressionLimit) {
  // 64 MiB of blanks in about 64 KiB; the limit lowered to 16 MiB keeps the case fast.
  const fs::path bomb = dir_ / "nav.rnx.gz";
  gzFile out = gzopen(bomb.c_str(), "wb9");
  ASSERT_NE(out, nullptr);
  const std::string block(1 << 20, ' ');
  for (int i = 0; i < 64; ++i) gzwrite(out, block.data(), static_cast<unsigned>(block.size()));
  gzclose(out);
  run_case("SKYTRACE_MAX_DECOMPRESSED_MB=16 " + skytrace_cmd() + " orbits --nav " + q(bomb) +
               " --start 2026-03-01T12:00:00 --duration-s 600 --interval-s 300",
           3, "nav.rnx.gz: decompresses to more than 16 MiB");
}

TEST_F(BadInputCatalogue, OsmWayOfAHundredThousandSelfCrossingNodesFailsFast) {
  std::ostringstream osm;
  osm << "<?xml version='1.0' encoding='UTF-8'?>\n<osm version='0.6' generator='test'>\n";
  constexpr int kNodes = 100000;
  osm.precision(9);
  for (long long i = 1; i <= kNodes; ++i) {
    // A zigzag that crosses itself everywhere.
    const double lat = 48.1 + 0.001 * static_cast<double>((i * 7919) % 1000) / 1000.0;
    const double lon = 11.6 + 0.001 * static_cast<double>((i * 104729) % 1000) / 1000.0;
    osm << "  <node id='" << i << "' version='1' lat='" << lat << "' lon='" << lon << "'/>\n";
  }
  osm << "  <way id='1' version='1'>\n";
  for (long long i = 1; i <= kNodes; ++i) osm << "    <nd ref='" << i << "'/>\n";
  osm << "    <nd ref='1'/>\n    <tag k='building' v='yes'/>\n    <tag k='height' v='10'/>\n  </way>\n</osm>\n";
  write_text(dir_ / "knot.osm", osm.str());
  write_text(dir_ / "s.yaml", nominal_scenario() + "world:\n  osm: knot.osm\n");
  const auto r = run_case(run_cmd(dir_ / "s.yaml", dir_ / "out"), 3, "knot.osm");
  EXPECT_LT(r.wall_s, 30.0);
}

TEST_F(BadInputCatalogue, OsmCoordinateWithAHugeExponentNamesItsLine) {
  // Found by fuzzing: libosmium's parser overflows on it (undefined behaviour in the library).
  write_text(dir_ / "exp.osm", "<?xml version='1.0' encoding='UTF-8'?>\n<osm version='0.6'>\n"
                               "  <node id='1' version='1' lat='48.1' lon='11.6'/>\n"
                               "  <node id='2' version='1' lat='48.135E5744' lon='11.6'/>\n</osm>\n");
  write_text(dir_ / "s.yaml", nominal_scenario() + "world:\n  osm: exp.osm\n");
  run_case(run_cmd(dir_ / "s.yaml", dir_ / "out"), 3, "exp.osm:4: lat=\"48.135E5744\" is no coordinate");
}

// ---------------------------------------------------------------- configuration mistakes

TEST_F(BadInputCatalogue, TwoReceiversOfOneNameAreRefused) {
  const std::string rx = "  - name: TWIN\n    position:\n      lla_deg_m: [48.1, 11.6, 520.0]\n    signals: [G1C]\n";
  write_text(dir_ / "s.yaml", nominal_scenario("receivers:\n" + rx + rx));
  run_case(run_cmd(dir_ / "s.yaml", dir_ / "out"), 3, "s.yaml:.*receiver name 'TWIN'.*unique");
}

TEST_F(BadInputCatalogue, ReceiverNameWithAFolderIsRefused) {
  write_text(dir_ / "s.yaml", nominal_scenario("receivers:\n  - name: ../escape\n    position:\n      lla_deg_m: [48.1, 11.6, 520.0]\n"
                                                "    signals: [G1C]\n  - name: B\n    position:\n      lla_deg_m: [48.1, 11.6, 520.0]\n"
                                                "    signals: [G1C]\n"));
  run_case(run_cmd(dir_ / "s.yaml", dir_ / "out"), 3, "receiver name '../escape'");
}

TEST_F(BadInputCatalogue, DuplicateYamlKeyNamesBothLines) {
  write_text(dir_ / "s.yaml", "name: dup\nname: dup2\n" + nominal_scenario().substr(nominal_scenario().find('\n') + 1));
  run_case(run_cmd(dir_ / "s.yaml", dir_ / "out"), 3, "s.yaml:2: name: duplicate key \\(first at line 1");
}

// Values given on the command line are named by their options: the file holds no line of them.
TEST_F(BadInputCatalogue, ARefusedSetValueNamesTheOptionNotALine) {
  write_text(dir_ / "s.yaml", nominal_scenario());
  run_case(run_cmd(dir_ / "s.yaml", dir_ / "out") + " --set time.interval_s=0", 3,
           "s.yaml \\(--set time.interval_s=0\\): time.interval_s: value 0 out of range");
  run_case(skytrace_cmd() + " iq " + q(dir_ / "s.yaml") + " --out " + q(dir_ / "out") + " --sample-rate 1e308", 3,
           "s.yaml \\(--sample-rate 1e\\+308 --format sc8 --band L1\\): output.iq.sample_rate_hz: value 1e\\+308 out of range");
  EXPECT_FALSE(fs::exists(dir_ / "out" / "obs.rnx"));
}

// NaN passes CLI11's range checks (no comparison with it fails): each option checks it itself.
TEST_F(BadInputCatalogue, NanOptionsOfPositionCompareFetchAndServeAreRefused) {
  run_case(skytrace_cmd() + " position " + q(obs()) + " --nav " + q(nav()) + " --base " + q(obs()) + " --ratio-threshold nan", 2,
           "--ratio-threshold nan: expected 1 to 100");
  run_case(skytrace_cmd() + " position " + q(obs()) + " --nav " + q(nav()) + " --min-cn0-dbhz inf", 2,
           "--min-cn0-dbhz inf: expected 0 \\(no limit\\) to 100");
  run_case(skytrace_cmd() + " position " + q(obs()) + " --nav " + q(nav()) + " --rtk-elevation-mask-deg -100", 2,
           "--rtk-elevation-mask-deg must be in");
  run_case(skytrace_cmd() + " compare " + q(obs()) + " " + q(obs()) + " --epoch-tolerance-ms nan", 2,
           "--epoch-tolerance-ms nan: expected 0 to 500");
  run_case(skytrace_cmd() + " fetch --date 2020-01-01 --cache " + q(dir_ / "cache") + " --retry-delay-s nan", 2,
           "--retry-delay-s nan: expected 0 to 60");
  // serve took NaN for no limit and served until killed.
  run_case(skytrace_cmd() + " serve " + q(base_ / "scenario.yaml") + " --nmea-tcp 127.0.0.1:0 --duration-s nan", 2,
           "--duration-s nan: expected seconds");
}

// Antennas (issue #13): an unknown name lists the known ones; a band the antenna lacks and a gain
// beyond -40..+20 dBic name the antenna's file and field.
std::string receiver_with_antenna(const std::string& antenna, const std::string& signals) {
  return "receiver:\n  name: CATA\n  position:\n    lla_deg_m: [48.1, 11.6, 520.0]\n  antenna: " + antenna +
         "\n  signals: " + signals + "\n";
}

TEST_F(BadInputCatalogue, UnknownAntennaListsTheKnownOnes) {
  write_text(dir_ / "s.yaml", nominal_scenario(receiver_with_antenna("no-such-antenna", "[G1C]")));
  run_case(run_cmd(dir_ / "s.yaml", dir_ / "out"), 3,
           "s.yaml: receiver.antenna: unknown antenna 'no-such-antenna' .*known: ann-mb, choke-ring-ash701073, choke-ring-ash701945e");
  EXPECT_FALSE(fs::exists(dir_ / "out" / "obs.rnx"));
}

TEST_F(BadInputCatalogue, AntennaWithoutTheSignalsBandNamesFileAndBand) {
  write_text(dir_ / "s.yaml", nominal_scenario(receiver_with_antenna("smartphone", "[G1C, G2L]")));
  run_case(run_cmd(dir_ / "s.yaml", dir_ / "out"), 3, "antennas/smartphone.yaml: gain_dbic: no band 2 for G2L");
}

TEST_F(BadInputCatalogue, AntennaGainBeyondTwentyDbiNamesFileLineAndField) {
  fs::create_directories(dir_ / "profiles" / "antennas");  // beside the scenario
  write_text(dir_ / "profiles" / "antennas" / "hot.yaml",
             "name: hot\nelevation_deg: [0, 90]\ngain_dbic:\n  1: [-5, 25]\nlhcp_rejection_db: [3, 20]\n");
  write_text(dir_ / "s.yaml", nominal_scenario(receiver_with_antenna("hot", "[G1C]")));
  run_case(run_cmd(dir_ / "s.yaml", dir_ / "out"), 3, "hot.yaml:4: gain_dbic.1\\[1\\]: value 25 out of range \\[-40, 20\\]");
}

TEST_F(BadInputCatalogue, ServePortAbove65535IsRefused) {
  run_case(skytrace_cmd() + " serve " + q(base_ / "scenario.yaml") + " --nmea-tcp :99999 --duration-s 1", 2,
           "port must be a number from 0 to 65535");
}

TEST_F(BadInputCatalogue, ServeSurvivesHostilePosesAndStopsWithinASecond) {
  const int port = test::free_loopback_port(SOCK_DGRAM);
  test::Background server(skytrace_cmd() + " serve " + q(base_ / "scenario.yaml") +
                              " --rate-hz 10 --nmea-tcp 127.0.0.1:0 --pose-udp 127.0.0.1:" + std::to_string(port),
                          dir_ / "log");
  for (int i = 0; i < 200 && read_text(dir_ / "log").find("poses on udp port") == std::string::npos; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  ASSERT_NE(read_text(dir_ / "log").find("poses on udp port"), std::string::npos) << read_text(dir_ / "log");
  const int fd = socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  to.sin_port = htons(static_cast<std::uint16_t>(port));
  const std::vector<std::string> hostile = {"ecef 4180626.8 858159.4 4724696.3 1e18 1e18 1e18",
                                            "ecef nan nan nan", "llh 1e308 -1e308 1e308", "world 1 2 3",
                                            std::string(1400, '\x7f'), "ecef 1 2"};
  for (int round = 0; round < 500; ++round) {
    for (const auto& datagram : hostile) {
      sendto(fd, datagram.data(), datagram.size(), 0, reinterpret_cast<sockaddr*>(&to), sizeof to);
    }
  }
  close(fd);
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));
  ASSERT_TRUE(server.running()) << "serve died: " << read_text(dir_ / "log");
  const auto signalled = std::chrono::steady_clock::now();
  const int exit_code = server.stop(SIGTERM);
  const double stop_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - signalled).count();
  EXPECT_LT(stop_s, 1.0);
  EXPECT_EQ(exit_code, 0) << "-1: ended by a signal";
  const std::string log = read_text(dir_ / "log");
  EXPECT_NE(log.find("more than 20 km/s"), std::string::npos) << log;
  EXPECT_NE(log.find("pose datagrams ignored"), std::string::npos) << log;
  EXPECT_LT(log.size(), 20000u) << "ignored poses must be counted, not each reported";
}

// ---------------------------------------------------------------- signals and stale staging

TEST_F(BadInputCatalogue, SigtermMidRunLeavesNothingBehind) {
  write_text(dir_ / "long.yaml", "name: long\ntime:\n  start: 2026-03-01T12:00:00\n  scale: GPST\n  duration_s: 86400\n"
                                 "  interval_s: 1\nreceiver:\n  position:\n    lla_deg_m: [48.1, 11.6, 520.0]\n"
                                 "  signals: [G1C, G2W, R1C, E1C, E5Q, C2I]\nephemeris:\n  nominal: true\n");
  const fs::path out = dir_ / "out";
  test::Background run(run_cmd(dir_ / "long.yaml", out), dir_ / "log");
  // Wait until the run writes into its staging folder, then stop it.
  for (int i = 0; i < 600 && !has_staging_folder(out); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  ASSERT_TRUE(has_staging_folder(out)) << read_text(dir_ / "log");
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  const auto signalled = std::chrono::steady_clock::now();
  const int exit_code = run.stop(SIGTERM);
  const double stop_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - signalled).count();
  EXPECT_EQ(exit_code, 128 + SIGTERM) << read_text(dir_ / "log");
  EXPECT_NE(read_text(dir_ / "log").find("stopped by SIGTERM"), std::string::npos) << read_text(dir_ / "log");
  EXPECT_LT(stop_s, 5.0);
  EXPECT_FALSE(has_staging_folder(out));
  EXPECT_TRUE(fs::is_empty(out));
}

TEST_F(BadInputCatalogue, StaleStagingOfADeadRunIsRemoved) {
  const fs::path out = dir_ / "out";
  const fs::path stale = out / ".skytrace-staging-999999-deadbeef";
  fs::create_directories(stale);
  write_text(stale / ".lock", "");
  write_text(stale / "truth.csv", std::string(1 << 20, 'x'));
  run_case(run_cmd(base_ / "scenario.yaml", out), 0, "");
  EXPECT_FALSE(fs::exists(stale));
  EXPECT_TRUE(fs::exists(out / "obs.rnx"));
}

}  // namespace
}  // namespace skytrace
