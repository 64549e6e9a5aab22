#include "skytrace/core/geoid.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <memory>

#include <fmt/format.h>

namespace skytrace {
namespace {

constexpr const char* kDefaultGeoidPath = "/usr/share/proj/egm96_15.gtx";
constexpr std::size_t kHeaderBytes = 40;
constexpr float kMissing = -88.8888f;

template <typename T>
T big_endian(const char* bytes) {
  using U = std::conditional_t<sizeof(T) == 8, std::uint64_t, std::uint32_t>;
  U raw = 0;
  for (std::size_t i = 0; i < sizeof(T); ++i) raw = static_cast<U>((raw << 8) | static_cast<unsigned char>(bytes[i]));
  return std::bit_cast<T>(raw);
}

struct DefaultGeoid {
  std::unique_ptr<GeoidGrid> grid;
  std::string note;
};

const DefaultGeoid& default_geoid_state() {
  static const DefaultGeoid state = [] {
    DefaultGeoid s;
    const char* env = std::getenv("SKYTRACE_GEOID");
    if (env != nullptr && std::string_view(env) == "none") {
      s.note = "no geoid (SKYTRACE_GEOID=none): GGA heights are ellipsoidal, geoid separation 0";
      return s;
    }
    const std::filesystem::path path = env != nullptr && *env != '\0' ? env : kDefaultGeoidPath;
    std::error_code ec;
    if (env == nullptr && !std::filesystem::exists(path, ec)) {
      s.note = fmt::format("no geoid model ({} not installed: Debian package proj-data): GGA heights are "
                           "ellipsoidal, geoid separation 0", path.string());
      return s;
    }
    auto grid = GeoidGrid::load_gtx(path);
    if (!grid) {
      s.note = grid.error().message + ": GGA heights are ellipsoidal, geoid separation 0";
      return s;
    }
    s.grid = std::make_unique<GeoidGrid>(std::move(grid).value());
    s.note = fmt::format("GGA heights above mean sea level with the geoid of {}", path.string());
    return s;
  }();
  return state;
}

}  // namespace

Result<GeoidGrid> GeoidGrid::load_gtx(const std::filesystem::path& path) {
  const std::string where = path.string();
  std::ifstream in(path, std::ios::binary);
  if (!in) return Error{ErrorCode::kIo, where + ": cannot open the geoid grid"};
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (bytes.size() < kHeaderBytes) {
    return Error{ErrorCode::kParse, where + ": not a GTX geoid grid (shorter than its 40-byte header)"};
  }
  GeoidGrid g;
  g.name_ = path.filename().string();
  g.south_deg_ = big_endian<double>(bytes.data());
  g.west_deg_ = big_endian<double>(bytes.data() + 8);
  g.step_lat_deg_ = big_endian<double>(bytes.data() + 16);
  g.step_lon_deg_ = big_endian<double>(bytes.data() + 24);
  g.rows_ = big_endian<std::int32_t>(bytes.data() + 32);
  g.columns_ = big_endian<std::int32_t>(bytes.data() + 36);
  const bool sane = std::isfinite(g.south_deg_) && std::isfinite(g.west_deg_) && g.step_lat_deg_ > 1e-4 &&
                    g.step_lon_deg_ > 1e-4 && g.step_lat_deg_ <= 90.0 && g.step_lon_deg_ <= 360.0 && g.rows_ >= 2 &&
                    g.columns_ >= 2 && g.south_deg_ >= -90.0 &&
                    g.south_deg_ + g.step_lat_deg_ * (g.rows_ - 1) <= 90.0 + 1e-9 && g.rows_ <= 100000 &&
                    g.columns_ <= 100000;
  if (!sane) {
    return Error{ErrorCode::kParse, fmt::format("{}: GTX header out of range (origin {} {} deg, spacing {} {} deg, "
                                                "{} rows x {} columns)",
                                                where, g.south_deg_, g.west_deg_, g.step_lat_deg_, g.step_lon_deg_,
                                                g.rows_, g.columns_)};
  }
  const std::size_t cells = static_cast<std::size_t>(g.rows_) * static_cast<std::size_t>(g.columns_);
  if (bytes.size() != kHeaderBytes + 4 * cells) {
    return Error{ErrorCode::kParse, fmt::format("{}: {} bytes, expected {} for {} x {} float32 cells", where,
                                                bytes.size(), kHeaderBytes + 4 * cells, g.rows_, g.columns_)};
  }
  g.undulations_m_.resize(cells);
  for (std::size_t i = 0; i < cells; ++i) {
    const float n = big_endian<float>(bytes.data() + kHeaderBytes + 4 * i);
    g.undulations_m_[i] = n == kMissing || !std::isfinite(n) ? std::numeric_limits<float>::quiet_NaN() : n;
  }
  g.wraps_ = std::abs(g.step_lon_deg_ * g.columns_ - 360.0) < 1e-6;
  return g;
}

double GeoidGrid::undulation_m(double latitude_deg, double longitude_deg) const {
  if (!std::isfinite(latitude_deg) || !std::isfinite(longitude_deg)) return std::numeric_limits<double>::quiet_NaN();
  const double y = std::clamp((latitude_deg - south_deg_) / step_lat_deg_, 0.0, static_cast<double>(rows_ - 1));
  double x = std::fmod(longitude_deg - west_deg_, 360.0);
  if (x < 0.0) x += 360.0;
  x /= step_lon_deg_;
  if (!wraps_) x = std::clamp(x, 0.0, static_cast<double>(columns_ - 1));
  const int row = std::min(static_cast<int>(y), rows_ - 2);
  const int column = std::min(static_cast<int>(x), columns_ - 1);
  const double fy = y - row, fx = x - column;
  const int next_column = wraps_ ? (column + 1) % columns_ : std::min(column + 1, columns_ - 1);
  auto at = [&](int r, int c) { return static_cast<double>(undulations_m_[static_cast<std::size_t>(r) * columns_ + c]); };
  return (at(row, column) * (1.0 - fx) + at(row, next_column) * fx) * (1.0 - fy) +
         (at(row + 1, column) * (1.0 - fx) + at(row + 1, next_column) * fx) * fy;
}

const GeoidGrid* default_geoid() { return default_geoid_state().grid.get(); }

std::string default_geoid_note() { return default_geoid_state().note; }

}  // namespace skytrace
