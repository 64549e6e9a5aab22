// `skytrace serve` against the programs robots and base stations use: gpsd reads the NMEA stream
// over TCP and reports 3D fixes at the ESBC antenna; RTKLIB's str2str records the RTCM 3 stream and
// convbin turns it into RINEX with the satellites and pseudoranges of `skytrace run` at the same
// epochs; the pseudo-terminal carries NMEA; SIGTERM stops the server cleanly.
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <cmath>
#include <fcntl.h>
#include <fstream>
#include <set>
#include <sstream>
#include <thread>

#include "process.hpp"
#include "skytrace/core/frames.hpp"
#include "skytrace/io/rinex_obs.hpp"
#include "test_support.hpp"

namespace skytrace {
namespace {

const Eigen::Vector3d kEsbcMarker(3582105.2910, 532589.7313, 5232754.8054);

using test::Background;

std::string read_file(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// Waits (up to 20 s) for a line of the log starting with `prefix`; returns the rest of the line.
std::string wait_for_line(const std::filesystem::path& log, const std::string& prefix) {
  for (int i = 0; i < 200; ++i) {
    std::istringstream lines(read_file(log));
    for (std::string line; std::getline(lines, line);) {
      if (line.rfind(prefix, 0) == 0) return line.substr(prefix.size());
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  return {};
}

class Serve : public ::testing::Test {
 protected:
  void SetUp() override {
    contract_ = test::shared_data_dir().parent_path() / "contract" / "esbc-open-sky.yaml";
    if (!std::filesystem::exists(contract_) ||
        !std::filesystem::exists(test::shared_data_dir() / "real/esbc_2020177/ESBC00DNK_R_20201770000_01D_MN.rnx")) {
      GTEST_SKIP() << "contract scenario or ESBC data absent (set SKYTRACE_SHARED_DATA)";
    }
    dir_ = test::make_temp_dir(std::string("serve_") + ::testing::UnitTest::GetInstance()->current_test_info()->name() +
                               "_" + std::to_string(getpid()));
  }
  std::string serve_command(const std::string& options) const {
    return test::shell_quote(test::skytrace_executable().string()) + " serve " + test::shell_quote(contract_.string()) +
           " " + options;
  }
  std::filesystem::path contract_, dir_;
};

TEST_F(Serve, GpsdReportsThreeDimensionalFixesAtTheStation) {
  if (!test::program_available("gpspipe") || !std::filesystem::exists("/usr/sbin/gpsd")) {
    GTEST_SKIP() << "gpsd and gpspipe (Debian packages gpsd, gpsd-clients) are not installed";
  }
  Background server(serve_command("--nmea-tcp 127.0.0.1:0 --rate-hz 2 --duration-s 120"), dir_ / "serve.log");
  const std::string port = wait_for_line(dir_ / "serve.log", "skytrace serve: NMEA on tcp port ");
  ASSERT_FALSE(port.empty()) << read_file(dir_ / "serve.log");
  const int control_port = test::free_loopback_port(SOCK_STREAM);
  Background gpsd("/usr/sbin/gpsd -N -n -S " + std::to_string(control_port) + " tcp://127.0.0.1:" + port,
                  dir_ / "gpsd.log");
  test::ProcessResult pipe;
  for (int attempt = 0; attempt < 10; ++attempt) {
    pipe = test::run_command("timeout 40 gpspipe -w -n 30 127.0.0.1:" + std::to_string(control_port));
    if (pipe.output.find("\"class\":\"TPV\"") != std::string::npos) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
  }
  const Eigen::Vector3d up = ecef_to_enu_rotation(ecef_to_geodetic(kEsbcMarker)).row(2).transpose();
  const Eigen::Vector3d antenna = kEsbcMarker + 0.2160 * up;
  int fixes = 0;
  std::istringstream lines(pipe.output);
  for (std::string line; std::getline(lines, line);) {
    const auto j = nlohmann::json::parse(line, nullptr, false);
    if (j.is_discarded() || j.value("class", "") != "TPV" || j.value("mode", 0) != 3) continue;
    ASSERT_TRUE(j.contains("lat") && j.contains("lon") && j.contains("altHAE")) << line;
    const Geodetic g{j["lat"].get<double>(), j["lon"].get<double>(), j["altHAE"].get<double>()};
    EXPECT_LT((geodetic_to_ecef(g) - antenna).norm(), 15.0) << line;
    ++fixes;
  }
  EXPECT_GE(fixes, 3) << pipe.output << "\n" << read_file(dir_ / "gpsd.log");
  gpsd.stop();
  EXPECT_EQ(server.stop(SIGTERM), 0) << read_file(dir_ / "serve.log");
  EXPECT_NE(read_file(dir_ / "serve.log").find("skytrace serve: stopped after"), std::string::npos);
}

TEST_F(Serve, Str2strRecordsRtcmThatConvbinTurnsIntoTheStationsObservations) {
  if (!test::program_available("str2str") || !test::program_available("convbin")) {
    GTEST_SKIP() << "str2str and convbin (Debian package rtklib) are not installed";
  }
  Background server(serve_command("--rtcm-tcp 127.0.0.1:0 --rate-hz 1 --duration-s 120"), dir_ / "serve.log");
  const std::string port = wait_for_line(dir_ / "serve.log", "skytrace serve: RTCM 3 on tcp port ");
  ASSERT_FALSE(port.empty()) << read_file(dir_ / "serve.log");
  {
    Background recorder("str2str -in tcpcli://127.0.0.1:" + port + " -out file://" +
                            test::shell_quote((dir_ / "stream.rtcm3").string()),
                        dir_ / "str2str.log");
    // Until a few epochs are in the file (the file grows by about 3 kB per epoch).
    for (int i = 0; i < 300; ++i) {
      std::error_code ec;
      if (std::filesystem::exists(dir_ / "stream.rtcm3") && std::filesystem::file_size(dir_ / "stream.rtcm3", ec) > 15000) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    recorder.stop(SIGINT);
  }
  EXPECT_EQ(server.stop(SIGINT), 0) << read_file(dir_ / "serve.log");
  const auto conv = test::run_command("convbin -r rtcm3 -tr '2020/06/25 00:00:00' -f 5 -od -os " +
                                      test::shell_quote((dir_ / "stream.rtcm3").string()) + " -o " +
                                      test::shell_quote((dir_ / "stream.obs").string()) + " 2>&1");
  ASSERT_EQ(conv.exit_code, 0) << conv.output;
  const auto served = io::read_rinex_obs(dir_ / "stream.obs");
  ASSERT_TRUE(served.ok()) << served.error().message;
  ASSERT_GE(served->epochs.size(), 2U) << read_file(dir_ / "str2str.log");

  // The same receiver simulated by `skytrace run` at 1 s epochs over the first two minutes.
  const auto run = test::run_command(test::shell_quote(test::skytrace_executable().string()) + " run " +
                                     test::shell_quote(contract_.string()) + " --out " +
                                     test::shell_quote((dir_ / "run").string()) +
                                     " --quiet --no-truth --set time.interval_s=1 --set time.duration_s=120");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const auto simulated = io::read_rinex_obs(dir_ / "run/obs.rnx");
  ASSERT_TRUE(simulated.ok()) << simulated.error().message;
  const auto c1c = [](const io::ObservationFile& file, const io::SatelliteObservations& sat) -> std::optional<double> {
    const auto k = file.header.type_index(sat.satellite.system, "C1C");
    if (!k || *k >= sat.values.size()) return std::nullopt;
    return sat.values[*k].value;
  };
  int compared = 0;
  for (const auto& epoch : served->epochs) {
    const io::ObservationEpoch* reference = nullptr;
    for (const auto& e : simulated->epochs) {
      if (e.time == epoch.time) reference = &e;
    }
    ASSERT_NE(reference, nullptr) << epoch.time.to_iso8601(TimeScale::kGpst) << " is not a whole second of the scenario";
    std::set<SatelliteId> a, b;
    for (const auto& s : epoch.satellites) a.insert(s.satellite);
    for (const auto& s : reference->satellites) b.insert(s.satellite);
    EXPECT_EQ(a, b) << epoch.time.to_iso8601(TimeScale::kGpst);
    for (const auto& s : epoch.satellites) {
      const auto* r = reference->find(s.satellite);
      if (r == nullptr) continue;
      const auto pa = c1c(*served, s);
      const auto pb = c1c(*simulated, *r);
      if (!pa || !pb) continue;
      EXPECT_NEAR(*pa, *pb, 0.002) << s.satellite.to_string() << " " << epoch.time.to_iso8601(TimeScale::kGpst);
      ++compared;
    }
  }
  EXPECT_GT(compared, 20);
}

TEST_F(Serve, PseudoTerminalCarriesNmeaAndDisappearsOnStop) {
  const auto link = dir_ / "gnss0";
  Background server(serve_command("--pty " + test::shell_quote(link.string()) + " --rate-hz 5 --duration-s 120"),
                    dir_ / "serve.log");
  ASSERT_FALSE(wait_for_line(dir_ / "serve.log", "skytrace serve: NMEA on ").empty()) << read_file(dir_ / "serve.log");
  ASSERT_TRUE(std::filesystem::is_symlink(link));
  const int fd = open(link.c_str(), O_RDONLY | O_NOCTTY | O_NONBLOCK);
  ASSERT_GE(fd, 0);
  std::string received;
  for (int i = 0; i < 200 && received.find("GGA,") == std::string::npos; ++i) {
    char buffer[1024];
    const ssize_t n = read(fd, buffer, sizeof buffer);
    if (n > 0) received.append(buffer, static_cast<size_t>(n));
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  close(fd);
  EXPECT_NE(received.find("$GNGGA,"), std::string::npos) << received;
  EXPECT_EQ(server.stop(SIGTERM), 0);
  EXPECT_FALSE(std::filesystem::exists(link));
}

}  // namespace
}  // namespace skytrace

namespace skytrace {
namespace {

// Reads what a TCP server sends for `seconds`.
std::string read_tcp(int port, double seconds) {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  address.sin_port = htons(static_cast<std::uint16_t>(port));
  std::string text;
  if (connect(fd, reinterpret_cast<sockaddr*>(&address), sizeof address) != 0) {
    close(fd);
    return text;
  }
  timeval timeout{0, 200000};
  setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof timeout);
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  char buffer[4096];
  while (std::chrono::steady_clock::now() < end) {
    const ssize_t n = recv(fd, buffer, sizeof buffer, 0);
    if (n > 0) text.append(buffer, static_cast<size_t>(n));
    if (n == 0) break;
  }
  close(fd);
  return text;
}

// Live RTK between two virtual receivers: one serve streams the base's RTCM 3 (the contract pair's
// BASE), another (its ROVR) takes it with --rtk-base-tcp, connecting again while the base is not
// up yet: its NMEA reports GGA quality 4 (RTK fixed) at the rover's position.
// GGA sentences with quality 4 (RTK fixed) at the rover of the RTK pair, each checked against the
// rover's position.
size_t rtk_fixed_gga_at_the_rover(const std::string& nmea) {
  size_t fixed = 0;
  std::istringstream lines(nmea);
  for (std::string line; std::getline(lines, line);) {
    if (line.find("GGA,") == std::string::npos) continue;
    std::vector<std::string> f;
    for (std::stringstream s(line); std::getline(s, line, ',');) f.push_back(line);
    if (f.size() < 10 || f[6] != "4") continue;
    ++fixed;
    // 55.4935 N, 8.4880 E, 75 m: ddmm.mmmmmmm to within a few centimetres; altitude above mean sea
    // level plus the geoid separation is the ellipsoidal height.
    EXPECT_NEAR(std::stod(f[2].substr(2)) / 60.0 + std::stod(f[2].substr(0, 2)), 55.4935, 1e-6) << line;
    EXPECT_NEAR(std::stod(f[4].substr(3)) / 60.0 + std::stod(f[4].substr(0, 3)), 8.4880, 2e-6) << line;
    EXPECT_NEAR(std::stod(f[9]) + std::stod(f[11]), 75.0, 0.1) << line;
  }
  return fixed;
}

TEST(ServeRtk, RoverFixesFromABaseStreamOverTcp) {
  const auto contract = test::shared_data_dir().parent_path() / "contract" / "rtk-pair.yaml";
  if (!std::filesystem::exists(contract) ||
      !std::filesystem::exists(test::shared_data_dir() / "real/esbc_2020177/ESBC00DNK_R_20201770000_01D_MN.rnx")) {
    GTEST_SKIP() << "contract scenario or ESBC data absent (set SKYTRACE_SHARED_DATA)";
  }
  const auto dir = test::make_temp_dir("serve_rtk_" + std::to_string(getpid()));
  const std::string skytrace = test::shell_quote(test::skytrace_executable().string());
  const int base_port = test::free_loopback_port(SOCK_STREAM);
  // The rover first: it waits for the base.
  Background rover(skytrace + " serve " + test::shell_quote(contract.string()) + " --receiver ROVR --rate-hz 2" +
                       " --duration-s 40 --nmea-tcp 127.0.0.1:0 --rtk-base-tcp 127.0.0.1:" + std::to_string(base_port),
                   dir / "rover.log");
  const std::string rover_port = wait_for_line(dir / "rover.log", "skytrace serve: NMEA on tcp port ");
  ASSERT_FALSE(rover_port.empty()) << read_file(dir / "rover.log");
  Background base(skytrace + " serve " + test::shell_quote(contract.string()) + " --receiver BASE --rate-hz 2" +
                      " --duration-s 40 --rtcm-tcp 127.0.0.1:" + std::to_string(base_port),
                  dir / "base.log");
  ASSERT_FALSE(wait_for_line(dir / "rover.log", "skytrace serve: RTK corrections from ").empty()) << read_file(dir / "rover.log");
  const std::string nmea = read_tcp(std::stoi(rover_port), 15.0);
  EXPECT_GT(rtk_fixed_gga_at_the_rover(nmea), 5u) << nmea.substr(0, 2000) << "\n" << read_file(dir / "rover.log");
}

// The same through an NTRIP caster (RTKLIB's str2str as the caster, user and password required),
// and what a rover says when the caster refuses it.
TEST(ServeRtk, RoverFixesFromAnNtripCasterAndRefusalsSayWhy) {
  const auto contract = test::shared_data_dir().parent_path() / "contract" / "rtk-pair.yaml";
  if (!std::filesystem::exists(contract) ||
      !std::filesystem::exists(test::shared_data_dir() / "real/esbc_2020177/ESBC00DNK_R_20201770000_01D_MN.rnx")) {
    GTEST_SKIP() << "contract scenario or ESBC data absent (set SKYTRACE_SHARED_DATA)";
  }
  if (!test::program_available("str2str")) GTEST_SKIP() << "str2str not installed (rtklib)";
  const auto dir = test::make_temp_dir("serve_ntrip_" + std::to_string(getpid()));
  const std::string skytrace = test::shell_quote(test::skytrace_executable().string());
  const int base_port = test::free_loopback_port(SOCK_STREAM);
  const int caster_port = test::free_loopback_port(SOCK_STREAM);
  Background base(skytrace + " serve " + test::shell_quote(contract.string()) + " --receiver BASE --rate-hz 2" +
                      " --duration-s 45 --rtcm-tcp 127.0.0.1:" + std::to_string(base_port),
                  dir / "base.log");
  ASSERT_FALSE(wait_for_line(dir / "base.log", "skytrace serve: RTCM 3 on tcp port ").empty()) << read_file(dir / "base.log");
  Background caster("str2str -in tcpcli://127.0.0.1:" + std::to_string(base_port) + " -out ntripc://rover:s3cret@:" +
                        std::to_string(caster_port) + "/ESBC",
                    dir / "caster.log");
  const std::string caster_url = "127.0.0.1:" + std::to_string(caster_port);
  const auto rover_command = [&](const std::string& url, double duration_s) {
    return skytrace + " serve " + test::shell_quote(contract.string()) + " --receiver ROVR --rate-hz 2 --duration-s " +
           std::to_string(duration_s) + " --nmea-tcp 127.0.0.1:0 --rtk-base-ntrip " + test::shell_quote(url);
  };
  Background rover(rover_command("ntrip://rover:s3cret@" + caster_url + "/ESBC", 35.0), dir / "rover.log");
  Background wrong_password(rover_command("ntrip://rover:guess@" + caster_url + "/ESBC", 8.0), dir / "wrong.log");
  Background wrong_mount(rover_command("ntrip://rover:s3cret@" + caster_url + "/NOPE", 8.0), dir / "mount.log");
  const std::string rover_port = wait_for_line(dir / "rover.log", "skytrace serve: NMEA on tcp port ");
  ASSERT_FALSE(rover_port.empty()) << read_file(dir / "rover.log");
  ASSERT_FALSE(wait_for_line(dir / "rover.log", "skytrace serve: RTK corrections from ntrip://rover@").empty())
      << read_file(dir / "rover.log") << read_file(dir / "caster.log");
  const std::string nmea = read_tcp(std::stoi(rover_port), 15.0);
  EXPECT_GT(rtk_fixed_gga_at_the_rover(nmea), 5u) << nmea.substr(0, 2000) << "\n" << read_file(dir / "rover.log");

  ASSERT_FALSE(wait_for_line(dir / "wrong.log", "skytrace serve: stopped after ").empty()) << read_file(dir / "wrong.log");
  const std::string wrong = read_file(dir / "wrong.log");
  EXPECT_NE(wrong.find("error: RTK base ntrip://rover@" + caster_url + "/ESBC: the caster closed the connection without answering"),
            std::string::npos) << wrong;
  EXPECT_EQ(wrong.find("guess"), std::string::npos) << "the password must not be printed:\n" << wrong;
  ASSERT_FALSE(wait_for_line(dir / "mount.log", "skytrace serve: stopped after ").empty()) << read_file(dir / "mount.log");
  const std::string mount = read_file(dir / "mount.log");
  EXPECT_NE(mount.find("no such mountpoint (it sent its source table); it offers ESBC"), std::string::npos) << mount;
}

}  // namespace
}  // namespace skytrace

namespace skytrace {
namespace {

// A moving-base rover served live (`--receiver` of a receiver with rtk.moving_base): serve
// simulates the base antenna beside it, and the heading of the baseline (30 degrees in the
// scenario) comes as HDT and THS on the NMEA stream.
TEST(ServeRtk, MovingBaseRoverStreamsItsHeading) {
  const auto nav = test::shared_data_dir() / "real/esbc_2020177/ESBC00DNK_R_20201770000_01D_MN.rnx";
  if (!std::filesystem::exists(nav)) GTEST_SKIP() << "ESBC navigation file absent";
  const auto dir = test::make_temp_dir("serve_heading_" + std::to_string(getpid()));
  std::ofstream(dir / "heading.yaml") << test::moving_base_scenario_yaml(nav, "0.7, 1.2124356, 1.5", 600);
  Background rover(test::shell_quote(test::skytrace_executable().string()) + " serve " +
                       test::shell_quote((dir / "heading.yaml").string()) +
                       " --receiver ANT2 --rate-hz 2 --duration-s 30 --nmea-tcp 127.0.0.1:0",
                   dir / "rover.log");
  const std::string port = wait_for_line(dir / "rover.log", "skytrace serve: NMEA on tcp port ");
  ASSERT_FALSE(port.empty()) << read_file(dir / "rover.log");
  const std::string nmea = read_tcp(std::stoi(port), 10.0);
  std::vector<double> headings;
  for (size_t at = nmea.find("HDT,"); at != std::string::npos; at = nmea.find("HDT,", at + 4)) {
    headings.push_back(std::stod(nmea.substr(at + 4)));
  }
  ASSERT_GT(headings.size(), 5u) << nmea.substr(0, 2000) << "\n" << read_file(dir / "rover.log");
  for (const double h : headings) EXPECT_NEAR(h, 30.0, 0.5);
  EXPECT_NE(nmea.find("THS,"), std::string::npos);
}

}  // namespace
}  // namespace skytrace
