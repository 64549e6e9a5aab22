// `skytrace fetch` end to end: the real executable against a local HTTP server (python3 -m
// http.server) serving a temporary folder laid out like the IGS archive, whose files are
// compressed copies of the real recordings in the shared data.
#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>
#include <zlib.h>

#include <array>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <unordered_map>
#include <vector>

#include "skytrace/orbits/fetch.hpp"
#include "test_support.hpp"

extern char** environ;

namespace skytrace {
namespace {

namespace fs = std::filesystem;

std::string read_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

void write_bytes(const fs::path& path, std::string_view bytes) {
  fs::create_directories(path.parent_path());
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

std::string gzip_bytes(std::string_view input) {
  z_stream stream{};
  EXPECT_EQ(deflateInit2(&stream, 1, Z_DEFLATED, 16 + MAX_WBITS, 8, Z_DEFAULT_STRATEGY), Z_OK);
  std::string out(deflateBound(&stream, static_cast<uLong>(input.size())) + 32, '\0');
  stream.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(input.data()));
  stream.avail_in = static_cast<uInt>(input.size());
  stream.next_out = reinterpret_cast<Bytef*>(out.data());
  stream.avail_out = static_cast<uInt>(out.size());
  EXPECT_EQ(deflate(&stream, Z_FINISH), Z_STREAM_END);
  out.resize(stream.total_out);
  deflateEnd(&stream);
  return out;
}

// Unix compress (.Z) writer in compress 4.x's layout (the unit tests check it against gzip -d).
std::string compress_lzw(std::string_view input) {
  constexpr int kMaxBits = 16;
  constexpr std::uint32_t kTableSize = std::uint32_t{1} << kMaxBits;
  std::string out{'\x1f', '\x9d', static_cast<char>(kMaxBits | 0x80)};
  if (input.empty()) return out;
  std::unordered_map<std::uint32_t, std::uint32_t> table;
  int width = 9;
  std::uint32_t max_code = 511;
  std::uint32_t next_free = 257;
  bool clear_pending = false;
  std::vector<unsigned char> group(16, 0);
  int offset_bits = 0;
  const auto flush = [&](size_t count) {
    out.append(group.begin(), group.begin() + static_cast<std::ptrdiff_t>(count));
    std::fill(group.begin(), group.end(), 0);
    offset_bits = 0;
  };
  const auto output = [&](std::uint32_t code) {
    for (int b = 0; b < width; ++b) {
      if ((code >> b) & 1U) group[static_cast<size_t>((offset_bits + b) / 8)] |= static_cast<unsigned char>(1U << ((offset_bits + b) % 8));
    }
    offset_bits += width;
    if (offset_bits == width * 8) flush(static_cast<size_t>(width));
    if (next_free > max_code || clear_pending) {
      if (offset_bits > 0) flush(static_cast<size_t>(width));
      if (clear_pending) {
        width = 9;
        max_code = 511;
        clear_pending = false;
      } else {
        ++width;
        max_code = width == kMaxBits ? kTableSize : (std::uint32_t{1} << width) - 1;
      }
    }
  };
  std::uint32_t current = static_cast<unsigned char>(input[0]);
  for (size_t i = 1; i < input.size(); ++i) {
    const auto c = static_cast<unsigned char>(input[i]);
    const std::uint32_t key = (current << 8) | c;
    if (const auto it = table.find(key); it != table.end()) {
      current = it->second;
      continue;
    }
    output(current);
    if (next_free < kTableSize) {
      table[key] = next_free++;
    } else {
      table.clear();
      next_free = 257;
      clear_pending = true;
      output(256);
    }
    current = c;
  }
  output(current);
  flush(static_cast<size_t>((offset_bits + 7) / 8));
  return out;
}

std::string quote(const std::string& text) {
  std::string out = "'";
  for (const char c : text) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

// A port nobody listens on right now (bound to port 0 by the kernel, then released).
int free_port() {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  address.sin_port = 0;
  ::bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof(address));
  socklen_t size = sizeof(address);
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&address), &size);
  ::close(fd);
  return ntohs(address.sin_port);
}

