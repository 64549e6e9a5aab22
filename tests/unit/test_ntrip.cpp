// NTRIP client side (io/ntrip): addresses, the request, and every kind of caster answer fed in
// pieces as a socket delivers them.
#include <gtest/gtest.h>

#include <string>

#include "skytrace/io/ntrip.hpp"

namespace skytrace::io {
namespace {

// Feeds `answer` in pieces of `piece` bytes; returns the stream bytes.
std::string feed_in_pieces(NtripResponse& response, const std::string& answer, size_t piece) {
  std::string out;
  for (size_t i = 0; i < answer.size(); i += piece) out += response.feed(std::string_view(answer).substr(i, piece));
  return out;
}

TEST(NtripUrl, ParsesUserPasswordHostPortAndMountpoint) {
  auto e = parse_ntrip_url("ntrip://rover:s%40cret@caster.example.org:2102/MOUNT1");
  ASSERT_TRUE(e.ok()) << e.error().message;
  EXPECT_EQ(e->user, "rover");
  EXPECT_EQ(e->password, "s@cret");
  EXPECT_EQ(e->host, "caster.example.org");
  EXPECT_EQ(e->port, "2102");
  EXPECT_EQ(e->mountpoint, "MOUNT1");
  EXPECT_EQ(ntrip_url_for_display(*e), "ntrip://rover@caster.example.org:2102/MOUNT1");  // no password

  auto plain = parse_ntrip_url("ntrip://[::1]/RTCM3");
  ASSERT_TRUE(plain.ok()) << plain.error().message;
  EXPECT_EQ(plain->host, "::1");
  EXPECT_EQ(plain->port, "2101");
  EXPECT_TRUE(plain->user.empty());
}

TEST(NtripUrl, RefusesWhatIsNotAnAddress) {
  for (const char* bad : {"tcp://host:2101/M", "ntrip://host:2101", "ntrip://host:2101/", "ntrip://:2101/M",
                          "ntrip://host:99999/M", "ntrip://host:port/M", "ntrip://u:%zz@host/M", "ntrip://host/M?x"}) {
    auto e = parse_ntrip_url(bad);
    ASSERT_FALSE(e.ok()) << bad;
    EXPECT_NE(e.error().message.find("ntrip://[USER[:PASSWORD]@]HOST[:PORT]/MOUNTPOINT"), std::string::npos) << e.error().message;
  }
}

TEST(NtripRequest, AsksForTheMountpointWithBasicAuthorization) {
  EXPECT_EQ(base64_encode(""), "");
  EXPECT_EQ(base64_encode("f"), "Zg==");
  EXPECT_EQ(base64_encode("fo"), "Zm8=");
  EXPECT_EQ(base64_encode("foo"), "Zm9v");
  EXPECT_EQ(base64_encode("Aladdin:open sesame"), "QWxhZGRpbjpvcGVuIHNlc2FtZQ==");  // RFC 7617's example
  auto e = parse_ntrip_url("ntrip://Aladdin:open%20sesame@host/M1");
  ASSERT_TRUE(e.ok());
  const std::string request = ntrip_request(*e, "skytrace/0.1.0");
  EXPECT_EQ(request.rfind("GET /M1 HTTP/1.0\r\n", 0), 0u) << request;
  EXPECT_NE(request.find("User-Agent: NTRIP skytrace/0.1.0\r\n"), std::string::npos);
  EXPECT_NE(request.find("Authorization: Basic QWxhZGRpbjpvcGVuIHNlc2FtZQ==\r\n"), std::string::npos);
  EXPECT_TRUE(request.ends_with("\r\n\r\n"));
  auto anonymous = parse_ntrip_url("ntrip://host/M1");
  EXPECT_EQ(ntrip_request(*anonymous, "x").find("Authorization"), std::string::npos);
}

TEST(NtripResponse, Version1StreamFollowsTheStatusLine) {
  const std::string rtcm("\xD3\x00\x13\x3E\xD0\x00\x03", 7);
  for (const size_t piece : {1, 3, 1000}) {
    NtripResponse r;
    EXPECT_EQ(feed_in_pieces(r, "ICY 200 OK\r\n" + rtcm, piece), rtcm) << piece;
    EXPECT_EQ(r.state(), NtripResponse::State::kStreaming);
    EXPECT_EQ(r.feed("more"), "more");
  }
}

TEST(NtripResponse, Version2ChunkedStreamIsUnframed) {
  const std::string answer =
      "HTTP/1.1 200 OK\r\nNtrip-Version: Ntrip/2.0\r\nContent-Type: gnss/data\r\nTransfer-Encoding: chunked\r\n\r\n"
      "5\r\nhello\r\n1A;ext=1\r\nabcdefghijklmnopqrstuvwxyz\r\n0\r\n\r\n";
  for (const size_t piece : {1, 2, 7, 4096}) {
    NtripResponse r;
    EXPECT_EQ(feed_in_pieces(r, answer, piece), "helloabcdefghijklmnopqrstuvwxyz") << piece;
    EXPECT_EQ(r.state(), NtripResponse::State::kStreaming);
  }
  NtripResponse plain;
  EXPECT_EQ(plain.feed("HTTP/1.1 200 OK\r\nContent-Type: gnss/data\r\n\r\nRTCM"), "RTCM");
}

TEST(NtripResponse, SourceTableMeansNoSuchMountpointAndListsWhatIsOffered) {
  const std::string table =
      "SOURCETABLE 200 OK\r\nServer: NTRIP caster\r\nContent-Type: text/plain\r\n\r\n"
      "STR;BASE1;Esbjerg;RTCM 3.3;1006(10),1077(1);2;GPS+GLO;SNIP;DNK;55.49;8.49;0;0;sNTRIP;none;B;N;0;\r\n"
      "CAS;caster.example.org;2101;x;y;0;DNK;55;8;0.0.0.0;0;http://x\r\n"
      "STR;BASE2;Esbjerg;RTCM 3.3;1006(10);2;GPS;SNIP;DNK;55.49;8.49;0;0;sNTRIP;none;B;N;0;\r\nENDSOURCETABLE\r\n";
  for (const size_t piece : {1, 13, 4096}) {
    NtripResponse r;
    // The status line alone: refused, and the offered mountpoints still to come.
    (void)r.feed(table.substr(0, 20));
    EXPECT_EQ(r.state(), NtripResponse::State::kRefused);
    EXPECT_TRUE(r.reading_source_table());
    EXPECT_EQ(feed_in_pieces(r, table.substr(20), piece), "");
    EXPECT_FALSE(r.reading_source_table());
    EXPECT_EQ(r.state(), NtripResponse::State::kRefused);
    EXPECT_NE(r.error().find("no such mountpoint"), std::string::npos) << r.error();
    EXPECT_EQ(r.offered_mountpoints(), (std::vector<std::string>{"BASE1", "BASE2"})) << piece;
  }
  NtripResponse v2;
  (void)v2.feed("HTTP/1.1 200 OK\r\nContent-Type: gnss/sourcetable\r\n\r\nSTR;ONLY;x\r\n");
  EXPECT_EQ(v2.state(), NtripResponse::State::kRefused);
  EXPECT_EQ(v2.offered_mountpoints(), std::vector<std::string>{"ONLY"});
}

TEST(NtripResponse, RefusalsSayWhy) {
  NtripResponse unauthorized;
  EXPECT_EQ(unauthorized.feed("HTTP/1.0 401 Unauthorized\r\nWWW-Authenticate: Basic realm=\"/M\"\r\n\r\n"), "");
  EXPECT_EQ(unauthorized.state(), NtripResponse::State::kRefused);
  EXPECT_NE(unauthorized.error().find("user name or password"), std::string::npos);
  NtripResponse missing;
  (void)missing.feed("HTTP/1.1 404 Not Found\r\n\r\n");
  EXPECT_NE(missing.error().find("no such mountpoint"), std::string::npos);
  NtripResponse web;
  (void)web.feed("SSH-2.0-OpenSSH_9.2\r\n");
  EXPECT_EQ(web.state(), NtripResponse::State::kRefused);
  EXPECT_NE(web.error().find("SSH-2.0"), std::string::npos);
  NtripResponse silent;
  silent.connection_closed();
  EXPECT_EQ(silent.state(), NtripResponse::State::kRefused);
  EXPECT_NE(silent.error().find("without answering"), std::string::npos);
  NtripResponse streaming;
  (void)streaming.feed("ICY 200 OK\r\n");
  streaming.connection_closed();  // a stream that ends is not a refusal
  EXPECT_EQ(streaming.state(), NtripResponse::State::kStreaming);
  NtripResponse endless;
  (void)endless.feed(std::string(20000, 'x'));
  EXPECT_EQ(endless.state(), NtripResponse::State::kRefused);
  EXPECT_NE(endless.error().find("no status line"), std::string::npos);
}

}  // namespace
}  // namespace skytrace::io
