// Downloading a day's broadcast navigation file and precise products (SP3 orbits, RINEX clocks,
// IONEX maps) from a public IGS archive, decompressing them and keeping them in a local cache.
//
// Archive layout (the IGS data-centre tree as mirrored by BKG, https://igs.bkg.bund.de/root_ftp/IGS/):
//
//   broadcast  BRDC/YYYY/DDD/<merged multi-GNSS RINEX 3 file>.rnx.gz       (dates >= 2016-01-01)
//              BRDC/YYYY/DDD/brdcDDD0.YYn.Z + brdcDDD0.YYg.Z (GPS, GLONASS) (earlier dates)
//   sp3, clk   products/WWWW/IGS0OPSFIN_YYYYDDD0000_01D_15M_ORB.SP3.gz       (IGS, week >= 2238)
//              products/WWWW/igsWWWWD.sp3.Z, igsWWWWD.clk_30s.Z               (IGS, week <  2238)
//              products/mgex/WWWW/GRG0MGXFIN_YYYYDDD0000_01D_15M_ORB.SP3.gz  (others, week <  2238)
//              products/WWWW/GRG0MGXFIN_...                                  (others, week >= 2238)
//   ionex      products/ionex/YYYY/DDD/IGS0OPSFIN_YYYYDDD0000_01D_02H_GIM.INX.gz (week >= 2238)
//              products/ionex/YYYY/DDD/igsgDDD0.YYi.Z                            (week <  2238)
//
// Why: GPS week 2238 (2022-11-27) is when the IGS switched its products to long file names and
// folded the MGEX campaign folder into the weekly product folders. Merged broadcast files have
// been published under several station-like names over the years (BKG's BRDC00WRD, the IGS
// BRDC00IGS, DLR's BRDM00DLR), so the broadcast product lists them all as alternatives, tried in
// order on HTTP 404. IONEX is always the IGS combined map, whatever the analysis centre.
// The layout follows published URLs of BKG and CDDIS (see tests/unit/test_fetch_urls.cpp); the
// IONEX folder is CDDIS's layout and was not confirmed on BKG (no network when written): use
// --base-url for another mirror with the same tree. file:// and ftp:// base URLs work too.
//
// Cache: <cache>/<archive path without the compression suffix>, e.g.
// ~/.cache/skytrace/BRDC/2020/177/BRDC00WRD_S_20201770000_01D_MN.rnx. A file there is never
// downloaded again unless forced. Files appear atomically (temporary name, then rename), so an
// interrupted or failed download leaves nothing under the final name.
#pragma once

#include <cstddef>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "skytrace/core/error.hpp"
#include "skytrace/core/time.hpp"

