// `skytrace serve SCENARIO`: a virtual receiver in real time. Streams NMEA 0183 and RTCM 3 over TCP
// (any number of clients) and NMEA over a pseudo-terminal, so gpsd, nmea_navsat_driver or RTKLIB's
// str2str connect as to hardware. The antenna follows the scenario, or poses sent as UDP datagrams.
#include <arpa/inet.h>
#include <fcntl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <termios.h>
#include <unistd.h>

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "commands.hpp"
#include "skytrace/core/cancellation.hpp"
#include "skytrace/core/frames.hpp"
#include "skytrace/io/nmea.hpp"
#include "skytrace/io/rtcm3.hpp"
#include "skytrace/sim/live.hpp"
#include "skytrace/sim/rtk_base_link.hpp"
#include "skytrace/sim/scenario.hpp"
#include "skytrace/sim/sinks.hpp"
#include "skytrace/sim/streams.hpp"

namespace skytrace::cli {
namespace {

// Bounds that keep one misbehaving peer from starving the epochs or growing memory.
constexpr size_t kMaxTcpClients = 64;
constexpr size_t kMaxDatagramsPerWakeup = 256;
constexpr size_t kMaxClientBacklogBytes = size_t{1} << 20;

struct ServeArgs {
  std::string scenario;
  std::string receiver;  // the receiver of a scenario with several (by name); empty: the first
  std::string nmea_tcp, rtcm_tcp, pty, pose_udp;
  std::string rtk_base_tcp;  // HOST:PORT of a base's RTCM 3 stream
  std::string rtk_base_ntrip;  // ntrip://[USER[:PASSWORD]@]HOST[:PORT]/MOUNTPOINT
  double rate_hz = 1.0;
  double duration_s = 0.0;
  std::vector<std::string> overrides;
};

Error io_error(const std::string& what) { return make_error(ErrorCode::kIo, what + ": " + std::strerror(errno)); }

// A bound socket of HOST:PORT (port 0: any free port).
Result<int> bind_socket(const std::string& endpoint, int type, const char* option) {
  const size_t colon = endpoint.rfind(':');
  if (colon == std::string::npos || colon + 1 == endpoint.size()) {
    return make_error(ErrorCode::kInvalidArgument, fmt::format("{} '{}': expected HOST:PORT", option, endpoint));
  }
  std::string host = endpoint.substr(0, colon);
  if (host.size() >= 2 && host.front() == '[' && host.back() == ']') host = host.substr(1, host.size() - 2);
  const std::string port = endpoint.substr(colon + 1);
  // getaddrinfo wraps numbers above 65535 into some other port: check the number ourselves.
  const bool digits = port.size() <= 5 && std::all_of(port.begin(), port.end(), [](unsigned char c) { return std::isdigit(c); });
  if (!digits || std::stoi(port) > 65535) {
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("{} '{}': port must be a number from 0 to 65535 (0: any free port)", option, endpoint));
  }
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = type;
  hints.ai_flags = AI_PASSIVE | AI_NUMERICSERV;
  addrinfo* found = nullptr;
  if (const int rc = getaddrinfo(host.empty() ? nullptr : host.c_str(), port.c_str(), &hints, &found); rc != 0) {
    return make_error(ErrorCode::kInvalidArgument, fmt::format("{} '{}': {}", option, endpoint, gai_strerror(rc)));
  }
  std::unique_ptr<addrinfo, decltype(&freeaddrinfo)> guard(found, freeaddrinfo);
  const int fd = socket(found->ai_family, found->ai_socktype | SOCK_NONBLOCK | SOCK_CLOEXEC, found->ai_protocol);
  if (fd < 0) return io_error(fmt::format("{} {}: socket", option, endpoint));
  const int yes = 1;
  setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
  if (bind(fd, found->ai_addr, found->ai_addrlen) != 0 || (type == SOCK_STREAM && listen(fd, 16) != 0)) {
    auto error = io_error(fmt::format("{} {}: cannot bind", option, endpoint));
    close(fd);
    return error;
  }
  return fd;
}

int bound_port(int fd) {
  sockaddr_storage address{};
  socklen_t length = sizeof address;
  getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length);
  if (address.ss_family == AF_INET6) return ntohs(reinterpret_cast<sockaddr_in6*>(&address)->sin6_port);
  return ntohs(reinterpret_cast<sockaddr_in*>(&address)->sin_port);
}