bool have_python3() { return std::system("python3 --version >/dev/null 2>&1") == 0; }

// The body of an HTTP/1.0 GET of `path` on 127.0.0.1:port, or "" when nothing answers.
std::string http_get(int port, const std::string& path) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  address.sin_port = htons(static_cast<std::uint16_t>(port));
  std::string response;
  if (::connect(fd, reinterpret_cast<sockaddr*>(&address), sizeof(address)) == 0) {
    const std::string request = "GET " + path + " HTTP/1.0\r\n\r\n";
    if (::send(fd, request.data(), request.size(), 0) == static_cast<ssize_t>(request.size())) {
      char buffer[4096];
      for (ssize_t n; (n = ::recv(fd, buffer, sizeof(buffer), 0)) > 0;) response.append(buffer, static_cast<size_t>(n));
    }
  }
  ::close(fd);
  const auto body = response.find("\r\n\r\n");
  return body == std::string::npos ? "" : response.substr(body + 4);
}

// python3 -m http.server on 127.0.0.1, stopped (SIGTERM to its pid) by stop() or the destructor.
// Tests run as parallel processes: a port found free may be taken before the server binds it, and
// another test's server may answer on it. The server is ready when it serves this instance's own
// token file; a server that could not bind is started again on another port.
class LocalHttpServer {
 public:
  explicit LocalHttpServer(const fs::path& root) : root_(root) {
    token_ = std::to_string(::getpid()) + "-" + std::to_string(reinterpret_cast<std::uintptr_t>(this)) + "-" +
             std::to_string(std::chrono::steady_clock::now().time_since_epoch().count());
    std::ofstream(root_ / kTokenFile) << token_;
    start();
  }
  ~LocalHttpServer() { stop(); }
  LocalHttpServer(const LocalHttpServer&) = delete;
  LocalHttpServer& operator=(const LocalHttpServer&) = delete;

  // Waits until the server serves this instance's files (at most 20 s per attempt, 5 attempts).
  [[nodiscard]] bool wait_ready() {
    for (int attempt = 0; attempt < 5; ++attempt) {
      if (pid_ <= 0) return false;
      for (int i = 0; i < 200; ++i) {
        if (http_get(port_, std::string("/") + kTokenFile) == token_) return true;
        int status = 0;
        if (::waitpid(pid_, &status, WNOHANG) == pid_) break;  // exited: the port was taken
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
      }
      stop();
      start();
    }
    return false;
  }
  void stop() {
    if (pid_ > 0) {
      ::kill(pid_, SIGTERM);
      int status = 0;
      ::waitpid(pid_, &status, 0);
      pid_ = -1;
    }
  }
  [[nodiscard]] int port() const { return port_; }
  [[nodiscard]] std::string base_url() const { return "http://127.0.0.1:" + std::to_string(port_) + "/"; }

 private:
  static constexpr const char* kTokenFile = ".local-http-server-token";

