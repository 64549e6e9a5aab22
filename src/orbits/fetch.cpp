// Archive URLs, cache paths and downloads (libcurl) of broadcast and precise products.
#include "skytrace/orbits/fetch.hpp"

#include <curl/curl.h>
#include <zlib.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <thread>

#include "skytrace/core/text_file.hpp"

namespace skytrace::orbits {

namespace {

constexpr int kFirstProductYear = 1994;  // IGS products start in GPS week 730 (1994-01-02)

bool is_leap_year(int year) { return (year % 4 == 0 && year % 100 != 0) || year % 400 == 0; }

int days_in_month(int year, int month) {
  static constexpr std::array<int, 12> kDays{31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
  return month == 2 && is_leap_year(year) ? 29 : kDays[static_cast<size_t>(month - 1)];
}

std::string printf_string(const char* format, auto... args) {
  std::array<char, 256> buffer{};
  std::snprintf(buffer.data(), buffer.size(), format, args...);
  return buffer.data();
}

std::string upper(std::string_view text) {
  std::string out(text);
  for (char& c : out) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return out;
}

bool is_upper_alnum(std::string_view text) {
  return std::all_of(text.begin(), text.end(), [](char c) {
    return std::isdigit(static_cast<unsigned char>(c)) || (c >= 'A' && c <= 'Z');
  });
}

// "15M", "30S", "02H", "01D": two digits and a unit, as in the IGS long names.
bool is_valid_sample(std::string_view sample) {
  return sample.size() == 3 && std::isdigit(static_cast<unsigned char>(sample[0])) &&
         std::isdigit(static_cast<unsigned char>(sample[1])) &&
         std::string_view("SMHD").find(sample[2]) != std::string_view::npos && sample.substr(0, 2) != "00";
}

// "YYYYDDD0000": the start of a daily product in the long names.
std::string long_name_start(const ArchiveDay& day) { return printf_string("%04d%03d0000", day.year, day.day_of_year); }

ArchiveCandidate make_candidate(std::string relative_url) {
  ArchiveCandidate candidate;
  std::string local = relative_url;
  if (relative_url.ends_with(".gz")) {
    candidate.compression = Compression::kGzip;
    local.resize(local.size() - 3);
  } else if (relative_url.ends_with(".Z")) {
    candidate.compression = Compression::kUnixCompress;
    local.resize(local.size() - 2);
  }
  candidate.relative_url = std::move(relative_url);
  candidate.cache_relative_path = std::filesystem::path(local);
  return candidate;
}

ArchiveFile single_file(ProductKind kind, std::string description, std::string relative_url) {
  ArchiveFile file;
  file.kind = kind;
  file.description = std::move(description);
  file.candidates.push_back(make_candidate(std::move(relative_url)));
  return file;
}

std::vector<ArchiveFile> broadcast_files(const ArchiveDay& day) {
  const std::string folder = printf_string("BRDC/%04d/%03d/", day.year, day.day_of_year);
  if (day.year < kLongBroadcastNameFirstYear) {
    // RINEX 2 era: one merged file per system.
    const std::string stem = printf_string("brdc%03d0.%02d", day.day_of_year, day.year % 100);
    return {single_file(ProductKind::kBroadcast, "GPS broadcast navigation (RINEX 2)", folder + stem + "n.Z"),
            single_file(ProductKind::kBroadcast, "GLONASS broadcast navigation (RINEX 2)", folder + stem + "g.Z")};
  }
  ArchiveFile file;
  file.kind = ProductKind::kBroadcast;
  file.description = "merged multi-GNSS broadcast navigation (RINEX 3)";
  const std::string tail = "_" + long_name_start(day) + "_01D_MN.rnx.gz";
  // BKG's own merge first, then the IGS and DLR merges published beside it.
  for (const char* source : {"BRDC00WRD_S", "BRDC00IGS_R", "BRDC00WRD_R", "BRDC00WRD_U", "BRDM00DLR_S"}) {
    file.candidates.push_back(make_candidate(folder + source + tail));
  }
  return {file};
}

struct CenterDefaults {
  std::string_view code;
  std::string_view prefix;
  std::string_view orbit_sample;
  std::string_view clock_sample;
};

// Usual MGEX/IGS final (or rapid, for GFZ) product of each centre with its sampling intervals.
constexpr std::array<CenterDefaults, 7> kCenters{{
    {"IGS", "IGS0OPSFIN", "15M", "30S"},
    {"GRG", "GRG0MGXFIN", "15M", "30S"},
    {"COD", "COD0MGXFIN", "05M", "30S"},
    {"GFZ", "GBM0MGXRAP", "05M", "30S"},
    {"WUM", "WUM0MGXFIN", "15M", "30S"},
    {"ESA", "ESA0MGNFIN", "05M", "30S"},
    {"JAX", "JAX0MGXFIN", "05M", "30S"},
}};

struct ResolvedCenter {
  std::string prefix;  // ten characters, e.g. GRG0MGXFIN
  std::string orbit_sample;
  std::string clock_sample;
  bool igs_combined = false;  // has the short igsWWWWD names before week 2238
};

Result<ResolvedCenter> resolve_center(const ProductOptions& options) {
  const std::string name = upper(options.analysis_center);
  ResolvedCenter center;
  center.orbit_sample = "15M";
  center.clock_sample = "30S";
  if (name.size() == 3) {
    const auto it = std::find_if(kCenters.begin(), kCenters.end(), [&](const CenterDefaults& c) { return c.code == name; });
    if (it == kCenters.end()) {
      return make_error(ErrorCode::kInvalidArgument,
                        "unknown analysis centre '" + options.analysis_center +
                            "': use IGS, GRG, COD, GFZ, WUM, ESA, JAX or a full product prefix such as " + name +
                            "0MGXFIN");
    }
    center.prefix = it->prefix;
    center.orbit_sample = it->orbit_sample;
    center.clock_sample = it->clock_sample;
    center.igs_combined = name == "IGS";
  } else if (name.size() == 10 && is_upper_alnum(name) && std::isdigit(static_cast<unsigned char>(name[3]))) {
    center.prefix = name;
    center.igs_combined = name == "IGS0OPSFIN";
    if (const auto it = std::find_if(kCenters.begin(), kCenters.end(),
                                     [&](const CenterDefaults& c) { return c.prefix == name; });
        it != kCenters.end()) {
      center.orbit_sample = it->orbit_sample;
      center.clock_sample = it->clock_sample;
    }
  } else {
    return make_error(ErrorCode::kInvalidArgument,
                      "invalid analysis centre '" + options.analysis_center +
                          "': expected three letters (GRG) or a ten-character product prefix (GRG0MGXFIN)");
  }
  if (!options.orbit_sample.empty()) center.orbit_sample = upper(options.orbit_sample);
  if (!options.clock_sample.empty()) center.clock_sample = upper(options.clock_sample);
  for (const auto& [what, sample] : {std::pair{"orbit", center.orbit_sample}, std::pair{"clock", center.clock_sample}}) {
    if (!is_valid_sample(sample)) {
      return make_error(ErrorCode::kInvalidArgument, std::string("invalid ") + what + " sample interval '" + sample +
                                                         "': expected two digits and S, M, H or D (e.g. 15M, 30S)");
    }
  }
  return center;
}

Result<std::vector<ArchiveFile>> precise_files(const ArchiveDay& day, ProductKind kind, const ProductOptions& options) {
  auto center = resolve_center(options);
  if (!center.ok()) return center.error();
  const bool orbit = kind == ProductKind::kOrbit;
  const bool long_names = day.gps_week >= kLongProductNameFirstWeek;
  if (center->igs_combined && !long_names) {
    const std::string stem = printf_string("products/%04d/igs%04d%d", day.gps_week, day.gps_week, day.gps_day_of_week);
    return std::vector<ArchiveFile>{orbit ? single_file(kind, "IGS final orbits (SP3)", stem + ".sp3.Z")
                                          : single_file(kind, "IGS final clocks (RINEX clock, 30 s)", stem + ".clk_30s.Z")};
  }
  // Before week 2238 the multi-GNSS products lived in the separate MGEX campaign folder.
  const std::string campaign = center->prefix.substr(4, 3);
  const bool mgex_folder = !long_names && (campaign == "MGX" || campaign == "MGN");
  const std::string folder = printf_string(mgex_folder ? "products/mgex/%04d/" : "products/%04d/", day.gps_week);
  const std::string name = center->prefix + "_" + long_name_start(day) + "_01D_" +
                           (orbit ? center->orbit_sample + "_ORB.SP3.gz" : center->clock_sample + "_CLK.CLK.gz");
  const std::string description = center->prefix + (orbit ? " orbits (SP3)" : " clocks (RINEX clock)");
  return std::vector<ArchiveFile>{single_file(kind, description, folder + name)};
}

std::vector<ArchiveFile> ionex_files(const ArchiveDay& day) {
  const std::string folder = printf_string("products/ionex/%04d/%03d/", day.year, day.day_of_year);
  if (day.gps_week >= kLongProductNameFirstWeek) {
    return {single_file(ProductKind::kIonex, "IGS final global ionosphere map (IONEX)",
                        folder + "IGS0OPSFIN_" + long_name_start(day) + "_01D_02H_GIM.INX.gz")};
  }
  return {single_file(ProductKind::kIonex, "IGS final global ionosphere map (IONEX)",
                      folder + printf_string("igsg%03d0.%02di.Z", day.day_of_year, day.year % 100))};
}

// ---------------------------------------------------------------------------------------------
// Downloads.

void ensure_curl_initialised() {
  // curl_global_init is not thread-safe in every libcurl; do it once, before any handle.
  static std::once_flag once;
  std::call_once(once, [] { curl_global_init(CURL_GLOBAL_DEFAULT); });
}

enum class Outcome { kOk, kNotFound, kTransient, kPermanent };

struct HttpResult {
  Outcome outcome = Outcome::kPermanent;
  std::string body;
  std::string why;  // curl's text or "HTTP 503"
};

constexpr curl_off_t kMaxDownloadBytes = curl_off_t{1} << 31;  // far above any daily product

size_t append_body(char* data, size_t size, size_t count, void* user) {
  auto* body = static_cast<std::string*>(user);
  body->append(data, size * count);
  return size * count;
}

bool is_transient(CURLcode code) {
  switch (code) {
    case CURLE_COULDNT_RESOLVE_HOST:
    case CURLE_COULDNT_RESOLVE_PROXY:
    case CURLE_COULDNT_CONNECT:
    case CURLE_OPERATION_TIMEDOUT:
    case CURLE_PARTIAL_FILE:
    case CURLE_GOT_NOTHING:
    case CURLE_SEND_ERROR:
    case CURLE_RECV_ERROR:
    case CURLE_SSL_CONNECT_ERROR:
    case CURLE_HTTP2:
    case CURLE_HTTP2_STREAM:
    case CURLE_FTP_ACCEPT_TIMEOUT:
    case CURLE_FTP_CANT_GET_HOST:
    case CURLE_WEIRD_SERVER_REPLY:
      return true;
    default:
      return false;
  }
}

HttpResult http_get(const std::string& url, const FetchRequest& request) {
  ensure_curl_initialised();
  HttpResult result;
  CURL* curl = curl_easy_init();
  if (curl == nullptr) {
    result.why = "cannot create a libcurl handle";
    return result;
  }
  std::array<char, CURL_ERROR_SIZE> error_text{};
  const auto to_ms = [](double seconds) { return static_cast<long>(std::max(1.0, seconds * 1000.0)); };
  curl_easy_setopt(curl, CURLOPT_URL, url.c_str());
  curl_easy_setopt(curl, CURLOPT_PROTOCOLS_STR, "http,https,ftp,ftps,file");
  curl_easy_setopt(curl, CURLOPT_REDIR_PROTOCOLS_STR, "http,https,ftp,ftps");
  curl_easy_setopt(curl, CURLOPT_FOLLOWLOCATION, 1L);
  curl_easy_setopt(curl, CURLOPT_MAXREDIRS, 10L);
  curl_easy_setopt(curl, CURLOPT_NOSIGNAL, 1L);  // timeouts without SIGALRM (thread safety)
  curl_easy_setopt(curl, CURLOPT_CONNECTTIMEOUT_MS, to_ms(request.connect_timeout_s));
  curl_easy_setopt(curl, CURLOPT_TIMEOUT_MS, to_ms(request.timeout_s));
  curl_easy_setopt(curl, CURLOPT_MAXFILESIZE_LARGE, kMaxDownloadBytes);
  curl_easy_setopt(curl, CURLOPT_USERAGENT, "skytrace/0.1 (+libcurl)");
  curl_easy_setopt(curl, CURLOPT_ERRORBUFFER, error_text.data());
  curl_easy_setopt(curl, CURLOPT_WRITEFUNCTION, append_body);
  curl_easy_setopt(curl, CURLOPT_WRITEDATA, &result.body);
  // The archives serve .gz/.Z files as they are; never let curl decode them on the way.
  curl_easy_setopt(curl, CURLOPT_HTTP_CONTENT_DECODING, 0L);

  const CURLcode code = curl_easy_perform(curl);
  long status = 0;
  curl_easy_getinfo(curl, CURLINFO_RESPONSE_CODE, &status);
  curl_easy_cleanup(curl);

  if (code != CURLE_OK) {
    // The error buffer has the details ("Failed to connect to host port 80 after 3 ms: ...").
    result.why = error_text[0] != '\0' ? std::string(error_text.data()) : std::string(curl_easy_strerror(code));
    if (code == CURLE_REMOTE_FILE_NOT_FOUND || code == CURLE_FILE_COULDNT_READ_FILE) {
      result.outcome = Outcome::kNotFound;
    } else {
      result.outcome = is_transient(code) ? Outcome::kTransient : Outcome::kPermanent;
    }
    result.body.clear();
    return result;
  }
  // status is 0 for file:// and the last FTP reply code for ftp://; only HTTP codes are >= 100
  // and < 600 with a meaning here.
  const bool is_http = url.starts_with("http://") || url.starts_with("https://");
  if (is_http && (status < 200 || status >= 300)) {
    result.why = "HTTP " + std::to_string(status);
    if (status == 404 || status == 410) {
      result.outcome = Outcome::kNotFound;
    } else if (status == 408 || status == 429 || status >= 500) {
      result.outcome = Outcome::kTransient;
    } else {
      result.outcome = Outcome::kPermanent;
    }
    result.body.clear();
    return result;
  }
  result.outcome = Outcome::kOk;
  return result;
}

std::optional<std::filesystem::path> cached_file(const std::filesystem::path& path) {
  std::error_code ec;
  if (std::filesystem::is_regular_file(path, ec) && std::filesystem::file_size(path, ec) > 0 && !ec) return path;
  return std::nullopt;
}

Result<FetchedProduct> fetch_file(const FetchRequest& request, const std::filesystem::path& cache_dir,
                                  const ArchiveFile& file) {
  const auto note = [&](const std::string& text) {
    if (request.on_note) request.on_note(text);
  };
  if (!request.force) {
    for (const auto& candidate : file.candidates) {
      if (auto path = cached_file(cache_dir / candidate.cache_relative_path)) {
        return FetchedProduct{file.kind, file.description, *path, join_url(request.base_url, candidate.relative_url),
                              true, 0};
      }
    }
  }
  const int retries = std::clamp(request.retries, 0, 10);
  std::vector<std::string> not_found;
  for (const auto& candidate : file.candidates) {
    const std::string url = join_url(request.base_url, candidate.relative_url);
    double delay_s = std::clamp(request.retry_delay_s, 0.0, 60.0);
    HttpResult got;
    int attempt = 0;
    for (;; ++attempt) {
      note("downloading " + url);
      got = http_get(url, request);
      if (got.outcome != Outcome::kTransient || attempt >= retries) break;
      note(url + ": " + got.why + "; retrying in " + printf_string("%.1f", delay_s) + " s (attempt " +
           std::to_string(attempt + 2) + " of " + std::to_string(retries + 1) + ")");
      std::this_thread::sleep_for(std::chrono::duration<double>(delay_s));
      delay_s = std::min(2.0 * delay_s, 60.0);
    }
    if (got.outcome == Outcome::kNotFound) {
      not_found.push_back(url + " (" + got.why + ")");
      continue;
    }
    if (got.outcome != Outcome::kOk) {
      const std::string attempts =
          attempt > 0 ? " (after " + std::to_string(attempt + 1) + " attempts)" : std::string();
      return make_error(ErrorCode::kNetwork, "download of " + file.description + " failed: " + url + ": " + got.why + attempts);
    }
    auto content = decompress(got.body, candidate.compression);
    if (!content.ok()) {
      return make_error(ErrorCode::kNetwork, "download of " + file.description + " failed: " + url +
                                                 ": the server's reply is not a valid file: " + content.error().message);
    }
    if (content->empty()) {
      return make_error(ErrorCode::kNetwork, "download of " + file.description + " failed: " + url + ": empty file");
    }
    const std::filesystem::path path = cache_dir / candidate.cache_relative_path;
    std::error_code ec;
    std::filesystem::create_directories(path.parent_path(), ec);
    if (ec) {
      return make_error(ErrorCode::kOutput, path.parent_path().string() + ": cannot create cache folder (" + ec.message() + ")");
    }
    if (auto written = write_file_atomically(path, *content); !written.ok()) return written.error();
    return FetchedProduct{file.kind, file.description, path, url, false, got.body.size()};
  }
  std::string list;
  for (const auto& entry : not_found) list += (list.empty() ? "" : ", ") + entry;
  return make_error(ErrorCode::kNotFound, file.description + " not found in the archive: " + list);
}

}  // namespace

std::string_view to_string(ProductKind kind) {
  switch (kind) {
    case ProductKind::kBroadcast: return "brdc";
    case ProductKind::kOrbit: return "sp3";
    case ProductKind::kClock: return "clk";
    case ProductKind::kIonex: return "ionex";
  }
  return "?";
}

Result<ProductKind> parse_product_kind(std::string_view name) {
  for (const ProductKind kind : {ProductKind::kBroadcast, ProductKind::kOrbit, ProductKind::kClock, ProductKind::kIonex}) {
    if (name == to_string(kind)) return kind;
  }
  return make_error(ErrorCode::kInvalidArgument,
                    "unknown product '" + std::string(name) + "': expected brdc, sp3, clk or ionex");
}

Result<std::vector<ProductKind>> parse_product_list(std::string_view text) {
  std::vector<ProductKind> kinds;
  size_t start = 0;
  while (start <= text.size()) {
    const size_t comma = std::min(text.find(',', start), text.size());
    std::string_view item = text.substr(start, comma - start);
    while (!item.empty() && std::isspace(static_cast<unsigned char>(item.front()))) item.remove_prefix(1);
    while (!item.empty() && std::isspace(static_cast<unsigned char>(item.back()))) item.remove_suffix(1);
    if (!item.empty()) {
      auto kind = parse_product_kind(item);
      if (!kind.ok()) return kind.error();
      if (std::find(kinds.begin(), kinds.end(), *kind) == kinds.end()) kinds.push_back(*kind);
    }
    start = comma + 1;
  }
  if (kinds.empty()) return make_error(ErrorCode::kInvalidArgument, "no product given: expected e.g. brdc,sp3,clk,ionex");
  return kinds;
}

ArchiveDay make_archive_day(int year, int month, int day) {
  ArchiveDay out;
  out.year = year;
  out.month = month;
  out.day = day;
  out.day_of_year = day;
  for (int m = 1; m < month; ++m) out.day_of_year += days_in_month(year, m);
  // The calendar day in GPST names the product day; weeks count from 1980-01-06.
  const WeekTow week_tow = GnssTime::from_calendar(CalendarTime{year, month, day, 0, 0, 0.0}, TimeScale::kGpst)
                               .to_week_tow(TimeScale::kGpst);
  out.gps_week = week_tow.week;
  out.gps_day_of_week = static_cast<int>(week_tow.tow_s / 86400.0);
  return out;
}

Result<ArchiveDay> parse_archive_day(std::string_view text) {
  const auto fail = [&](const std::string& why) -> Result<ArchiveDay> {
    return make_error(ErrorCode::kInvalidArgument, "invalid date '" + std::string(text) + "': " + why);
  };
  if (text.size() != 10 || text[4] != '-' || text[7] != '-') return fail("expected YYYY-MM-DD");
  for (const size_t i : {0, 1, 2, 3, 5, 6, 8, 9}) {
    if (!std::isdigit(static_cast<unsigned char>(text[i]))) return fail("expected YYYY-MM-DD");
  }
  const int year = std::stoi(std::string(text.substr(0, 4)));
  const int month = std::stoi(std::string(text.substr(5, 2)));
  const int day = std::stoi(std::string(text.substr(8, 2)));
  if (month < 1 || month > 12) return fail("month out of range");
  if (day < 1 || day > days_in_month(year, month)) return fail("day out of range for the month");
  if (year < kFirstProductYear) return fail("the IGS archive starts in 1994");
  return make_archive_day(year, month, day);
}

Result<std::vector<ArchiveFile>> archive_files(const ArchiveDay& day, ProductKind kind, const ProductOptions& options) {
  switch (kind) {
    case ProductKind::kBroadcast: return broadcast_files(day);
    case ProductKind::kOrbit:
    case ProductKind::kClock: return precise_files(day, kind, options);
    case ProductKind::kIonex: return ionex_files(day);
  }
  return make_error(ErrorCode::kInvalidArgument, "unknown product kind");
}

std::string join_url(std::string_view base_url, std::string_view relative_url) {
  std::string out(base_url);
  while (!out.empty() && out.back() == '/') out.pop_back();
  while (!relative_url.empty() && relative_url.front() == '/') relative_url.remove_prefix(1);
  out += '/';
  out += relative_url;
  return out;
}

Result<std::filesystem::path> default_cache_dir(const char* xdg_cache_home, const char* home) {
  // The XDG base-directory rules ignore a relative XDG_CACHE_HOME.
  if (xdg_cache_home != nullptr && *xdg_cache_home != '\0' && std::filesystem::path(xdg_cache_home).is_absolute()) {
    return std::filesystem::path(xdg_cache_home) / "skytrace";
  }
  if (home != nullptr && *home != '\0') return std::filesystem::path(home) / ".cache" / "skytrace";
  return make_error(ErrorCode::kInvalidArgument,
                    "no cache folder: neither XDG_CACHE_HOME nor HOME is set (give --cache DIR)");
}

Result<std::filesystem::path> default_cache_dir() {
  return default_cache_dir(std::getenv("XDG_CACHE_HOME"), std::getenv("HOME"));
}

Result<std::string> gunzip(std::string_view data) {
  if (data.size() < 2 || static_cast<unsigned char>(data[0]) != 0x1f || static_cast<unsigned char>(data[1]) != 0x8b) {
    return make_error(ErrorCode::kParse, "not gzip data (no 1f 8b magic number)");
  }
  z_stream stream{};
  if (inflateInit2(&stream, 16 + MAX_WBITS) != Z_OK) return make_error(ErrorCode::kParse, "zlib initialisation failed");
  std::string out;
  std::array<char, 1 << 16> chunk{};
  stream.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(data.data()));
  stream.avail_in = static_cast<uInt>(data.size());
  for (;;) {
    stream.next_out = reinterpret_cast<Bytef*>(chunk.data());
    stream.avail_out = static_cast<uInt>(chunk.size());
    const int status = inflate(&stream, Z_NO_FLUSH);
    out.append(chunk.data(), chunk.size() - stream.avail_out);
    if (status == Z_STREAM_END) {
      // Another member may follow (concatenated .gz files are valid gzip); anything else is
      // trailing garbage, which gzip ignores too.
      if (stream.avail_in >= 2 && stream.next_in[0] == 0x1f && stream.next_in[1] == 0x8b) {
        inflateReset(&stream);
        continue;
      }
      break;
    }
    if (status != Z_OK) {
      const std::string why = stream.msg != nullptr ? stream.msg : "stream error";
      inflateEnd(&stream);
      return make_error(ErrorCode::kParse, "corrupt gzip data: " + why);
    }
    if (stream.avail_in == 0 && stream.avail_out != 0) {
      inflateEnd(&stream);
      return make_error(ErrorCode::kParse, "truncated gzip data");
    }
  }
  inflateEnd(&stream);
  return out;
}

Result<std::string> decompress(std::string_view data, Compression compression) {
  switch (compression) {
    case Compression::kNone: return std::string(data);
    case Compression::kGzip: return gunzip(data);
    case Compression::kUnixCompress: return uncompress_lzw(data);
  }
  return make_error(ErrorCode::kParse, "unknown compression");
}

Result<std::vector<FetchedProduct>> fetch_product(const FetchRequest& request, ProductKind kind) {
  if (request.base_url.empty()) return make_error(ErrorCode::kInvalidArgument, "empty base URL");
  if (!(request.timeout_s > 0.0) || !(request.connect_timeout_s > 0.0)) {
    return make_error(ErrorCode::kInvalidArgument, "timeouts must be positive");
  }
  if (request.retries < 0 || request.retries > 10) {
    return make_error(ErrorCode::kInvalidArgument, "retries must be between 0 and 10");
  }
  if (!(request.retry_delay_s >= 0.0 && request.retry_delay_s <= 60.0)) {  // NaN too
    return make_error(ErrorCode::kInvalidArgument, "the retry delay must be 0 to 60 s");
  }
  std::filesystem::path cache_dir = request.cache_dir;
  if (cache_dir.empty()) {
    auto dir = default_cache_dir();
    if (!dir.ok()) return dir.error();
    cache_dir = *dir;
  }
  auto files = archive_files(request.day, kind, request.options);
  if (!files.ok()) return files.error();
  std::vector<FetchedProduct> fetched;
  for (const auto& file : *files) {
    auto one = fetch_file(request, cache_dir, file);
    if (!one.ok()) return one.error();
    fetched.push_back(std::move(*one));
  }
  return fetched;
}

Result<std::vector<FetchedProduct>> fetch_products(const FetchRequest& request) {
  std::vector<FetchedProduct> fetched;
  for (const ProductKind kind : request.products) {
    auto some = fetch_product(request, kind);
    if (!some.ok()) return some.error();
    for (auto& product : *some) fetched.push_back(std::move(product));
  }
  return fetched;
}

}  // namespace skytrace::orbits