// A TCP server that sends the same bytes to every connected client. A client that does not keep up
// (more than 1 MiB waiting) is dropped, as a receiver's port would overrun.
class TcpBroadcaster {
 public:
  explicit TcpBroadcaster(int listen_fd) : listen_fd_(listen_fd) {}
  ~TcpBroadcaster() {
    for (const auto& c : clients_) close(c.fd);
    close(listen_fd_);
  }
  TcpBroadcaster(const TcpBroadcaster&) = delete;
  TcpBroadcaster& operator=(const TcpBroadcaster&) = delete;

  [[nodiscard]] int port() const { return bound_port(listen_fd_); }
  void add_poll_fds(std::vector<pollfd>& fds) const {
    fds.push_back({listen_fd_, POLLIN, 0});
    for (const auto& c : clients_) {
      fds.push_back({c.fd, static_cast<short>(POLLIN | (c.pending.empty() ? 0 : POLLOUT)), 0});
    }
  }
  // Accepts new clients, discards what clients send, flushes pending bytes, drops closed ones.
  void service() {
    for (;;) {
      const int fd = accept4(listen_fd_, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
      if (fd < 0) break;
      if (clients_.size() >= kMaxTcpClients) {
        close(fd);  // full, as a receiver with all its ports in use
        ++refused_;
        continue;
      }
      clients_.push_back({fd, {}});
    }
    for (auto& c : clients_) {
      char discard[4096];
      for (int reads = 0;; ++reads) {
        const ssize_t n = recv(c.fd, discard, sizeof discard, MSG_DONTWAIT);
        if (n > 0 && reads < 64) continue;  // what clients send is not used; bounded per wake-up
        if (n > 0) break;
        if (n == 0 || (errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR)) c.dead = true;
        break;
      }
      flush(c);
    }
    drop_dead();
  }
  void broadcast(std::string_view bytes) {
    for (auto& c : clients_) {
      if (c.pending.size() + bytes.size() > kMaxClientBacklogBytes) {
        c.dead = true;
        continue;
      }
      c.pending.append(bytes);
      flush(c);
    }
    drop_dead();
  }
  [[nodiscard]] size_t client_count() const { return clients_.size(); }
  [[nodiscard]] size_t refused_count() const { return refused_; }

 private:
  struct Client {
    int fd;
    std::string pending;
    bool dead = false;
  };
  static void flush(Client& c) {
    while (!c.pending.empty() && !c.dead) {
      const ssize_t n = send(c.fd, c.pending.data(), c.pending.size(), MSG_DONTWAIT | MSG_NOSIGNAL);
      if (n > 0) {
        c.pending.erase(0, static_cast<size_t>(n));
      } else if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
        break;
      } else if (n < 0 && errno == EINTR) {
        continue;
      } else {
        c.dead = true;
      }
    }
  }
  void drop_dead() {
    for (auto it = clients_.begin(); it != clients_.end();) {
      if (it->dead) {
        close(it->fd);
        it = clients_.erase(it);
      } else {
        ++it;
      }
    }
  }
  int listen_fd_;
  std::vector<Client> clients_;
  size_t refused_ = 0;
};