  void start() {
    port_ = free_port();
    const std::string port_text = std::to_string(port_);
    const std::string root_text = root_.string();
    std::vector<std::string> args{"python3", "-m", "http.server", "--bind", "127.0.0.1", port_text,
                                  "--directory", root_text};
    std::vector<char*> argv;
    for (auto& arg : args) argv.push_back(arg.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    // The server logs every request on stderr; keep the test output readable.
    posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
    posix_spawn_file_actions_addopen(&actions, 2, "/dev/null", O_WRONLY, 0);
    if (posix_spawnp(&pid_, "python3", &actions, nullptr, argv.data(), environ) != 0) pid_ = -1;
    posix_spawn_file_actions_destroy(&actions);
  }

  fs::path root_;
  std::string token_;
  int port_ = 0;
  pid_t pid_ = -1;
};

struct RunResult {
  int exit_code = -1;
  std::string out;
  std::string err;
};

// Runs build/bin/skytrace with the arguments; `env` is prefixed to the command (VAR=value ...).
RunResult run_skytrace(const std::vector<std::string>& args, const fs::path& scratch, const std::string& env = "") {
  const fs::path binary = test::binary_dir() / "bin" / "skytrace";
  const fs::path err_path = scratch / "stderr.txt";
  std::string command = env + (env.empty() ? "" : " ") + quote(binary.string());
  for (const auto& arg : args) command += " " + quote(arg);
  command += " 2>" + quote(err_path.string());
  RunResult result;
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) return result;
  std::array<char, 4096> buffer{};
  size_t n = 0;
  while ((n = fread(buffer.data(), 1, buffer.size(), pipe)) > 0) result.out.append(buffer.data(), n);
  const int status = pclose(pipe);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  result.err = read_bytes(err_path);
  return result;
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

// The local path at the end of a "product status path" line.
fs::path path_of(const std::string& line) {
  const size_t first = line.find(' ');
  const size_t second = line.find(' ', first + 1);
  return fs::path(line.substr(second + 1));
}

std::vector<fs::path> regular_files_under(const fs::path& dir) {
  std::vector<fs::path> files;
  if (!fs::exists(dir)) return files;
  for (const auto& entry : fs::recursive_directory_iterator(dir)) {
    if (entry.is_regular_file()) files.push_back(entry.path());
  }
  return files;
}

class FetchCli : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!have_python3()) GTEST_SKIP() << "python3 not installed (needed for the local HTTP server)";
    ASSERT_TRUE(fs::exists(test::binary_dir() / "bin" / "skytrace")) << "build the skytrace target first";
  }
};

