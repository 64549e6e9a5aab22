#include "skytrace/sim/rtk_base_link.hpp"

#include <fmt/format.h>
#include <netdb.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <span>

#include "skytrace/core/version.hpp"
#include "skytrace/io/nmea.hpp"
#include "skytrace/sim/live.hpp"

namespace skytrace::sim {

bool RtcmBaseDecoder::feed(std::span<const std::uint8_t> bytes, LiveSession& session) {
  decoder_.feed(bytes);
  bool positioned = true;
  for (const auto& epoch : decoder_.take_epochs()) {
    if (!decoder_.station()) {
      positioned = false;
      continue;
    }
    session.add_base_epoch(positioning::BaseEpoch{converter_.convert(epoch), decoder_.station()->arp_ecef_m});
  }
  return positioned;
}

Result<std::unique_ptr<RtkBaseLink>> RtkBaseLink::create(const std::string& source, GnssTime reference, Notify notify) {
  std::unique_ptr<RtkBaseLink> link(new RtkBaseLink(reference, std::move(notify)));
  if (source.rfind("ntrip://", 0) == 0) {
    auto endpoint = io::parse_ntrip_url(source);
    if (!endpoint) return endpoint.error();
    link->ntrip_ = *endpoint;
    link->host_ = endpoint->host;
    link->port_ = endpoint->port;
    link->display_ = io::ntrip_url_for_display(*endpoint);
  } else {
    const size_t colon = source.rfind(':');
    if (colon == std::string::npos || colon == 0 || colon + 1 == source.size()) {
      return make_error(ErrorCode::kInvalidArgument,
                        "RTK base '" + source + "': expected HOST:PORT or ntrip://[USER[:PASSWORD]@]HOST[:PORT]/MOUNTPOINT");
    }
    link->host_ = source.substr(0, colon);
    link->port_ = source.substr(colon + 1);
    link->display_ = source;
  }
  return link;
}

RtkBaseLink::~RtkBaseLink() { disconnect(); }

void RtkBaseLink::disconnect() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

void RtkBaseLink::service(LiveSession& session) {
  using Clock = std::chrono::steady_clock;
  if (fd_ < 0) {
    if (Clock::now() < next_attempt_) return;
    next_attempt_ = Clock::now() + std::chrono::seconds(1);
    connect_now();
    return;
  }
  std::uint8_t buffer[8192];
  for (int reads = 0; reads < 64; ++reads) {
    const ssize_t n = recv(fd_, buffer, sizeof buffer, MSG_DONTWAIT);
    if (n > 0) {
      std::string_view bytes(reinterpret_cast<const char*>(buffer), static_cast<size_t>(n));
      std::string stream;
      if (ntrip_) {
        stream = response_.feed(bytes);
        bytes = stream;
        if (response_.state() == io::NtripResponse::State::kStreaming && !streaming_announced_) {
          streaming_announced_ = true;
          notify_(Note::kInfo, "RTK corrections from " + display_);
        }
      }
      const bool positioned =
          decoder_.feed(std::span<const std::uint8_t>(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()), session);
      if (!positioned && !warned_position_) notify_(Note::kWarning, "RTK base " + display_ + ": no 1005/1006 yet, epochs wait");
      warned_position_ = warned_position_ || !positioned;
      continue;
    }
    if (n == 0 || (errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR)) {
      if (ntrip_) response_.connection_closed();
      if (ntrip_ && response_.state() == io::NtripResponse::State::kRefused) {
        refused();
      } else {
        notify_(Note::kWarning, "RTK base " + display_ + " closed the connection");
      }
      disconnect();
    }
    break;
  }
  // A refusal ends the connection now, once a source table that came with it is complete (or the
  // caster closes the connection, above).
  if (fd_ >= 0 && ntrip_ && response_.state() == io::NtripResponse::State::kRefused && !response_.reading_source_table()) {
    refused();
    disconnect();
  }
}

void RtkBaseLink::send_position(const positioning::PositionFix& fix) {
  using Clock = std::chrono::steady_clock;
  if (!ntrip_ || fd_ < 0 || fix.type == positioning::FixType::kNone ||
      response_.state() != io::NtripResponse::State::kStreaming || Clock::now() < next_gga_) {
    return;
  }
  for (const auto& sentence : io::nmea_epoch(fix)) {
    if (sentence.find("GGA,") == std::string::npos) continue;
    next_gga_ = Clock::now() + std::chrono::seconds(10);
    (void)send(fd_, sentence.data(), sentence.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
  }
}

void RtkBaseLink::refused() {
  std::string why = response_.error();
  const auto& offered = response_.offered_mountpoints();
  if (!offered.empty()) {
    why += "; it offers ";
    for (size_t i = 0; i < offered.size() && i < 20; ++i) why += (i > 0 ? ", " : "") + offered[i];
    if (offered.size() > 20) why += fmt::format(" and {} more", offered.size() - 20);
  }
  if (why != last_refusal_) notify_(Note::kError, "RTK base " + display_ + ": " + why + " (trying again every 10 s)");
  last_refusal_ = why;
  next_attempt_ = std::chrono::steady_clock::now() + std::chrono::seconds(10);
}

void RtkBaseLink::connect_now() {
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  addrinfo* found = nullptr;
  if (const int rc = getaddrinfo(host_.c_str(), port_.c_str(), &hints, &found); rc != 0) {
    if (!warned_connect_) notify_(Note::kWarning, "RTK base " + display_ + ": " + gai_strerror(rc) + " (trying again every second)");
    warned_connect_ = true;
    return;
  }
  std::unique_ptr<addrinfo, decltype(&freeaddrinfo)> guard(found, freeaddrinfo);
  const int fd = socket(found->ai_family, found->ai_socktype | SOCK_CLOEXEC, found->ai_protocol);
  if (fd < 0) return;
  if (connect(fd, found->ai_addr, found->ai_addrlen) != 0) {
    const int error = errno;
    ::close(fd);
    if (!warned_connect_) {
      notify_(Note::kWarning, "RTK base " + display_ + ": " + std::strerror(error) + " (trying again every second)");
    }
    warned_connect_ = true;
    return;
  }
  fd_ = fd;
  if (!ntrip_) {
    notify_(Note::kInfo, "RTK corrections from " + display_);
    return;
  }
  response_ = io::NtripResponse{};
  streaming_announced_ = false;
  next_gga_ = {};
  const std::string request = io::ntrip_request(*ntrip_, std::string("skytrace/") + version());
  if (send(fd_, request.data(), request.size(), MSG_NOSIGNAL) != static_cast<ssize_t>(request.size())) {
    notify_(Note::kWarning, "RTK base " + display_ + ": cannot send the request (" + std::strerror(errno) + ")");
    disconnect();
  }
}

}  // namespace skytrace::sim