// A pseudo-terminal in raw mode whose slave is reached through a symbolic link, like a serial port.
class PseudoTerminal {
 public:
  static Result<std::unique_ptr<PseudoTerminal>> open(const std::filesystem::path& link) {
    std::error_code ec;
    if (std::filesystem::is_symlink(link, ec)) {
      std::filesystem::remove(link, ec);  // left behind by an earlier run
    } else if (std::filesystem::exists(link, ec)) {
      return make_error(ErrorCode::kInvalidArgument, link.string() + ": --pty path exists and is not a symbolic link");
    }
    const int master = posix_openpt(O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
    if (master < 0) return io_error("posix_openpt");
    auto pty = std::unique_ptr<PseudoTerminal>(new PseudoTerminal(master));
    if (grantpt(master) != 0 || unlockpt(master) != 0) return io_error("grantpt/unlockpt");
    const char* name = ptsname(master);
    if (name == nullptr) return io_error("ptsname");
    pty->slave_name_ = name;
    // Keeping the slave open lets writes succeed while no reader is attached; raw mode keeps CR LF.
    pty->slave_ = ::open(name, O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
    if (pty->slave_ < 0) return io_error(std::string("open ") + name);
    termios tio{};
    if (tcgetattr(pty->slave_, &tio) == 0) {
      cfmakeraw(&tio);
      cfsetispeed(&tio, B115200);
      cfsetospeed(&tio, B115200);
      tcsetattr(pty->slave_, TCSANOW, &tio);
    }
    std::filesystem::create_symlink(name, link, ec);
    if (ec) return make_error(ErrorCode::kIo, link.string() + ": cannot create the link to " + name + " (" + ec.message() + ")");
    pty->link_ = link;
    return pty;
  }
  ~PseudoTerminal() {
    if (!link_.empty()) {
      std::error_code ignored;
      std::filesystem::remove(link_, ignored);
    }
    if (slave_ >= 0) close(slave_);
    close(master_);
  }
  PseudoTerminal(const PseudoTerminal&) = delete;
  PseudoTerminal& operator=(const PseudoTerminal&) = delete;

  [[nodiscard]] const std::string& slave_name() const { return slave_name_; }
  // Writes what fits; with nobody reading, stale sentences are discarded rather than queued.
  void write_bytes(std::string_view bytes) {
    while (!bytes.empty()) {
      const ssize_t n = ::write(master_, bytes.data(), bytes.size());
      if (n > 0) {
        bytes.remove_prefix(static_cast<size_t>(n));
      } else if (n < 0 && errno == EINTR) {
        continue;
      } else {
        tcflush(slave_, TCIFLUSH);
        break;
      }
    }
  }

 private:
  explicit PseudoTerminal(int master) : master_(master) {}
  int master_;
  int slave_ = -1;
  std::string slave_name_;
  std::filesystem::path link_;
};

// The byte streams of serve's sinks: every TCP client, or the pseudo-terminal.
class TcpStream final : public sim::ByteStream {
 public:
  explicit TcpStream(std::shared_ptr<TcpBroadcaster> server) : server_(std::move(server)) {}
  Status write(std::string_view bytes) override {
    server_->broadcast(bytes);
    return Ok{};
  }

 private:
  std::shared_ptr<TcpBroadcaster> server_;
};
class PtyStream final : public sim::ByteStream {
 public:
  explicit PtyStream(std::unique_ptr<PseudoTerminal> pty) : pty_(std::move(pty)) {}
  Status write(std::string_view bytes) override {
    pty_->write_bytes(bytes);
    return Ok{};
  }

 private:
  std::unique_ptr<PseudoTerminal> pty_;
};

int serve(const ServeArgs& args) {
  if (!(args.rate_hz > 0.0 && args.rate_hz <= 100.0)) {
    return report_error(make_error(ErrorCode::kInvalidArgument, fmt::format("--rate-hz {}: expected 0 < R <= 100", args.rate_hz)));
  }
  if (!(args.duration_s >= 0.0)) {  // NaN too: it compared as no limit and served for ever
    return report_error(make_error(
        ErrorCode::kInvalidArgument,
        fmt::format("--duration-s {}: expected seconds, 0 or more (0: until SIGINT/SIGTERM)", args.duration_s)));
  }
  if (args.nmea_tcp.empty() && args.rtcm_tcp.empty() && args.pty.empty()) {
    return report_error(make_error(ErrorCode::kInvalidArgument, "give at least one of --nmea-tcp, --rtcm-tcp, --pty"));
  }
  auto scenario = sim::load_scenario(args.scenario, args.overrides);
  if (!scenario) return report_error(scenario.error());
  sim::LiveOptions live_options;
  if (!args.receiver.empty()) {
    auto index = sim::find_receiver(*scenario, args.receiver);
    if (!index) return report_error(index.error().with_context("--receiver"));
    live_options.receiver_index = *index;
  }
  if (!args.rtk_base_tcp.empty() && !args.rtk_base_ntrip.empty()) {
    return report_error(make_error(ErrorCode::kInvalidArgument, "give one of --rtk-base-tcp and --rtk-base-ntrip"));
  }
  const std::string rtk_source = !args.rtk_base_ntrip.empty() ? args.rtk_base_ntrip : args.rtk_base_tcp;
  if (!args.rtk_base_ntrip.empty() && args.rtk_base_ntrip.rfind("ntrip://", 0) != 0) {
    return report_error(make_error(ErrorCode::kInvalidArgument, "--rtk-base-ntrip '" + args.rtk_base_ntrip +
                                                                    "': expected ntrip://[USER[:PASSWORD]@]HOST[:PORT]/MOUNTPOINT"));
  }
  std::unique_ptr<sim::RtkBaseLink> rtk_base;
  if (!rtk_source.empty()) {
    auto link = sim::RtkBaseLink::create(rtk_source, scenario->time.start,
                                         [](sim::RtkBaseLink::Note kind, const std::string& text) {
                                           if (kind == sim::RtkBaseLink::Note::kInfo) {
                                             std::cout << "skytrace serve: " << text << std::endl;
                                           } else {
                                             std::cerr << "skytrace serve: "
                                                       << (kind == sim::RtkBaseLink::Note::kError ? "error: " : "warning: ")
                                                       << text << "\n";
                                           }
                                         });
    if (!link) return report_error(link.error());
    rtk_base = std::move(*link);
  }
  live_options.rtk = rtk_base != nullptr;
  auto session = sim::LiveSession::create(*scenario, live_options);
  if (!session) return report_error(session.error());
  sim::LiveSession& live = **session;
  for (const auto& warning : live.resources().warnings) std::cerr << "skytrace serve: warning: " << warning << "\n";

  // The outputs: sinks of the receiver's epoch stream, as `skytrace run`'s (sim/sinks).
  const sim::SinkReceiver sink_receiver{&live.receiver(), live.marker_ecef_m(), &live.observation_header(), nullptr, ""};
  std::vector<std::unique_ptr<sim::EpochSink>> sinks;
  std::vector<std::shared_ptr<TcpBroadcaster>> servers;  // served between epochs
  auto tcp_server = [&](const std::string& endpoint, const char* option, const char* what) -> Result<std::shared_ptr<TcpBroadcaster>> {
    auto fd = bind_socket(endpoint, SOCK_STREAM, option);
    if (!fd) return fd.error();
    auto server = std::make_shared<TcpBroadcaster>(*fd);
    std::cout << "skytrace serve: " << what << " on tcp port " << server->port() << std::endl;
    servers.push_back(server);
    return server;
  };
  if (!args.nmea_tcp.empty()) {
    auto server = tcp_server(args.nmea_tcp, "--nmea-tcp", "NMEA");
    if (!server) return report_error(server.error());
    sinks.push_back(std::make_unique<sim::StreamSink>(0, sim::make_nmea_encoder(), std::make_unique<TcpStream>(*server)));
  }
  if (!args.rtcm_tcp.empty()) {
    auto server = tcp_server(args.rtcm_tcp, "--rtcm-tcp", "RTCM 3");
    if (!server) return report_error(server.error());
    sinks.push_back(std::make_unique<sim::StreamSink>(
        0, sim::make_rtcm3_encoder(*live.resources().ephemerides, sim::rtcm_station(live.marker_ecef_m(), live.receiver())),
        std::make_unique<TcpStream>(*server)));
  }
  if (!args.pty.empty()) {
    auto opened = PseudoTerminal::open(args.pty);
    if (!opened) return report_error(opened.error());
    std::cout << "skytrace serve: NMEA on " << args.pty << " -> " << (*opened)->slave_name() << std::endl;
    sinks.push_back(std::make_unique<sim::StreamSink>(0, sim::make_nmea_encoder(), std::make_unique<PtyStream>(std::move(*opened))));
  }
  int pose_fd = -1;
  if (!args.pose_udp.empty()) {
    auto fd = bind_socket(args.pose_udp, SOCK_DGRAM, "--pose-udp");
    if (!fd) return report_error(fd.error());
    pose_fd = *fd;
    std::cout << "skytrace serve: poses on udp port " << bound_port(pose_fd) << std::endl;
  }
  struct CloseFd {
    int fd;
    ~CloseFd() {
      if (fd >= 0) close(fd);
    }
  } pose_guard{pose_fd};

  install_live_stop_handlers();
  std::signal(SIGPIPE, SIG_IGN);

  using Clock = std::chrono::steady_clock;
  const double period_s = 1.0 / args.rate_hz;
  const auto wall_start = Clock::now();
  const GnssTime start = scenario->time.start;
  const auto tag_at = [&](Clock::time_point t) { return start + std::chrono::duration<double>(t - wall_start).count(); };
  std::int64_t k = 0;
  std::int64_t late_epochs = 0;
  constexpr std::int64_t kReportedIgnoredPoses = 10;
  std::int64_t ignored_poses = 0;
  while (!cancellation_requested()) {
    if (args.duration_s > 0.0 && static_cast<double>(k) * period_s > args.duration_s + 1e-9) break;
    const auto deadline = wall_start + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(k * period_s));
    // Serve clients and poses until the epoch is due.
    for (;;) {
      std::vector<pollfd> fds;
      for (const auto& server : servers) server->add_poll_fds(fds);
      if (pose_fd >= 0) fds.push_back({pose_fd, POLLIN, 0});
      if (rtk_base && rtk_base->fd() >= 0) fds.push_back({rtk_base->fd(), POLLIN, 0});
      const auto now = Clock::now();
      if (now >= deadline || cancellation_requested()) break;
      const auto wait_ms = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - now).count() + 1;
      const int ready = poll(fds.data(), fds.size(), static_cast<int>(std::min<long long>(wait_ms, 100)));
      if (ready < 0 && errno != EINTR) return report_error(io_error("poll"));
      for (const auto& server : servers) server->service();
      if (rtk_base) rtk_base->service(live);
      if (pose_fd >= 0) {
        char buffer[2048];
        for (size_t datagrams = 0; datagrams < kMaxDatagramsPerWakeup; ++datagrams) {
          const ssize_t n = recv(pose_fd, buffer, sizeof buffer, MSG_DONTWAIT);
          if (n <= 0) break;
          auto pose = sim::parse_pose_datagram(std::string_view(buffer, static_cast<size_t>(n)));
          Status applied = Ok{};
          if (!pose) {
            applied = pose.error();
          } else if (pose->frame == sim::PoseDatagram::Frame::kWorld) {
            applied = live.set_antenna_pose_world(tag_at(Clock::now()), pose->position, pose->velocity);
          } else {
            applied = live.set_antenna_pose_ecef(tag_at(Clock::now()), pose->position, pose->velocity);
          }
          if (!applied && ++ignored_poses <= kReportedIgnoredPoses) {
            std::cerr << "skytrace serve: warning: pose ignored: " << applied.error().message.substr(0, 200) << "\n";
            if (ignored_poses == kReportedIgnoredPoses) std::cerr << "skytrace serve: further ignored poses are only counted\n";
          }
        }
      }
    }
    if (cancellation_requested()) break;

    const GnssTime tag = start + static_cast<double>(k) * period_s;
    auto epoch = live.step(tag);
    if (!epoch) return report_error(epoch.error());
    const sim::SinkEpoch sink_epoch{k, 0, &sink_receiver, &epoch->observations, epoch->fix ? &*epoch->fix : nullptr};
    for (auto& sink : sinks) {
      if (auto st = sink->add(sink_epoch); !st) return report_error(st.error());
    }
    if (rtk_base && epoch->fix) rtk_base->send_position(*epoch->fix);
    ++k;
    // Behind the wall clock by more than an epoch (a slow world, a suspended process): skip ahead
    // so that epochs keep their wall-clock times instead of bunching up.
    const auto behind = std::chrono::duration<double>(Clock::now() - wall_start).count() / period_s;
    if (behind > static_cast<double>(k) + 1.0) {
      late_epochs += static_cast<std::int64_t>(std::floor(behind)) - k;
      k = static_cast<std::int64_t>(std::floor(behind));
    }
  }
  disarm_stop_watchdog();  // stopped in time: no forced exit
  if (late_epochs > 0) std::cerr << "skytrace serve: " << late_epochs << " epochs skipped to keep real time\n";
  if (ignored_poses > 0) std::cerr << "skytrace serve: " << ignored_poses << " pose datagrams ignored\n";
  for (auto& sink : sinks) {
    if (auto st = sink->finish(); !st) return report_error(st.error());
  }
  for (const auto& server : servers) {
    if (server->refused_count() > 0) {
      std::cerr << "skytrace serve: " << server->refused_count() << " connections refused (more than "
                << kMaxTcpClients << " clients at once)\n";
    }
  }
  std::cout << "skytrace serve: stopped after " << k << " epochs" << std::endl;
  return kExitOk;
}

}  // namespace