TEST_F(FetchCli, DownloadsDecompressesCachesAndWorksOffline) {
  const auto nav = SKYTRACE_SHARED_FILE("real/esbc_2020177/ESBC00DNK_R_20201770000_01D_MN.rnx");
  const auto sp3 = SKYTRACE_SHARED_FILE("real/esbc_2020177/GRG0MGXFIN_20201770000_01D_15M_ORB.SP3");
  const auto clk = SKYTRACE_SHARED_FILE("real/esbc_2020177/GRG0MGXFIN_20201770000_01D_30S_CLK.CLK");
  const auto ionex_stand_in = SKYTRACE_SHARED_FILE("real/esbc_2020177/MOJN00DNK_R_20201770000_01D_MN.rnx");

  const fs::path root = test::make_temp_dir("fetch_archive_2020");
  const fs::path cache = test::make_temp_dir("fetch_cache_2020");
  const fs::path scratch = test::make_temp_dir("fetch_scratch_2020");
  write_bytes(root / "BRDC/2020/177/BRDC00WRD_S_20201770000_01D_MN.rnx.gz", gzip_bytes(read_bytes(nav)));
  write_bytes(root / "products/mgex/2111/GRG0MGXFIN_20201770000_01D_15M_ORB.SP3.gz", gzip_bytes(read_bytes(sp3)));
  write_bytes(root / "products/mgex/2111/GRG0MGXFIN_20201770000_01D_30S_CLK.CLK.gz", gzip_bytes(read_bytes(clk)));
  // No IONEX for that day in the shared data: any real text file exercises the .Z path.
  write_bytes(root / "products/ionex/2020/177/igsg1770.20i.Z", compress_lzw(read_bytes(ionex_stand_in)));

  LocalHttpServer server(root);
  ASSERT_TRUE(server.wait_ready()) << "python3 http.server did not start";
  const std::vector<std::string> args{"fetch", "--date", "2020-06-25", "--products", "brdc,sp3,clk,ionex",
                                      "--cache", cache.string(), "--base-url", server.base_url(), "--retries", "0"};
  const RunResult first = run_skytrace(args, scratch);
  ASSERT_EQ(first.exit_code, 0) << first.out << first.err;
  const auto lines = lines_of(first.out);
  ASSERT_EQ(lines.size(), 4u) << first.out;
  const std::vector<std::pair<std::string, fs::path>> expected{
      {"brdc", nav}, {"sp3", sp3}, {"clk", clk}, {"ionex", ionex_stand_in}};
  for (size_t i = 0; i < lines.size(); ++i) {
    EXPECT_EQ(lines[i].rfind(expected[i].first + " downloaded ", 0), 0u) << lines[i];
    const fs::path local = path_of(lines[i]);
    EXPECT_EQ(local.string().rfind(cache.string() + "/", 0), 0u) << lines[i];
    ASSERT_TRUE(fs::exists(local)) << local;
    EXPECT_TRUE(read_bytes(local) == read_bytes(expected[i].second)) << local << " differs from " << expected[i].second;
  }
  EXPECT_EQ(path_of(lines[0]), cache / "BRDC/2020/177/BRDC00WRD_S_20201770000_01D_MN.rnx");
  EXPECT_EQ(path_of(lines[3]), cache / "products/ionex/2020/177/igsg1770.20i");
  EXPECT_NE(first.err.find("downloading " + server.base_url() + "BRDC/2020/177/"), std::string::npos) << first.err;
  EXPECT_EQ(regular_files_under(cache).size(), 4u);  // no temporary files left behind

  // Offline: everything comes from the cache.
  server.stop();
  const RunResult second = run_skytrace(args, scratch);
  ASSERT_EQ(second.exit_code, 0) << second.out << second.err;
  const auto cached_lines = lines_of(second.out);
  ASSERT_EQ(cached_lines.size(), 4u);
  for (size_t i = 0; i < cached_lines.size(); ++i) {
    EXPECT_EQ(cached_lines[i].rfind(expected[i].first + " cached ", 0), 0u) << cached_lines[i];
    EXPECT_EQ(path_of(cached_lines[i]), path_of(lines[i]));
  }
  EXPECT_EQ(second.err.find("downloading"), std::string::npos) << second.err;

  // The library says the same, with the URL each file came from.
  orbits::FetchRequest request;
  request.day = *orbits::parse_archive_day("2020-06-25");
  request.products = {orbits::ProductKind::kOrbit};
  request.cache_dir = cache;
  request.base_url = server.base_url();
  const auto from_library = orbits::fetch_products(request);
  ASSERT_TRUE(from_library.ok()) << from_library.error().message;
  ASSERT_EQ(from_library->size(), 1u);
  EXPECT_TRUE(from_library->front().from_cache);
  EXPECT_EQ(from_library->front().url, server.base_url() + "products/mgex/2111/GRG0MGXFIN_20201770000_01D_15M_ORB.SP3.gz");

  // --force with the server gone: exit 6, the URL named, the cached copy untouched.
  std::vector<std::string> forced = args;
  forced.push_back("--force");
  const RunResult third = run_skytrace(forced, scratch);
  EXPECT_EQ(third.exit_code, 6) << third.out << third.err;
  EXPECT_NE(third.err.find(server.base_url() + "BRDC/2020/177/BRDC00WRD_S_20201770000_01D_MN.rnx.gz"),
            std::string::npos)
      << third.err;
  EXPECT_NE(third.err.find("remaining products not attempted"), std::string::npos) << third.err;
  EXPECT_TRUE(third.out.empty()) << third.out;
  EXPECT_TRUE(read_bytes(path_of(lines[0])) == read_bytes(nav));
  EXPECT_EQ(regular_files_under(cache).size(), 4u);
}

