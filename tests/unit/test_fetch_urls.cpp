// Archive URLs and cache paths of `skytrace fetch`, and the .gz / .Z decoders it relies on.
#include <zlib.h>

#include <cstdio>
#include <fstream>
#include <random>
#include <string>
#include <unordered_map>
#include <vector>

#include "skytrace/orbits/fetch.hpp"
#include "test_support.hpp"

namespace skytrace::orbits {
namespace {

// ---------------------------------------------------------------------------------------------
// Helpers: independent encoders for the decoder tests.

// An LZW encoder written the way compress 4.x writes .Z files: codes in groups of eight, a group
// padded to `width` bytes whenever the width grows or the table is cleared. Its output is checked
// against `gzip -d` below, so the decoder is not only tested against itself.
std::string compress_lzw(std::string_view input, int max_bits, bool block_mode, bool clear_when_full) {
  std::string out{'\x1f', '\x9d', static_cast<char>(max_bits | (block_mode ? 0x80 : 0))};
  if (input.empty()) return out;
  const std::uint32_t table_size = std::uint32_t{1} << max_bits;
  std::unordered_map<std::uint32_t, std::uint32_t> table;
  int width = 9;
  std::uint32_t max_code = 511;
  std::uint32_t next_free = block_mode ? 257 : 256;
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
      if (offset_bits > 0) flush(static_cast<size_t>(width));  // whole group, padded
      if (clear_pending) {
        width = 9;
        max_code = 511;
        clear_pending = false;
      } else {
        ++width;
        max_code = width == max_bits ? table_size : (std::uint32_t{1} << width) - 1;
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
    if (next_free < table_size) {
      table[key] = next_free++;
    } else if (block_mode && clear_when_full) {
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

std::string gzip_member(std::string_view input) {
  z_stream stream{};
  EXPECT_EQ(deflateInit2(&stream, 6, Z_DEFLATED, 16 + MAX_WBITS, 8, Z_DEFAULT_STRATEGY), Z_OK);
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

// Text with the repetitiveness of a RINEX file plus noise, so the LZW table fills and clears.
std::string sample_text(size_t size_bytes, unsigned seed) {
  std::mt19937 rng(seed);
  std::string text;
  const char* words[] = {"G01 ", "2020 06 25 00 00 00.0 ", "-1.234567890123D-04 ", "R24 ", "  0.000000000000E+00",
                         "\n", "END OF HEADER\n", "E11 ", "C30 "};
  while (text.size() < size_bytes) {
    if (rng() % 5 == 0) {
      text += static_cast<char>(rng() % 256);
    } else {
      text += words[rng() % std::size(words)];
    }
  }
  text.resize(size_bytes);
  return text;
}

// Runs `gzip -dc` on a file; nullopt when gzip is not available.
std::optional<std::string> gzip_decompress_file(const std::filesystem::path& path) {
  const std::string command = "gzip -dc '" + path.string() + "' 2>/dev/null";
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) return std::nullopt;
  std::string out;
  std::array<char, 1 << 16> buffer{};
  size_t n = 0;
  while ((n = fread(buffer.data(), 1, buffer.size(), pipe)) > 0) out.append(buffer.data(), n);
  const int status = pclose(pipe);
  if (status != 0) return std::nullopt;
  return out;
}

bool have_gzip() { return std::system("gzip --version >/dev/null 2>&1") == 0; }

std::vector<std::string> urls_of(const std::string& date, ProductKind kind, const ProductOptions& options = {}) {
  const auto day = parse_archive_day(date);
  EXPECT_TRUE(day.ok()) << (day.ok() ? "" : day.error().message);
  const auto files = archive_files(*day, kind, options);
  EXPECT_TRUE(files.ok()) << (files.ok() ? "" : files.error().message);
  std::vector<std::string> urls;
  for (const auto& file : *files) {
    for (const auto& candidate : file.candidates) urls.push_back(candidate.relative_url);
  }
  return urls;
}

// ---------------------------------------------------------------------------------------------
// Dates: day of year and GPS week.

TEST(FetchDates, DayOfYearAndGpsWeekMatchPublishedCalendar) {
  // Values from the IGS week boundaries and published URLs, recomputed with Python datetime.
  struct Case {
    const char* date;
    int day_of_year;
    int week;
    int day_of_week;
  };
  for (const Case& c : {Case{"2020-06-25", 177, 2111, 4}, Case{"2020-06-24", 176, 2111, 3},
                        Case{"2022-11-26", 330, 2237, 6}, Case{"2022-11-27", 331, 2238, 0},
                        Case{"1999-08-22", 234, 1024, 0}, Case{"2019-04-07", 97, 2048, 0},
                        Case{"1994-01-02", 2, 730, 0}, Case{"2016-02-29", 60, 1886, 1},
                        Case{"2020-12-31", 366, 2138, 4}, Case{"2024-01-01", 1, 2295, 1}}) {
    const auto day = parse_archive_day(c.date);
    ASSERT_TRUE(day.ok()) << c.date;
    EXPECT_EQ(day->day_of_year, c.day_of_year) << c.date;
    EXPECT_EQ(day->gps_week, c.week) << c.date;
    EXPECT_EQ(day->gps_day_of_week, c.day_of_week) << c.date;
  }
}

TEST(FetchDates, RejectsMalformedAndImpossibleDates) {
  for (const char* bad : {"2021-02-29", "2020-6-25", "2020-13-01", "2020-00-10", "2020-04-31", "1993-12-31",
                          "20200625", "2020/06/25", ""}) {
    const auto day = parse_archive_day(bad);
    ASSERT_FALSE(day.ok()) << bad;
    EXPECT_EQ(day.error().code, ErrorCode::kInvalidArgument);
    EXPECT_NE(day.error().message.find(bad), std::string::npos) << day.error().message;
  }
  EXPECT_TRUE(parse_archive_day("2000-02-29").ok());  // divisible by 400: leap
  EXPECT_FALSE(parse_archive_day("2100-02-29").ok()); // divisible by 100 only: not leap
}

TEST(FetchProducts, ParsesProductLists) {
  const auto all = parse_product_list("brdc, sp3,clk,ionex,sp3");
  ASSERT_TRUE(all.ok());
  EXPECT_EQ(*all, (std::vector<ProductKind>{ProductKind::kBroadcast, ProductKind::kOrbit, ProductKind::kClock,
                                            ProductKind::kIonex}));
  EXPECT_FALSE(parse_product_list("brdc,orbits").ok());
  EXPECT_FALSE(parse_product_list(" , ").ok());
}

// ---------------------------------------------------------------------------------------------
// URLs.

TEST(FetchUrls, BroadcastLongNamesFor2020) {
  const auto urls = urls_of("2020-06-25", ProductKind::kBroadcast);
  ASSERT_GE(urls.size(), 3u);
  EXPECT_EQ(urls[0], "BRDC/2020/177/BRDC00WRD_S_20201770000_01D_MN.rnx.gz");
  // The other merges published in the same folder are alternatives of the same file.
  EXPECT_NE(std::find(urls.begin(), urls.end(), "BRDC/2020/177/BRDC00WRD_R_20201770000_01D_MN.rnx.gz"), urls.end());
  EXPECT_NE(std::find(urls.begin(), urls.end(), "BRDC/2020/177/BRDM00DLR_S_20201770000_01D_MN.rnx.gz"), urls.end());
  // Published BKG URL (2024-01-01) must be among the candidates.
  const auto urls_2024 = urls_of("2024-01-01", ProductKind::kBroadcast);
  EXPECT_NE(std::find(urls_2024.begin(), urls_2024.end(), "BRDC/2024/001/BRDC00IGS_R_20240010000_01D_MN.rnx.gz"),
            urls_2024.end());
  const auto day = parse_archive_day("2020-06-25");
  const auto files = archive_files(*day, ProductKind::kBroadcast, {});
  ASSERT_EQ(files->size(), 1u);  // one file with alternative names
}

TEST(FetchUrls, BroadcastShortNamesBefore2016AreTwoFiles) {
  const auto urls = urls_of("2015-06-25", ProductKind::kBroadcast);
  EXPECT_EQ(urls, (std::vector<std::string>{"BRDC/2015/176/brdc1760.15n.Z", "BRDC/2015/176/brdc1760.15g.Z"}));
  const auto urls_2005 = urls_of("2005-01-09", ProductKind::kBroadcast);
  EXPECT_EQ(urls_2005.front(), "BRDC/2005/009/brdc0090.05n.Z");
}

TEST(FetchUrls, MgexProductsBeforeAndAfterWeek2238) {
  // Before: the MGEX campaign folder.
  EXPECT_EQ(urls_of("2020-06-25", ProductKind::kOrbit),
            std::vector<std::string>{"products/mgex/2111/GRG0MGXFIN_20201770000_01D_15M_ORB.SP3.gz"});
  EXPECT_EQ(urls_of("2020-06-25", ProductKind::kClock),
            std::vector<std::string>{"products/mgex/2111/GRG0MGXFIN_20201770000_01D_30S_CLK.CLK.gz"});
  EXPECT_EQ(urls_of("2022-11-26", ProductKind::kOrbit),
            std::vector<std::string>{"products/mgex/2237/GRG0MGXFIN_20223300000_01D_15M_ORB.SP3.gz"});
  // From week 2238: the weekly product folder.
  EXPECT_EQ(urls_of("2022-11-27", ProductKind::kOrbit),
            std::vector<std::string>{"products/2238/GRG0MGXFIN_20223310000_01D_15M_ORB.SP3.gz"});
  // CODE's usual 5-minute orbits; a slac_2021118 file name from the shared data.
  EXPECT_EQ(urls_of("2021-04-28", ProductKind::kOrbit, {"COD", "", ""}),
            std::vector<std::string>{"products/mgex/2155/COD0MGXFIN_20211180000_01D_05M_ORB.SP3.gz"});
  EXPECT_EQ(urls_of("2021-04-28", ProductKind::kClock, {"cod", "", ""}),
            std::vector<std::string>{"products/mgex/2155/COD0MGXFIN_20211180000_01D_30S_CLK.CLK.gz"});
  // A full prefix and explicit samples are used as given.
  EXPECT_EQ(urls_of("2020-06-25", ProductKind::kOrbit, {"GBM0MGXRAP", "05M", ""}),
            std::vector<std::string>{"products/mgex/2111/GBM0MGXRAP_20201770000_01D_05M_ORB.SP3.gz"});
  EXPECT_EQ(urls_of("2020-06-25", ProductKind::kClock, {"GRG", "", "05M"}),
            std::vector<std::string>{"products/mgex/2111/GRG0MGXFIN_20201770000_01D_05M_CLK.CLK.gz"});
}

TEST(FetchUrls, IgsCombinedProductsSwitchToLongNamesAtWeek2238) {
  const ProductOptions igs{"IGS", "", ""};
  EXPECT_EQ(urls_of("2022-11-26", ProductKind::kOrbit, igs), std::vector<std::string>{"products/2237/igs22376.sp3.Z"});
  EXPECT_EQ(urls_of("2022-11-26", ProductKind::kClock, igs),
            std::vector<std::string>{"products/2237/igs22376.clk_30s.Z"});
  EXPECT_EQ(urls_of("2020-06-25", ProductKind::kOrbit, igs), std::vector<std::string>{"products/2111/igs21114.sp3.Z"});
  // Published BKG URLs: .../products/2238/IGS0OPSFIN_20223310000_01D_15M_ORB.SP3.gz and
  // .../products/2295/IGS0OPSFIN_20240010000_01D_30S_CLK.CLK.gz.
  EXPECT_EQ(urls_of("2022-11-27", ProductKind::kOrbit, igs),
            std::vector<std::string>{"products/2238/IGS0OPSFIN_20223310000_01D_15M_ORB.SP3.gz"});
  EXPECT_EQ(urls_of("2024-01-01", ProductKind::kOrbit, igs),
            std::vector<std::string>{"products/2295/IGS0OPSFIN_20240010000_01D_15M_ORB.SP3.gz"});
  EXPECT_EQ(urls_of("2024-01-01", ProductKind::kClock, igs),
            std::vector<std::string>{"products/2295/IGS0OPSFIN_20240010000_01D_30S_CLK.CLK.gz"});
  EXPECT_EQ(urls_of("2026-04-30", ProductKind::kClock, igs),
            std::vector<std::string>{"products/2416/IGS0OPSFIN_20261200000_01D_30S_CLK.CLK.gz"});
}

TEST(FetchUrls, IonexShortAndLongNames) {
  EXPECT_EQ(urls_of("2020-06-25", ProductKind::kIonex), std::vector<std::string>{"products/ionex/2020/177/igsg1770.20i.Z"});
  EXPECT_EQ(urls_of("2022-11-26", ProductKind::kIonex), std::vector<std::string>{"products/ionex/2022/330/igsg3300.22i.Z"});
  EXPECT_EQ(urls_of("2022-11-27", ProductKind::kIonex),
            std::vector<std::string>{"products/ionex/2022/331/IGS0OPSFIN_20223310000_01D_02H_GIM.INX.gz"});
  EXPECT_EQ(urls_of("2023-02-18", ProductKind::kIonex),
            std::vector<std::string>{"products/ionex/2023/049/IGS0OPSFIN_20230490000_01D_02H_GIM.INX.gz"});
  // IONEX is the IGS combined map whatever centre is chosen for orbits.
  EXPECT_EQ(urls_of("2020-06-25", ProductKind::kIonex, {"COD", "", ""}),
            std::vector<std::string>{"products/ionex/2020/177/igsg1770.20i.Z"});
}

TEST(FetchUrls, RejectsBadCentresAndSamples) {
  const auto day = parse_archive_day("2020-06-25");
  for (const ProductOptions& bad : {ProductOptions{"XYZ", "", ""}, ProductOptions{"GRG0MGX", "", ""},
                                    ProductOptions{"GRG/../FIN", "", ""}, ProductOptions{"GRG", "5M", ""},
                                    ProductOptions{"GRG", "", "30X"}, ProductOptions{"GRG", "00M", ""}}) {
    const auto files = archive_files(*day, ProductKind::kOrbit, bad);
    ASSERT_FALSE(files.ok()) << bad.analysis_center << " " << bad.orbit_sample << " " << bad.clock_sample;
    EXPECT_EQ(files.error().code, ErrorCode::kInvalidArgument);
  }
  // Broadcast and IONEX do not depend on the centre, so they do not fail on it.
  EXPECT_TRUE(archive_files(*day, ProductKind::kBroadcast, {"XYZ", "", ""}).ok());
}

TEST(FetchUrls, JoinsBaseAndRelativeWithOneSlash) {
  EXPECT_EQ(join_url("https://igs.bkg.bund.de/root_ftp/IGS/", "BRDC/x.gz"), "https://igs.bkg.bund.de/root_ftp/IGS/BRDC/x.gz");
  EXPECT_EQ(join_url("https://igs.bkg.bund.de/root_ftp/IGS", "BRDC/x.gz"), "https://igs.bkg.bund.de/root_ftp/IGS/BRDC/x.gz");
  EXPECT_EQ(join_url("http://127.0.0.1:8000//", "/products/a"), "http://127.0.0.1:8000/products/a");
  EXPECT_EQ(join_url(kDefaultArchiveBaseUrl, "products/2111/igs21114.sp3.Z"),
            "https://igs.bkg.bund.de/root_ftp/IGS/products/2111/igs21114.sp3.Z");
}

// ---------------------------------------------------------------------------------------------
// Cache paths.

TEST(FetchCache, LocalPathMirrorsArchiveWithoutCompressionSuffix) {
  const auto day = parse_archive_day("2020-06-25");
  const auto brdc = archive_files(*day, ProductKind::kBroadcast, {});
  EXPECT_EQ(brdc->front().candidates.front().cache_relative_path,
            std::filesystem::path("BRDC/2020/177/BRDC00WRD_S_20201770000_01D_MN.rnx"));
  EXPECT_EQ(brdc->front().candidates.front().compression, Compression::kGzip);
  const auto ionex = archive_files(*day, ProductKind::kIonex, {});
  EXPECT_EQ(ionex->front().candidates.front().cache_relative_path,
            std::filesystem::path("products/ionex/2020/177/igsg1770.20i"));
  EXPECT_EQ(ionex->front().candidates.front().compression, Compression::kUnixCompress);
}

TEST(FetchCache, DefaultFolderFollowsXdgThenHome) {
  EXPECT_EQ(*default_cache_dir("/var/cache/me", "/home/me"), std::filesystem::path("/var/cache/me/skytrace"));
  EXPECT_EQ(*default_cache_dir(nullptr, "/home/me"), std::filesystem::path("/home/me/.cache/skytrace"));
  EXPECT_EQ(*default_cache_dir("", "/home/me"), std::filesystem::path("/home/me/.cache/skytrace"));
  // A relative XDG_CACHE_HOME is invalid per the XDG rules and ignored.
  EXPECT_EQ(*default_cache_dir("relative/cache", "/home/me"), std::filesystem::path("/home/me/.cache/skytrace"));
  const auto none = default_cache_dir(nullptr, nullptr);
  ASSERT_FALSE(none.ok());
  EXPECT_NE(none.error().message.find("--cache"), std::string::npos);
}

// ---------------------------------------------------------------------------------------------
// .Z (LZW) decoder.

// "TOBEORNOTTOBEORTOBEORNOT" in .Z form (16-bit, block mode), derived by hand from the LZW codes
// (T O B E O R N O T 257 259 261 266 260 262 264) and accepted by gzip -dc.
constexpr unsigned char kTobeVector[] = {0x1f, 0x9d, 0x90, 0x54, 0x9e, 0x08, 0x29, 0xf2, 0x44, 0x8a, 0x93,
                                         0x27, 0x54, 0x02, 0x0e, 0x2c, 0xa8, 0x90, 0xa0, 0x41, 0x84};

TEST(FetchLzw, DecodesHandMadeVector) {
  const std::string_view data(reinterpret_cast<const char*>(kTobeVector), sizeof(kTobeVector));
  const auto text = uncompress_lzw(data);
  ASSERT_TRUE(text.ok()) << text.error().message;
  EXPECT_EQ(*text, "TOBEORNOTTOBEORTOBEORNOT");
  // The test encoder writes exactly these bytes, so it speaks the real format too.
  EXPECT_EQ(compress_lzw("TOBEORNOTTOBEORTOBEORNOT", 16, true, true), std::string(data));
}

TEST(FetchLzw, DecodesKwKwKAndEmptyInput) {
  // "aaaaaaa": the second code is the entry being defined (the cScSc case).
  const auto text = uncompress_lzw(compress_lzw("aaaaaaaaaaaaaaaaaaaaaaaaa", 16, true, true));
  ASSERT_TRUE(text.ok());
  EXPECT_EQ(*text, std::string(25, 'a'));
  const auto empty = uncompress_lzw(compress_lzw("", 16, true, true));
  ASSERT_TRUE(empty.ok());
  EXPECT_TRUE(empty->empty());
}

TEST(FetchLzw, RoundTripsThroughWidthChangesAndTableClears) {
  // 600 kB fill a 16-bit table; 12- and 9-bit tables fill and clear many times.
  const std::string text = sample_text(600000, 7);
  for (const int max_bits : {16, 12, 9}) {
    for (const bool block_mode : {true, false}) {
      const std::string packed = compress_lzw(text, max_bits, block_mode, block_mode);
      const auto unpacked = uncompress_lzw(packed);
      ASSERT_TRUE(unpacked.ok()) << max_bits << " " << block_mode << ": " << unpacked.error().message;
      ASSERT_EQ(unpacked->size(), text.size()) << max_bits << " " << block_mode;
      EXPECT_TRUE(*unpacked == text) << max_bits << " " << block_mode;
    }
  }
}

TEST(FetchLzw, AgreesWithGzipOnEncodedFiles) {
  if (!have_gzip()) GTEST_SKIP() << "gzip not installed";
  const auto dir = test::make_temp_dir("fetch_lzw_gzip");
  const std::string text = sample_text(400000, 11);
  for (const int max_bits : {16, 13, 9}) {
    for (const bool block_mode : {true, false}) {
      const auto path = dir / ("sample" + std::to_string(max_bits) + (block_mode ? "b" : "n") + ".Z");
      const std::string packed = compress_lzw(text, max_bits, block_mode, block_mode);
      std::ofstream(path, std::ios::binary) << packed;
      const auto by_gzip = gzip_decompress_file(path);
      ASSERT_TRUE(by_gzip.has_value()) << "gzip -dc rejected " << path;
      ASSERT_TRUE(*by_gzip == text) << "gzip -dc disagrees for " << path;
      const auto ours = uncompress_lzw(packed);
      ASSERT_TRUE(ours.ok());
      EXPECT_TRUE(*ours == *by_gzip) << path;
    }
  }
  const auto vector_path = dir / "tobe.Z";
  std::ofstream(vector_path, std::ios::binary)
      .write(reinterpret_cast<const char*>(kTobeVector), sizeof(kTobeVector));
  EXPECT_EQ(gzip_decompress_file(vector_path).value_or("<gzip failed>"), "TOBEORNOTTOBEORTOBEORNOT");
}

TEST(FetchLzw, DecodesRealNavigationFile) {
  const auto path = SKYTRACE_SHARED_FILE("real/esbc_2020177/ESBC00DNK_R_20201770000_01D_MN.rnx");
  std::ifstream in(path, std::ios::binary);
  const std::string original((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_GT(original.size(), 1000000u);
  const std::string packed = compress_lzw(original, 16, true, true);
  EXPECT_LT(packed.size(), original.size() / 2);  // RINEX compresses well: sanity of the encoder
  const auto unpacked = uncompress_lzw(packed);
  ASSERT_TRUE(unpacked.ok());
  EXPECT_TRUE(*unpacked == original);
}

TEST(FetchLzw, RejectsCorruptInput) {
  const auto not_z = uncompress_lzw("<html>404</html>");
  ASSERT_FALSE(not_z.ok());
  EXPECT_EQ(not_z.error().code, ErrorCode::kParse);
  EXPECT_FALSE(uncompress_lzw(std::string{'\x1f', '\x9d', static_cast<char>(0x91), 'a', 'b'}).ok());  // 17 bits
  EXPECT_FALSE(uncompress_lzw(std::string{'\x1f', '\x9d'}).ok());
  // First code 300 (not a literal): 9-bit LSB-first 300 = 0x12c -> bytes 2c 01.
  EXPECT_FALSE(uncompress_lzw(std::string{'\x1f', '\x9d', static_cast<char>(0x90), '\x2c', '\x01'}).ok());
  // 'a' then code 400 while the next free entry is 257.
  std::string beyond{'\x1f', '\x9d', static_cast<char>(0x90)};
  const std::uint32_t bits = 97U | (400U << 9);
  beyond += static_cast<char>(bits & 0xff);
  beyond += static_cast<char>((bits >> 8) & 0xff);
  beyond += static_cast<char>((bits >> 16) & 0xff);
  const auto corrupt = uncompress_lzw(beyond);
  ASSERT_FALSE(corrupt.ok());
  EXPECT_NE(corrupt.error().message.find("beyond the table"), std::string::npos) << corrupt.error().message;
}

// ---------------------------------------------------------------------------------------------
// gzip.

TEST(FetchGzip, DecodesSingleAndConcatenatedMembers) {
  const std::string a = sample_text(200000, 3);
  const std::string b = sample_text(1000, 4);
  const auto one = gunzip(gzip_member(a));
  ASSERT_TRUE(one.ok()) << one.error().message;
  EXPECT_TRUE(*one == a);
  const auto two = gunzip(gzip_member(a) + gzip_member(b));
  ASSERT_TRUE(two.ok()) << two.error().message;
  EXPECT_TRUE(*two == a + b);
  const auto via_kind = decompress(gzip_member(b), Compression::kGzip);
  ASSERT_TRUE(via_kind.ok());
  EXPECT_EQ(*via_kind, b);
}

TEST(FetchGzip, RejectsHtmlAndTruncatedData) {
  const auto html = gunzip("<!DOCTYPE html><title>Login</title>");
  ASSERT_FALSE(html.ok());
  EXPECT_EQ(html.error().code, ErrorCode::kParse);
  const std::string member = gzip_member(sample_text(50000, 5));
  const auto truncated = gunzip(std::string_view(member).substr(0, member.size() / 2));
  ASSERT_FALSE(truncated.ok());
  EXPECT_NE(truncated.error().message.find("truncated"), std::string::npos) << truncated.error().message;
  std::string flipped = member;
  flipped[member.size() / 2] = static_cast<char>(flipped[member.size() / 2] ^ 0x55);
  EXPECT_FALSE(gunzip(flipped).ok());
}

}  // namespace
}  // namespace skytrace::orbits