void register_serve_command(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<ServeArgs>();
  CLI::App* cmd = app.add_subcommand(
      "serve", "Virtual receiver in real time: NMEA and RTCM 3 over TCP, NMEA over a pseudo-terminal (docs/streams.md)");
  cmd->add_option("scenario", args->scenario, "Scenario YAML file (see docs/scenario.md)")->required();
  cmd->add_option("--nmea-tcp", args->nmea_tcp, "Serve NMEA 0183 on HOST:PORT (port 0: any free port, printed)");
  cmd->add_option("--rtcm-tcp", args->rtcm_tcp, "Serve RTCM 3 (1006, MSM7, ephemerides) on HOST:PORT");
  cmd->add_option("--pty", args->pty, "Create a pseudo-terminal carrying NMEA, with a symbolic link at PATH");
  cmd->add_option("--pose-udp", args->pose_udp,
                  "Receive antenna poses as UDP text datagrams on HOST:PORT ('ecef X Y Z [VX VY VZ]', "
                  "'world X Y Z [VX VY VZ]', 'llh LAT LON H')");
  cmd->add_option("--receiver", args->receiver, "The receiver of a scenario with several, by name (default: the first)");
  cmd->add_option("--rtk-base-tcp", args->rtk_base_tcp,
                  "RTK: a base station's RTCM 3 stream on HOST:PORT (MSM and 1005/1006, e.g. another skytrace serve "
                  "--rtcm-tcp or str2str); the fixes become rtk_fixed / rtk_float (NMEA GGA quality 4/5)");
  cmd->add_option("--rtk-base-ntrip", args->rtk_base_ntrip,
                  "RTK: a base station's RTCM 3 stream from an NTRIP caster, ntrip://[USER[:PASSWORD]@]HOST[:PORT]/MOUNTPOINT "
                  "(port 2101 by default; the rover's GGA is sent every 10 s for VRS casters)");
  cmd->add_option("--rate-hz", args->rate_hz, "Epochs per second (default 1)");
  cmd->add_option("--duration-s", args->duration_s, "Stop after this many seconds (default: until SIGINT/SIGTERM)");
  cmd->add_option("--set", args->overrides, "Override a scenario key, KEY.PATH=YAML_VALUE (repeatable)");
  cmd->callback([args, &exit_code]() { exit_code = serve(*args); });
}

}  // namespace skytrace::cli