TEST_F(FetchCli, MissingProductGivesExit6WithUrlAndLeavesNoFile) {
  const auto nav = SKYTRACE_SHARED_FILE("real/esbc_2020177/ESBC00DNK_R_20201770000_01D_MN.rnx");
  const fs::path root = test::make_temp_dir("fetch_archive_404");
  const fs::path cache = test::make_temp_dir("fetch_cache_404");
  const fs::path scratch = test::make_temp_dir("fetch_scratch_404");
  write_bytes(root / "BRDC/2020/177/BRDC00WRD_S_20201770000_01D_MN.rnx.gz", gzip_bytes(read_bytes(nav)));
  // An error page served under a .gz name must not be stored as the product.
  write_bytes(root / "products/mgex/2111/GRG0MGXFIN_20201770000_01D_30S_CLK.CLK.gz",
              "<!DOCTYPE html><html><body>Please log in</body></html>\n");

  LocalHttpServer server(root);
  ASSERT_TRUE(server.wait_ready());
  const RunResult missing = run_skytrace({"fetch", "--date", "2020-06-25", "--products", "sp3", "--cache",
                                          cache.string(), "--base-url", server.base_url(), "--analysis-center",
                                          "COD", "--retries", "0"},
                                         scratch);
  EXPECT_EQ(missing.exit_code, 6) << missing.out << missing.err;
  EXPECT_NE(missing.err.find(server.base_url() + "products/mgex/2111/COD0MGXFIN_20201770000_01D_05M_ORB.SP3.gz"),
            std::string::npos)
      << missing.err;
  EXPECT_NE(missing.err.find("HTTP 404"), std::string::npos) << missing.err;
  EXPECT_TRUE(missing.out.empty()) << missing.out;
  EXPECT_TRUE(regular_files_under(cache).empty());

  // The library tells a missing file (kNotFound) from a failing server (kNetwork).
  orbits::FetchRequest request;
  request.day = *orbits::parse_archive_day("2020-06-25");
  request.products = {orbits::ProductKind::kIonex};
  request.cache_dir = cache;
  request.base_url = server.base_url();
  request.retries = 0;
  const auto not_found = orbits::fetch_products(request);
  ASSERT_FALSE(not_found.ok());
  EXPECT_EQ(not_found.error().code, ErrorCode::kNotFound);
  EXPECT_NE(not_found.error().message.find(server.base_url() + "products/ionex/2020/177/igsg1770.20i.Z (HTTP 404)"),
            std::string::npos)
      << not_found.error().message;

  const RunResult html = run_skytrace({"fetch", "--date", "2020-06-25", "--products", "clk", "--cache", cache.string(),
                                       "--base-url", server.base_url(), "--retries", "0"},
                                      scratch);
  EXPECT_EQ(html.exit_code, 6) << html.out << html.err;
  EXPECT_NE(html.err.find("not gzip data"), std::string::npos) << html.err;
  EXPECT_TRUE(regular_files_under(cache).empty());

  // One product missing does not stop the others; the exit code still reports the failure.
  const RunResult mixed = run_skytrace({"fetch", "--date", "2020-06-25", "--products", "brdc,sp3", "--cache",
                                        cache.string(), "--base-url", server.base_url(), "--retries", "0"},
                                       scratch);
  EXPECT_EQ(mixed.exit_code, 6) << mixed.out << mixed.err;
  ASSERT_EQ(lines_of(mixed.out).size(), 1u) << mixed.out;
  EXPECT_EQ(lines_of(mixed.out)[0].rfind("brdc downloaded ", 0), 0u);
  EXPECT_NE(mixed.err.find("GRG0MGXFIN_20201770000_01D_15M_ORB.SP3.gz"), std::string::npos) << mixed.err;
  EXPECT_EQ(regular_files_under(cache).size(), 1u);
}

TEST_F(FetchCli, UnreachableServerGivesExit6AfterBoundedRetries) {
  const fs::path cache = test::make_temp_dir("fetch_cache_closed");
  const fs::path scratch = test::make_temp_dir("fetch_scratch_closed");
  const std::string base_url = "http://127.0.0.1:" + std::to_string(free_port()) + "/";
  const RunResult result = run_skytrace({"fetch", "--date", "2020-06-25", "--products", "brdc", "--cache",
                                         cache.string(), "--base-url", base_url, "--retries", "2",
                                         "--retry-delay-s", "0.05"},
                                        scratch);
  EXPECT_EQ(result.exit_code, 6) << result.out << result.err;
  EXPECT_NE(result.err.find(base_url + "BRDC/2020/177/BRDC00WRD_S_20201770000_01D_MN.rnx.gz"), std::string::npos)
      << result.err;
  EXPECT_NE(result.err.find("connect"), std::string::npos) << result.err;  // curl's reason
  EXPECT_NE(result.err.find("after 3 attempts"), std::string::npos) << result.err;
  EXPECT_TRUE(regular_files_under(cache).empty());

  const RunResult usage = run_skytrace({"fetch", "--date", "2020-02-30", "--cache", cache.string()}, scratch);
  EXPECT_EQ(usage.exit_code, 2) << usage.err;
  EXPECT_NE(usage.err.find("2020-02-30"), std::string::npos) << usage.err;
}

