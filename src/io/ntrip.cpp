#include "skytrace/io/ntrip.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>

namespace skytrace::io {
namespace {

constexpr size_t kMaxHeaderBytes = 16 * 1024;
constexpr size_t kMaxSourceTableBytes = 4 * 1024 * 1024;

bool starts_with_nocase(std::string_view text, std::string_view prefix) {
  return text.size() >= prefix.size() && std::equal(prefix.begin(), prefix.end(), text.begin(), [](char a, char b) {
           return std::tolower(static_cast<unsigned char>(a)) == std::tolower(static_cast<unsigned char>(b));
         });
}

std::string lower(std::string_view text) {
  std::string out(text);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

Result<std::string> percent_decode(std::string_view text, std::string_view what) {
  std::string out;
  for (size_t i = 0; i < text.size(); ++i) {
    if (text[i] != '%') {
      out.push_back(text[i]);
      continue;
    }
    if (i + 2 >= text.size() || !std::isxdigit(static_cast<unsigned char>(text[i + 1])) ||
        !std::isxdigit(static_cast<unsigned char>(text[i + 2]))) {
      return make_error(ErrorCode::kInvalidArgument, fmt::format("{}: '%' must be followed by two hexadecimal digits", what));
    }
    out.push_back(static_cast<char>(std::stoi(std::string(text.substr(i + 1, 2)), nullptr, 16)));
    i += 2;
  }
  return out;
}

}  // namespace

Result<NtripEndpoint> parse_ntrip_url(std::string_view url) {
  const auto bad = [&](std::string_view why) {
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("NTRIP source '{}': {} (expected ntrip://[USER[:PASSWORD]@]HOST[:PORT]/MOUNTPOINT)", url, why));
  };
  constexpr std::string_view kScheme = "ntrip://";
  if (!starts_with_nocase(url, kScheme)) return bad("not an ntrip:// address");
  std::string_view rest = url.substr(kScheme.size());
  const size_t slash = rest.find('/');
  if (slash == std::string_view::npos || slash + 1 >= rest.size()) return bad("no mountpoint");
  NtripEndpoint e;
  e.mountpoint = std::string(rest.substr(slash + 1));
  if (e.mountpoint.find_first_of(" \r\n/?#") != std::string::npos) return bad("the mountpoint has characters a caster does not allow");
  std::string_view authority = rest.substr(0, slash);
  const size_t at = authority.rfind('@');
  if (at != std::string_view::npos) {
    const std::string_view credentials = authority.substr(0, at);
    authority = authority.substr(at + 1);
    const size_t colon = credentials.find(':');
    auto user = percent_decode(credentials.substr(0, colon), "NTRIP user");
    if (!user) return bad(user.error().message);
    e.user = *user;
    if (colon != std::string_view::npos) {
      auto password = percent_decode(credentials.substr(colon + 1), "NTRIP password");
      if (!password) return bad(password.error().message);
      e.password = *password;
    }
  }
  if (!authority.empty() && authority.front() == '[') {  // [IPv6]:port
    const size_t close = authority.find(']');
    if (close == std::string_view::npos) return bad("an IPv6 address without ']'");
    e.host = std::string(authority.substr(1, close - 1));
    authority = authority.substr(close + 1);
    if (!authority.empty()) {
      if (authority.front() != ':') return bad("text after the IPv6 address");
      e.port = std::string(authority.substr(1));
    }
  } else {
    const size_t colon = authority.rfind(':');
    e.host = std::string(authority.substr(0, colon));
    if (colon != std::string_view::npos) e.port = std::string(authority.substr(colon + 1));
  }
  if (e.host.empty()) return bad("no host");
  const bool numeric = !e.port.empty() && std::all_of(e.port.begin(), e.port.end(), [](char c) { return c >= '0' && c <= '9'; });
  if (!numeric || e.port.size() > 5 || std::stoi(e.port) < 1 || std::stoi(e.port) > 65535) return bad("the port must be 1-65535");
  return e;
}

std::string ntrip_url_for_display(const NtripEndpoint& e) {
  const bool v6 = e.host.find(':') != std::string::npos;
  return fmt::format("ntrip://{}{}{}{}:{}/{}", e.user.empty() ? "" : e.user + "@", v6 ? "[" : "", e.host, v6 ? "]" : "", e.port,
                     e.mountpoint);
}

std::string base64_encode(std::string_view bytes) {
  static constexpr char kAlphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  for (size_t i = 0; i < bytes.size(); i += 3) {
    const size_t n = std::min<size_t>(3, bytes.size() - i);
    std::uint32_t v = 0;
    for (size_t k = 0; k < 3; ++k) v = (v << 8) | (k < n ? static_cast<std::uint8_t>(bytes[i + k]) : 0u);
    for (size_t k = 0; k < 4; ++k) out.push_back(k <= n ? kAlphabet[(v >> (18 - 6 * k)) & 0x3F] : '=');
  }
  return out;
}

std::string ntrip_request(const NtripEndpoint& e, std::string_view user_agent) {
  // NTRIP 1.0 asks that the agent start with "NTRIP" (casters check it).
  std::string request = fmt::format("GET /{} HTTP/1.0\r\nUser-Agent: NTRIP {}\r\nAccept: */*\r\n", e.mountpoint, user_agent);
  if (!e.user.empty()) request += "Authorization: Basic " + base64_encode(e.user + ":" + e.password) + "\r\n";
  request += "Connection: close\r\n\r\n";
  return request;
}

std::string NtripResponse::feed(std::string_view bytes) {
  if (state_ == State::kStreaming) return chunked_ ? take_chunked(bytes) : std::string(bytes);
  if (state_ == State::kRefused) {
    if (!source_table_ || table_complete_) return {};
    if (header_.size() + bytes.size() <= kMaxSourceTableBytes) header_.append(bytes);
  } else {
    header_.append(bytes);
    const size_t status_end = header_.find("\r\n");
    if (status_end == std::string::npos) {
      if (header_.size() > kMaxHeaderBytes) refuse("the caster's answer has no status line (not an NTRIP caster?)");
      return {};
    }
    const std::string status = header_.substr(0, status_end);
    if (starts_with_nocase(status, "ICY 200")) {
      // NTRIP 1.0: the stream follows the status line.
      state_ = State::kStreaming;
      std::string rest = header_.substr(status_end + 2);
      header_.clear();
      return rest;
    }
    if (starts_with_nocase(status, "SOURCETABLE 200")) {
      source_table_ = true;
      refuse("the caster has no such mountpoint (it sent its source table)");
      header_.erase(0, status_end + 2);
    } else if (starts_with_nocase(status, "HTTP/1.")) {
      const size_t header_end = header_.find("\r\n\r\n");
      if (header_end == std::string::npos) {
        if (header_.size() > kMaxHeaderBytes) refuse("the caster's answer header is longer than 16 KiB");
        return {};
      }
      const std::string code = status.size() >= 12 ? status.substr(9, 3) : std::string();
      const std::string headers = lower(std::string_view(header_).substr(status_end + 2, header_end - status_end - 2));
      std::string body = header_.substr(header_end + 4);
      header_.clear();
      if (code == "200" && headers.find("content-type: gnss/sourcetable") != std::string::npos) {
        source_table_ = true;
        refuse("the caster has no such mountpoint (it sent its source table)");
        header_ = std::move(body);
      } else if (code == "200") {
        state_ = State::kStreaming;
        chunked_ = headers.find("transfer-encoding: chunked") != std::string::npos;
        return chunked_ ? take_chunked(body) : body;
      } else if (code == "401") {
        refuse("the caster refused the user name or password (HTTP 401 Unauthorized)");
        return {};
      } else if (code == "404") {
        refuse("the caster has no such mountpoint (HTTP 404)");
        return {};
      } else {
        refuse(fmt::format("the caster answered '{}'", status));
        return {};
      }
    } else {
      refuse(fmt::format("the caster answered '{}' (expected ICY 200 OK or HTTP 200)", status.substr(0, 80)));
      return {};
    }
  }
  // A source table: "STR;MOUNTPOINT;..." lines until ENDSOURCETABLE.
  for (size_t end; (end = header_.find('\n')) != std::string::npos;) {
    std::string_view line(header_.data(), end);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    if (starts_with_nocase(line, "STR;")) {
      const std::string_view fields = line.substr(4);
      offered_.emplace_back(fields.substr(0, fields.find(';')));
    } else if (starts_with_nocase(line, "ENDSOURCETABLE")) {
      table_complete_ = true;
    }
    header_.erase(0, end + 1);
  }
  return {};
}

std::string NtripResponse::take_chunked(std::string_view bytes) {
  std::string out;
  size_t i = 0;
  while (i < bytes.size()) {
    if (chunk_left_ > 0) {
      const size_t n = std::min(chunk_left_, bytes.size() - i);
      out.append(bytes.substr(i, n));
      chunk_left_ -= n;
      i += n;
      continue;
    }
    if (chunk_crlf_left_ > 0) {  // the CRLF after a chunk's data
      --chunk_crlf_left_;
      ++i;
      continue;
    }
    const char c = bytes[i++];
    if (c != '\n') {
      if (chunk_line_.size() < 64) chunk_line_.push_back(c);
      continue;
    }
    // A size line: hexadecimal digits, maybe an extension after ';'.
    size_t size = 0;
    bool digits = false;
    for (const char h : chunk_line_) {
      if (!std::isxdigit(static_cast<unsigned char>(h))) break;
      digits = true;
      size = size * 16 + static_cast<size_t>(std::isdigit(static_cast<unsigned char>(h)) ? h - '0' : std::tolower(h) - 'a' + 10);
      if (size > (size_t{1} << 30)) break;
    }
    chunk_line_.clear();
    if (!digits) continue;  // an empty line (after the last chunk's trailer)
    chunk_left_ = size;
    chunk_crlf_left_ = size > 0 ? 2 : 0;
  }
  return out;
}

}  // namespace skytrace::io
