// A live receiver's link to a base station for RTK: the base's RTCM 3 stream over plain TCP
// (skytrace serve --rtcm-tcp, RTKLIB's str2str) or from an NTRIP caster's mountpoint (io/ntrip,
// the rover's GGA sent every 10 s as VRS casters need), decoded into base epochs for a
// LiveSession. Used by skytrace serve and the ROS 1 and ROS 2 nodes. Non-blocking: service() reads
// what has arrived; it connects again while the base is away (every second; every 10 s after a
// caster said no, as casters limit logins).
#pragma once

#include <chrono>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>

#include "skytrace/core/error.hpp"
#include "skytrace/core/time.hpp"
#include "skytrace/io/ntrip.hpp"
#include "skytrace/io/rtcm3.hpp"
#include "skytrace/positioning/spp.hpp"

namespace skytrace::sim {

class LiveSession;

// A base's RTCM 3 bytes, in any pieces and framing, decoded into base epochs (with the station's
// position from 1005/1006) for a session: what RtkBaseLink reads from the network, or a ROS node
// from an rtcm_msgs topic.
class RtcmBaseDecoder {
 public:
  explicit RtcmBaseDecoder(GnssTime reference) : decoder_(reference) {}
  // Hands the complete epochs to the session. False while epochs wait for the station's position.
  bool feed(std::span<const std::uint8_t> bytes, LiveSession& session);

 private:
  io::Rtcm3Decoder decoder_;
  io::RtcmMeasurementConverter converter_;
};

class RtkBaseLink {
 public:
  enum class Note { kInfo, kWarning, kError };
  // What the link has to say (connected, refused, closed); each kind of trouble is said once.
  using Notify = std::function<void(Note, const std::string&)>;

  // `source`: HOST:PORT, or ntrip://[USER[:PASSWORD]@]HOST[:PORT]/MOUNTPOINT. `reference`: an
  // instant near the data (RTCM times of week). Errors name the source (never the password).
  [[nodiscard]] static Result<std::unique_ptr<RtkBaseLink>> create(const std::string& source, GnssTime reference,
                                                                   Notify notify);
  ~RtkBaseLink();
  RtkBaseLink(const RtkBaseLink&) = delete;
  RtkBaseLink& operator=(const RtkBaseLink&) = delete;

  // The socket to poll for input, -1 while not connected.
  [[nodiscard]] int fd() const { return fd_; }
  // Connects when due; reads what is there; hands complete base epochs with the base's position
  // (RTCM 1005/1006) to the session.
  void service(LiveSession& session);
  // NTRIP: the rover's position for the caster (its GGA), at most every 10 s.
  void send_position(const positioning::PositionFix& fix);

 private:
  RtkBaseLink(GnssTime reference, Notify notify) : decoder_(reference), notify_(std::move(notify)) {}
  void refused();
  void connect_now();
  void disconnect();

  std::string host_, port_, display_;
  std::optional<io::NtripEndpoint> ntrip_;
  io::NtripResponse response_;
  RtcmBaseDecoder decoder_;
  Notify notify_;
  int fd_ = -1;
  bool streaming_announced_ = false;
  bool warned_connect_ = false, warned_position_ = false;
  std::string last_refusal_;
  std::chrono::steady_clock::time_point next_attempt_{}, next_gga_{};
};

}  // namespace skytrace::sim