TEST_F(FetchCli, ShortNamesFallbackNamesAndDefaultCacheFolder) {
  const auto gps_nav = SKYTRACE_SHARED_FILE("real/slac_2021118/brdc1180.21n");
  const auto glonass_nav = SKYTRACE_SHARED_FILE("real/smartloc_berlin_potsdamer_platz_2016158/brdc1580.16g");
  const auto sp3 = SKYTRACE_SHARED_FILE("real/slac_2021118/COD0MGXFIN_20211180000_01D_05M_ORB.SP3");
  const auto nav_2024 = SKYTRACE_SHARED_FILE("real/nya1_2024124/NYA100NOR_S_20241240000_01D_GN.rnx");

  const fs::path root = test::make_temp_dir("fetch_archive_old");
  const fs::path xdg = test::make_temp_dir("fetch_xdg_cache");
  const fs::path scratch = test::make_temp_dir("fetch_scratch_old");
  // 2015-06-25: RINEX 2 files and IGS short names, all Unix-compressed as in the archive.
  write_bytes(root / "BRDC/2015/176/brdc1760.15n.Z", compress_lzw(read_bytes(gps_nav)));
  write_bytes(root / "BRDC/2015/176/brdc1760.15g.Z", compress_lzw(read_bytes(glonass_nav)));
  write_bytes(root / "products/1850/igs18504.sp3.Z", compress_lzw(read_bytes(sp3)));
  // 2024-05-03: only the IGS merge exists, so the first name (BRDC00WRD_S) gives 404 first.
  write_bytes(root / "BRDC/2024/124/BRDC00IGS_R_20241240000_01D_MN.rnx.gz", gzip_bytes(read_bytes(nav_2024)));

  LocalHttpServer server(root);
  ASSERT_TRUE(server.wait_ready());
  const std::string env = "XDG_CACHE_HOME=" + quote(xdg.string());
  const RunResult old = run_skytrace({"fetch", "--date", "2015-06-25", "--products", "brdc,sp3", "--analysis-center",
                                      "IGS", "--base-url", server.base_url(), "--retries", "0"},
                                     scratch, env);
  ASSERT_EQ(old.exit_code, 0) << old.out << old.err;
  const auto lines = lines_of(old.out);
  ASSERT_EQ(lines.size(), 3u) << old.out;
  const fs::path cache = xdg / "skytrace";
  EXPECT_EQ(path_of(lines[0]), cache / "BRDC/2015/176/brdc1760.15n");
  EXPECT_EQ(path_of(lines[1]), cache / "BRDC/2015/176/brdc1760.15g");
  EXPECT_EQ(path_of(lines[2]), cache / "products/1850/igs18504.sp3");
  EXPECT_TRUE(read_bytes(path_of(lines[0])) == read_bytes(gps_nav));
  EXPECT_TRUE(read_bytes(path_of(lines[1])) == read_bytes(glonass_nav));
  EXPECT_TRUE(read_bytes(path_of(lines[2])) == read_bytes(sp3));

  const RunResult fallback = run_skytrace({"fetch", "--date", "2024-05-03", "--base-url", server.base_url(),
                                           "--retries", "0"},
                                          scratch, env);
  ASSERT_EQ(fallback.exit_code, 0) << fallback.out << fallback.err;
  ASSERT_EQ(lines_of(fallback.out).size(), 1u);
  const fs::path local = path_of(lines_of(fallback.out)[0]);
  EXPECT_EQ(local, cache / "BRDC/2024/124/BRDC00IGS_R_20241240000_01D_MN.rnx");
  EXPECT_TRUE(read_bytes(local) == read_bytes(nav_2024));
}

}  // namespace
}  // namespace skytrace
