// The rover's side of NTRIP (Networked Transport of RTCM via Internet Protocol, RTCM 10410.1):
// the request for a caster's mountpoint and the reading of the caster's answer, independent of
// sockets so that it can be tested byte by byte. The request is NTRIP 1.0's (an HTTP/1.0 GET that
// every caster answers, RTKLIB's and BKG's included); the answer may be NTRIP 1.0's ("ICY 200 OK"
// and the stream) or 2.0's (HTTP/1.1, chunked transfer), a source table (the mountpoint is not
// there) or a refusal (401: user or password wrong).
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "skytrace/core/error.hpp"

namespace skytrace::io {

struct NtripEndpoint {
  std::string host;
  std::string port = "2101";  // the port IANA assigned to NTRIP
  std::string mountpoint;
  std::string user;
  std::string password;
};

// ntrip://[USER[:PASSWORD]@]HOST[:PORT]/MOUNTPOINT (user and password percent-decoded).
[[nodiscard]] Result<NtripEndpoint> parse_ntrip_url(std::string_view url);
// The URL again, without the password (for messages).
[[nodiscard]] std::string ntrip_url_for_display(const NtripEndpoint& endpoint);

[[nodiscard]] std::string base64_encode(std::string_view bytes);

// The request for the endpoint's mountpoint (Basic authorization when a user is given).
[[nodiscard]] std::string ntrip_request(const NtripEndpoint& endpoint, std::string_view user_agent);

// The caster's answer, fed as it arrives.
class NtripResponse {
 public:
  enum class State {
    kHeader,     // waiting for the status line and headers
    kStreaming,  // the mountpoint's data flow
    kRefused,    // the caster said no: error() says why
  };
  // Returns the stream bytes (RTCM) in `bytes`, without the answer's header or chunk framing.
  [[nodiscard]] std::string feed(std::string_view bytes);
  // The caster closed the connection: before any answer, that is a refusal too (some casters,
  // RTKLIB's among them, answer a wrong user name or password so).
  void connection_closed() {
    if (state_ == State::kHeader) refuse("the caster closed the connection without answering (a wrong user name or password?)");
  }
  [[nodiscard]] State state() const { return state_; }
  [[nodiscard]] const std::string& error() const { return error_; }
  // The mountpoints of a source table the caster sent instead of the stream.
  [[nodiscard]] const std::vector<std::string>& offered_mountpoints() const { return offered_; }
  // Refused with a source table whose end (ENDSOURCETABLE) has not come yet: the mountpoints it
  // offers are still arriving.
  [[nodiscard]] bool reading_source_table() const { return source_table_ && !table_complete_; }

 private:
  std::string take_chunked(std::string_view bytes);
  void refuse(std::string why) {
    state_ = State::kRefused;
    error_ = std::move(why);
  }
  State state_ = State::kHeader;
  std::string header_;  // bytes of the header read so far (and of a source table)
  bool source_table_ = false;
  bool table_complete_ = false;
  bool chunked_ = false;
  // Chunked transfer: the size line being read, and the bytes left of the current chunk (+ CRLF).
  std::string chunk_line_;
  size_t chunk_left_ = 0;
  size_t chunk_crlf_left_ = 0;
  std::string error_;
  std::vector<std::string> offered_;
};

}  // namespace skytrace::io