namespace skytrace::orbits {

inline constexpr std::string_view kDefaultArchiveBaseUrl = "https://igs.bkg.bund.de/root_ftp/IGS/";
// First GPS week of the IGS long product names (2022-11-27).
inline constexpr int kLongProductNameFirstWeek = 2238;
// First year whose merged broadcast file is looked up under long RINEX 3 names.
inline constexpr int kLongBroadcastNameFirstYear = 2016;

enum class ProductKind { kBroadcast, kOrbit, kClock, kIonex };

// "brdc", "sp3", "clk", "ionex".
[[nodiscard]] std::string_view to_string(ProductKind kind);
[[nodiscard]] Result<ProductKind> parse_product_kind(std::string_view name);
// A comma-separated list ("brdc,sp3"); duplicates are dropped, order is kept.
[[nodiscard]] Result<std::vector<ProductKind>> parse_product_list(std::string_view text);

enum class Compression { kNone, kGzip, kUnixCompress };

// Calendar day plus the archive's folder keys for it.
struct ArchiveDay {
  int year = 0;
  int month = 0;
  int day = 0;
  int day_of_year = 0;      // 1..366
  int gps_week = 0;         // continuous GPS week of the day's 00:00 GPST
  int gps_day_of_week = 0;  // 0 = Sunday
};

// Parses "YYYY-MM-DD" (a real calendar date from 1994 on, when the IGS products start).
[[nodiscard]] Result<ArchiveDay> parse_archive_day(std::string_view text);
// The archive keys of a valid calendar date (no range check).
[[nodiscard]] ArchiveDay make_archive_day(int year, int month, int day);

// One way a file may be named in the archive.
struct ArchiveCandidate {
  std::string relative_url;                    // below the base URL, e.g. "BRDC/2020/177/X.rnx.gz"
  Compression compression = Compression::kNone;
  std::filesystem::path cache_relative_path;   // relative_url without the compression suffix
};

// One file of a product; the candidates are alternative names, the first one found wins.
struct ArchiveFile {
  ProductKind kind = ProductKind::kBroadcast;
  std::string description;                     // e.g. "GLONASS broadcast navigation (RINEX 2)"
  std::vector<ArchiveCandidate> candidates;
};

struct ProductOptions {
  // Three letters (GRG, COD, GFZ, WUM, ESA, JAX, IGS, ...) or a full ten-character product prefix
  // such as "GBM0MGXRAP" that is used as given.
  std::string analysis_center = "GRG";
  std::string orbit_sample;  // e.g. "05M"; empty = the centre's usual interval
  std::string clock_sample;  // e.g. "30S"; empty = the centre's usual interval
};

// The files that make up `kind` for `day` (pure: no network, no file system). Errors for an
// analysis centre or sample spelling that cannot form a valid file name.
[[nodiscard]] Result<std::vector<ArchiveFile>> archive_files(const ArchiveDay& day, ProductKind kind,
                                                             const ProductOptions& options);

// base + relative with exactly one '/' between them.
[[nodiscard]] std::string join_url(std::string_view base_url, std::string_view relative_url);

// $XDG_CACHE_HOME/skytrace when that is an absolute path, else $HOME/.cache/skytrace. Pure: the
// environment values are passed in (nullptr = unset).
[[nodiscard]] Result<std::filesystem::path> default_cache_dir(const char* xdg_cache_home, const char* home);
// Same, reading the process environment.
[[nodiscard]] Result<std::filesystem::path> default_cache_dir();

// Decompression of downloaded bodies. The format is checked by its magic number; a mismatch
// (e.g. an HTML error page served as .gz) is a kParse error. gzip accepts concatenated members.
[[nodiscard]] Result<std::string> gunzip(std::string_view data);
// Unix `compress` (.Z, LZW with 9..16-bit codes, block mode or not), as decoded by `gzip -d`.
[[nodiscard]] Result<std::string> uncompress_lzw(std::string_view data);
[[nodiscard]] Result<std::string> decompress(std::string_view data, Compression compression);

struct FetchRequest {
  ArchiveDay day;
  std::vector<ProductKind> products{ProductKind::kBroadcast};
  std::filesystem::path cache_dir;  // empty = default_cache_dir()
  std::string base_url{kDefaultArchiveBaseUrl};
  ProductOptions options;
  double timeout_s = 300.0;         // whole transfer of one attempt
  double connect_timeout_s = 30.0;
  int retries = 3;                  // extra attempts after a transient failure (0..10)
  double retry_delay_s = 2.0;       // first back-off, doubled per attempt, at most 60 s
  bool force = false;               // download even when the cache has the file
  // Optional progress notes (downloads started, retries); the library itself never prints.
  std::function<void(const std::string&)> on_note;
};

struct FetchedProduct {
  ProductKind kind = ProductKind::kBroadcast;
  std::string description;
  std::filesystem::path path;       // decompressed file in the cache
  std::string url;                  // where it came from (the cached candidate's URL when cached)
  bool from_cache = false;
  std::size_t downloaded_bytes = 0; // compressed size; 0 when cached
};

// Fetches every file of one product. Errors name the URL(s) tried and why (curl's text or the HTTP
// status): kNotFound when the archive answered that no candidate name exists (HTTP 404/410),
// kNetwork when the server could not be reached, failed (5xx after the retries) or sent something
// that does not decompress; kInvalidArgument for a bad request; kIo when the cache cannot be written.
[[nodiscard]] Result<std::vector<FetchedProduct>> fetch_product(const FetchRequest& request, ProductKind kind);
// All products of the request, stopping at the first failure.
[[nodiscard]] Result<std::vector<FetchedProduct>> fetch_products(const FetchRequest& request);

}  // namespace skytrace::orbits
