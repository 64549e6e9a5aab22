#include "skytrace/atmosphere/ionex.hpp"

#include "skytrace/core/input_limits.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>
#include <utility>

#include "skytrace/core/text_file.hpp"

namespace skytrace::atmosphere {
namespace {

constexpr double kDegToRad = std::numbers::pi / 180.0;
constexpr double kRadToDeg = 180.0 / std::numbers::pi;
constexpr double kSecondsPerDay = 86400.0;
constexpr double kGridTolerance_deg = 1e-6;
constexpr long kMissingValue = 9999;
constexpr size_t kValuesPerLine = 16;  // 16I5 per data line
constexpr size_t kValueWidth = 5;

// Message text from pieces (the atmosphere library does not link a formatting library).
template <typename... Pieces>
std::string cat(const Pieces&... pieces) {
  std::ostringstream out;
  (out << ... << pieces);
  return out.str();
}

std::string fixed(double value, int decimals) {
  std::ostringstream out;
  out.setf(std::ios::fixed);
  out.precision(decimals);
  out << value;
  return out.str();
}

std::string_view trim(std::string_view text) {
  const auto begin = text.find_first_not_of(" \t");
  if (begin == std::string_view::npos) return {};
  const auto end = text.find_last_not_of(" \t");
  return text.substr(begin, end - begin + 1);
}

// The record label in columns 61-80 (IONEX header and map records, as in RINEX).
std::string_view label_of(std::string_view line) {
  return line.size() > 60 ? trim(line.substr(60)) : std::string_view{};
}
std::string_view content_of(std::string_view line) {
  return line.substr(0, std::min<size_t>(line.size(), 60));
}

std::string file_name_of(const std::string& source) {
  const auto slash = source.find_last_of('/');
  return slash == std::string::npos ? source : source.substr(slash + 1);
}

double normalize_longitude_deg(double longitude_deg) {
  double out = std::fmod(longitude_deg, 360.0);
  if (out > 180.0) out -= 360.0;
  if (out <= -180.0) out += 360.0;
  return out;
}

class Parser {
 public:
  explicit Parser(const TextLines& lines) : lines_(lines) { maps_.source = lines.name(); }

  Result<IonexMaps> run() {
    if (auto s = header(); !s.ok()) return s.error();
    if (auto s = body(); !s.ok()) return s.error();
    return std::move(maps_);
  }

 private:
  Error error_at(size_t index, const std::string& message) const {
    return lines_.error_at(index, message);
  }

  // Reals in the fixed F6.1 columns after two blanks (2X,nF6.1) as the spec writes them; producers
  // that drift from the columns are read by blank-separated tokens instead.
  Result<std::vector<double>> fixed_reals(size_t index, size_t count, std::string_view what) const {
    const std::string_view line = content_of(lines_[index]);
    std::vector<double> values;
    bool fixed_ok = true;
    for (size_t k = 0; k < count && fixed_ok; ++k) {
      const auto text = field(line, 2 + 6 * k, 6);
      auto v = text.empty() ? Result<double>(make_error(ErrorCode::kParse, "blank"))
                            : parse_fortran_double(text);
      if (!v.ok())
        fixed_ok = false;
      else
        values.push_back(*v);
    }
    if (fixed_ok) return values;
    const auto parts = split_words(line);
    values.clear();
    for (const auto& part : parts) {
      auto v = parse_fortran_double(part);
      if (!v.ok()) break;
      values.push_back(*v);
    }
    if (values.size() != count) {
      return error_at(
          index, cat("field ", what, ": expected ", count, " numbers, found \"", trim(line), "\""));
    }
    return values;
  }

  Result<double> real_token(size_t index, std::string_view what) const {
    const auto parts = split_words(content_of(lines_[index]));
    if (parts.empty()) return error_at(index, cat("field ", what, ": blank"));
    auto v = parse_fortran_double(parts.front());
    if (!v.ok())
      return error_at(index, cat("field ", what, ": not a number: \"", parts.front(), "\""));
    return *v;
  }

  Result<long> integer_token(size_t index, std::string_view what) const {
    const auto parts = split_words(content_of(lines_[index]));
    if (parts.empty()) return error_at(index, cat("field ", what, ": blank"));
    auto v = parse_integer(parts.front());
    if (!v.ok())
      return error_at(index, cat("field ", what, ": not an integer: \"", parts.front(), "\""));
    return *v;
  }

  // Year, month, day, hour, minute, second (6I6; some producers write the second as a real), UT.
  Result<GnssTime> epoch(size_t index, std::string_view what) const {
    const auto parts = split_words(content_of(lines_[index]));
    if (parts.size() != 6) {
      return error_at(index,
                      cat("field ", what, ": expected year month day hour minute second, found \"",
                          trim(content_of(lines_[index])), "\""));
    }
    long numbers[5] = {};
    for (size_t k = 0; k < 5; ++k) {
      auto v = parse_integer(parts[k]);
      if (!v.ok())
        return error_at(index, cat("field ", what, ": not an integer: \"", parts[k], "\""));
      numbers[k] = *v;
    }
    auto second = parse_fortran_double(parts[5]);
    if (!second.ok())
      return error_at(index, cat("field ", what, ": not a number: \"", parts[5], "\""));
    long year = numbers[0];
    if (year < 100) year += year < 80 ? 2000 : 1900;
    if (numbers[1] < 1 || numbers[1] > 12 || numbers[2] < 1 || numbers[2] > 31 || numbers[3] < 0 ||
        numbers[3] > 24 || numbers[4] < 0 || numbers[4] > 59 || *second < 0.0 || *second >= 61.0) {
      return error_at(index, cat("field ", what, ": invalid date or time \"",
                                 trim(content_of(lines_[index])), "\""));
    }
    // Hour 24 (end of day) is accepted: the hours are added to midnight.
    const GnssTime midnight =
        GnssTime::from_calendar(CalendarTime{static_cast<int>(year), static_cast<int>(numbers[1]),
                                             static_cast<int>(numbers[2]), 0, 0, 0.0},
                                TimeScale::kUtc);
    return midnight + (static_cast<double>(numbers[3]) * 3600.0 +
                       static_cast<double>(numbers[4]) * 60.0 + *second);
  }

  // EXPONENT: TEC values are stored as integers times 10^exponent (IONEX 1.0: -1 in practice).
  Result<int> exponent_at(size_t index) const {
    constexpr long kMaxExponent = 9;
    auto v = integer_token(index, "EXPONENT");
    if (!v.ok()) return v.error();
    if (*v < -kMaxExponent || *v > kMaxExponent) {
      return error_at(index, cat("field EXPONENT: expected an integer from -9 to 9, found ", *v));
    }
    return static_cast<int>(*v);
  }

  Result<IonexAxis> axis(size_t index, std::string_view what, bool latitude) const {
    auto v = fixed_reals(index, 3, what);
    if (!v.ok()) return v.error();
    IonexAxis a{(*v)[0], (*v)[1], (*v)[2]};
    const double limit_deg = latitude ? 90.0 : 360.0;
    if (a.step_deg == 0.0 || std::abs(a.first_deg) > limit_deg ||
        std::abs(a.last_deg) > limit_deg) {
      return error_at(index, cat("field ", what, ": invalid grid ", a.first_deg, " ", a.last_deg,
                                 " ", a.step_deg));
    }
    const double steps = (a.last_deg - a.first_deg) / a.step_deg;
    constexpr double kMaxSteps = 1e7;  // keeps count() within range; the grid limit applies later
    if (steps > kMaxSteps) {
      return error_at(index, cat("field ", what, ": a step of ", a.step_deg, " degrees gives more than 10^7 points"));
    }
    if (steps < 0.0 || std::abs(steps - std::round(steps)) > 1e-6) {
      return error_at(index, cat("field ", what, ": ", a.first_deg, " to ", a.last_deg,
                                 " is not a whole number of steps of ", a.step_deg));
    }
    return a;
  }

  Status header() {
    bool seen_version = false, seen_first = false, seen_last = false, seen_interval = false,
         seen_count = false;
    bool seen_radius = false, seen_height = false, seen_lat = false, seen_lon = false,
         seen_mapping = false;
    for (i_ = 0; i_ < lines_.size(); ++i_) {
      const std::string_view line = lines_[i_];
      const std::string_view label = label_of(line);
      if (i_ == 0) {
        if (label != "IONEX VERSION / TYPE") {
          return error_at(i_, "not an IONEX file: the first line must be IONEX VERSION / TYPE");
        }
        auto version = parse_fortran_double(field(line, 0, 8));
        if (!version.ok()) return error_at(i_, "field IONEX VERSION: not a number");
        if (*version < 1.0 || *version >= 2.0) {
          return make_error(
              ErrorCode::kUnsupported,
              lines_.where(i_) + cat(": IONEX version ", *version, " (1.0 and 1.1 are read)"));
        }
        maps_.version = std::string(field(line, 0, 8));
        if (field(line, 20, 1) != "I")
          return error_at(i_, "field FILE TYPE: expected I (ionosphere maps)");
        maps_.satellite_system = std::string(field(line, 40, 3));
        seen_version = true;
        continue;
      }
      if (label == "END OF HEADER") {
        ++i_;
        break;
      }
      if (label == "PGM / RUN BY / DATE") {
        maps_.program = std::string(trim(content_of(line)));
      } else if (label == "DESCRIPTION") {
        maps_.description.emplace_back(trim(content_of(line)));
      } else if (label == "COMMENT") {
        maps_.comments.emplace_back(trim(content_of(line)));
      } else if (label == "EPOCH OF FIRST MAP") {
        auto t = epoch(i_, label);
        if (!t.ok()) return t.error();
        maps_.first_epoch = *t;
        seen_first = true;
      } else if (label == "EPOCH OF LAST MAP") {
        auto t = epoch(i_, label);
        if (!t.ok()) return t.error();
        maps_.last_epoch = *t;
        seen_last = true;
      } else if (label == "INTERVAL") {
        auto v = real_token(i_, label);
        if (!v.ok()) return v.error();
        if (*v < 0.0) return error_at(i_, "field INTERVAL: negative");
        maps_.interval_s = *v;
        seen_interval = true;
      } else if (label == "# OF MAPS IN FILE") {
        auto v = integer_token(i_, label);
        if (!v.ok()) return v.error();
        if (*v < 1) return error_at(i_, "field # OF MAPS IN FILE: must be at least 1");
        maps_.map_count = static_cast<int>(*v);
        seen_count = true;
      } else if (label == "MAPPING FUNCTION") {
        const auto name = trim(content_of(line));
        if (name == "NONE")
          maps_.mapping_function = IonexMappingFunction::kNone;
        else if (name == "COSZ")
          maps_.mapping_function = IonexMappingFunction::kCosZ;
        else if (name == "QFAC")
          maps_.mapping_function = IonexMappingFunction::kQFactor;
        else
          return error_at(
              i_, cat("field MAPPING FUNCTION: \"", name, "\" (expected NONE, COSZ or QFAC)"));
        seen_mapping = true;
      } else if (label == "ELEVATION CUTOFF") {
        auto v = real_token(i_, label);
        if (!v.ok()) return v.error();
        maps_.elevation_cutoff_deg = *v;
      } else if (label == "BASE RADIUS") {
        auto v = real_token(i_, label);
        if (!v.ok()) return v.error();
        if (*v < 6000.0 || *v > 7000.0)
          return error_at(i_, cat("field BASE RADIUS: ", *v, " km is not an Earth radius"));
        maps_.base_radius_m = *v * 1e3;
        seen_radius = true;
      } else if (label == "MAP DIMENSION") {
        auto v = integer_token(i_, label);
        if (!v.ok()) return v.error();
        if (*v != 2 && *v != 3) return error_at(i_, "field MAP DIMENSION: must be 2 or 3");
        maps_.map_dimension = static_cast<int>(*v);
      } else if (label == "HGT1 / HGT2 / DHGT") {
        auto v = fixed_reals(i_, 3, label);
        if (!v.ok()) return v.error();
        if ((*v)[0] != (*v)[1] || (*v)[2] != 0.0) {
          return make_error(
              ErrorCode::kUnsupported,
              lines_.where(i_) +
                  ": field HGT1 / HGT2 / DHGT: 3-D maps (several heights) are not supported");
        }
        if ((*v)[0] <= 0.0 || (*v)[0] > 5000.0)
          return error_at(i_, cat("field HGT1: ", (*v)[0], " km is out of range"));
        maps_.shell_height_m = (*v)[0] * 1e3;
        seen_height = true;
      } else if (label == "LAT1 / LAT2 / DLAT") {
        auto a = axis(i_, label, true);
        if (!a.ok()) return a.error();
        maps_.latitude = *a;
        seen_lat = true;
      } else if (label == "LON1 / LON2 / DLON") {
        auto a = axis(i_, label, false);
        if (!a.ok()) return a.error();
        maps_.longitude = *a;
        seen_lon = true;
      } else if (label == "EXPONENT") {
        auto v = exponent_at(i_);
        if (!v.ok()) return v.error();
        maps_.exponent = *v;
      } else if (label == "START OF AUX DATA") {
        // Differential code biases: not needed for the delay; skip the block.
        const size_t start = i_;
        while (i_ + 1 < lines_.size() && label_of(lines_[i_ + 1]) != "END OF AUX DATA") ++i_;
        if (i_ + 1 >= lines_.size())
          return error_at(start, "START OF AUX DATA without END OF AUX DATA");
        ++i_;
      }
      // Other records (OBSERVABLES USED, # OF STATIONS, # OF SATELLITES, ...) carry nothing needed.
    }
    if (!seen_version) return make_error(ErrorCode::kParse, lines_.name() + ": empty file");
    if (i_ > lines_.size() || label_of(lines_[i_ - 1]) != "END OF HEADER") {
      return make_error(ErrorCode::kParse, lines_.name() + ": END OF HEADER missing");
    }
    const std::pair<bool, const char*> required[] = {
        {seen_first, "EPOCH OF FIRST MAP"},  {seen_last, "EPOCH OF LAST MAP"},
        {seen_interval, "INTERVAL"},         {seen_count, "# OF MAPS IN FILE"},
        {seen_mapping, "MAPPING FUNCTION"},  {seen_radius, "BASE RADIUS"},
        {seen_height, "HGT1 / HGT2 / DHGT"}, {seen_lat, "LAT1 / LAT2 / DLAT"},
        {seen_lon, "LON1 / LON2 / DLON"}};
    for (const auto& [seen, name] : required) {
      if (!seen)
        return make_error(ErrorCode::kParse,
                          cat(lines_.name(), ": header record ", name, " missing"));
    }
    const std::uint64_t points = static_cast<std::uint64_t>(maps_.latitude.count()) * maps_.longitude.count();
    if (points > input_limits().max_grid_points) {
      return make_error(ErrorCode::kParse,
                        cat(lines_.name(), ": LAT1 / LAT2 / DLAT and LON1 / LON2 / DLON give ", points,
                            " grid points per map ", limit_hint(input_limits().max_grid_points, "SKYTRACE_MAX_GRID_POINTS")));
    }
    if (maps_.map_dimension != 2) {
      return make_error(ErrorCode::kUnsupported,
                        lines_.name() + ": 3-D maps (MAP DIMENSION 3) are not supported");
    }
    if (maps_.last_epoch < maps_.first_epoch) {
      return make_error(ErrorCode::kParse,
                        lines_.name() + ": EPOCH OF LAST MAP is before EPOCH OF FIRST MAP");
    }
    return Ok{};
  }

  Status body() {
    for (; i_ < lines_.size(); ++i_) {
      const std::string_view label = label_of(lines_[i_]);
      if (label == "START OF TEC MAP" || label == "START OF RMS MAP") {
        const bool rms = label == "START OF RMS MAP";
        const std::uint64_t per_map = static_cast<std::uint64_t>(maps_.latitude.count()) * maps_.longitude.count();
        const std::uint64_t file_limit = 5 * input_limits().max_grid_points;
        if ((maps_.tec_maps.size() + maps_.rms_maps.size() + 1) * per_map > file_limit) {
          return error_at(i_, cat("the maps of this file hold more than ", file_limit, " grid points together ",
                                  limit_hint(input_limits().max_grid_points, "SKYTRACE_MAX_GRID_POINTS"),
                                  " (five times the per-map limit)"));
        }
        auto map = read_map(rms ? "RMS" : "TEC");
        if (!map.ok()) return map.error();
        (rms ? maps_.rms_maps : maps_.tec_maps).push_back(std::move(*map));
      } else if (label == "START OF HEIGHT MAP") {
        const size_t start = i_;
        while (i_ + 1 < lines_.size() && label_of(lines_[i_ + 1]) != "END OF HEIGHT MAP") ++i_;
        if (i_ + 1 >= lines_.size())
          return error_at(start, "START OF HEIGHT MAP without END OF HEIGHT MAP");
        ++i_;
      } else if (label == "END OF FILE") {
        break;
      } else if (!trim(lines_[i_]).empty() && label != "COMMENT") {
        return error_at(i_, cat("unexpected record \"", trim(lines_[i_]), "\" between maps"));
      }
    }
    if (maps_.tec_maps.empty())
      return make_error(ErrorCode::kParse, lines_.name() + ": no TEC map in the file");
    if (static_cast<int>(maps_.tec_maps.size()) != maps_.map_count) {
      return make_error(ErrorCode::kParse,
                        cat(lines_.name(), ": header # OF MAPS IN FILE says ", maps_.map_count,
                            " but the file holds ", maps_.tec_maps.size(), " TEC maps"));
    }
    for (auto* list : {&maps_.tec_maps, &maps_.rms_maps}) {
      for (size_t k = 1; k < list->size(); ++k) {
        if (!((*list)[k - 1].epoch < (*list)[k].epoch)) {
          return error_at((*list)[k].first_line - 1,
                          "field EPOCH OF CURRENT MAP: maps not in increasing time order");
        }
      }
    }
    return Ok{};
  }

  Result<IonexMap> read_map(std::string_view kind) {
    const size_t start = i_;
    const std::string end_label = cat("END OF ", kind, " MAP");
    IonexMap map;
    map.first_line = start + 1;
    const size_t n_lat = maps_.latitude.count();
    const size_t n_lon = maps_.longitude.count();
    map.values_tecu.assign(n_lat * n_lon, std::numeric_limits<double>::quiet_NaN());
    std::vector<bool> row_seen(n_lat, false);
    bool seen_epoch = false;
    int exponent = maps_.exponent;
    for (++i_; i_ < lines_.size(); ++i_) {
      const std::string_view line = lines_[i_];
      const std::string_view label = label_of(line);
      if (label == end_label) break;
      if (label == "EPOCH OF CURRENT MAP") {
        auto t = epoch(i_, label);
        if (!t.ok()) return t.error();
        map.epoch = *t;
        seen_epoch = true;
      } else if (label == "EXPONENT") {
        auto v = exponent_at(i_);
        if (!v.ok()) return v.error();
        exponent = *v;
      } else if (label == "LAT/LON1/LON2/DLON/H") {
        if (!seen_epoch) return error_at(i_, "LAT/LON1/LON2/DLON/H before EPOCH OF CURRENT MAP");
        auto row = read_row(exponent, map.values_tecu, row_seen);
        if (!row.ok()) return row.error();
      } else if (label == "COMMENT") {
        continue;
      } else if (label.starts_with("START OF") || label.starts_with("END OF")) {
        return error_at(i_, cat("\"", label, "\" inside ", kind, " map started at line ", start + 1,
                                " (missing ", end_label, ")"));
      } else {
        return error_at(i_, cat("unexpected record \"", trim(line), "\" in ", kind, " map"));
      }
    }
    if (i_ >= lines_.size()) return error_at(start, cat(kind, " map without ", end_label));
    if (!seen_epoch) return error_at(start, cat(kind, " map without EPOCH OF CURRENT MAP"));
    for (size_t r = 0; r < n_lat; ++r) {
      if (!row_seen[r]) {
        return error_at(i_, cat(kind, " map started at line ", start + 1,
                                " has no row for latitude ", maps_.latitude.at_deg(r)));
      }
    }
    return map;
  }

  // One LAT/LON1/LON2/DLON/H record (2X,5F6.1) and its values (16I5 per line) into `values`.
  Status read_row(int exponent, std::vector<double>& values, std::vector<bool>& row_seen) {
    auto v = fixed_reals(i_, 5, "LAT/LON1/LON2/DLON/H");
    if (!v.ok()) return v.error();
    const double latitude_deg = (*v)[0];
    const IonexAxis& lat = maps_.latitude;
    const IonexAxis& lon = maps_.longitude;
    const double row_f = (latitude_deg - lat.first_deg) / lat.step_deg;
    const long row = std::lround(row_f);
    if (std::abs(row_f - static_cast<double>(row)) > 1e-6 || row < 0 ||
        row >= static_cast<long>(lat.count())) {
      return error_at(i_, cat("field LAT: ", latitude_deg, " is not on the header's grid ",
                              lat.first_deg, " to ", lat.last_deg, " step ", lat.step_deg));
    }
    if (std::abs((*v)[1] - lon.first_deg) > kGridTolerance_deg ||
        std::abs((*v)[2] - lon.last_deg) > kGridTolerance_deg ||
        std::abs((*v)[3] - lon.step_deg) > kGridTolerance_deg) {
      return error_at(i_, cat("field LON1/LON2/DLON: ", (*v)[1], " ", (*v)[2], " ", (*v)[3],
                              " differ from the header's ", lon.first_deg, " ", lon.last_deg, " ",
                              lon.step_deg));
    }
    if (std::abs((*v)[4] * 1e3 - maps_.shell_height_m) > 1.0) {
      return error_at(i_, cat("field H: ", (*v)[4], " km differs from the header's HGT1 ",
                              maps_.shell_height_m / 1e3, " km"));
    }
    const size_t index_row = static_cast<size_t>(row);
    if (row_seen[index_row])
      return error_at(i_, cat("field LAT: latitude ", latitude_deg, " given twice in one map"));
    row_seen[index_row] = true;

    const size_t n_lon = lon.count();
    const double unit_tecu = std::pow(10.0, exponent);
    const size_t row_line = i_;
    size_t filled = 0;
    while (filled < n_lon) {
      ++i_;
      if (i_ >= lines_.size()) return error_at(row_line, "file ends inside the values of this row");
      const std::string_view line = lines_[i_];
      const size_t on_line = std::min(kValuesPerLine, n_lon - filled);
      for (size_t k = 0; k < on_line; ++k, ++filled) {
        const auto text = field(line, k * kValueWidth, kValueWidth);
        auto value = text.empty() ? Result<long>(make_error(ErrorCode::kParse, "blank"))
                                  : parse_integer(text);
        if (!value.ok()) {
          return error_at(
              i_, cat("field value ", filled + 1, " of latitude ", latitude_deg, " (longitude ",
                      lon.at_deg(filled), "): expected an integer, found \"", text, "\""));
        }
        values[index_row * n_lon + filled] = *value == kMissingValue
                                                 ? std::numeric_limits<double>::quiet_NaN()
                                                 : static_cast<double>(*value) * unit_tecu;
      }
    }
    return Ok{};
  }

  const TextLines& lines_;
  IonexMaps maps_;
  size_t i_ = 0;
};

}  // namespace

size_t IonexAxis::count() const {
  if (step_deg == 0.0) return 1;
  return static_cast<size_t>(std::lround((last_deg - first_deg) / step_deg)) + 1;
}

Result<IonexMaps> read_ionex(const std::filesystem::path& path) {
  auto lines = TextLines::read(path);
  if (!lines.ok()) return lines.error();
  return Parser(*lines).run();
}

Result<IonexMaps> parse_ionex(const std::string& name, std::string content) {
  const TextLines lines(name, std::move(content));
  return Parser(lines).run();
}

std::optional<PiercePoint> thin_shell_pierce_point(const Geodetic& receiver,
                                                   const AzimuthElevation& direction,
                                                   double earth_radius_m, double shell_height_m,
                                                   ThinShellMapping mapping) {
  if (direction.elevation_deg <= 0.0) return std::nullopt;
  const double zenith_rad = (90.0 - direction.elevation_deg) * kDegToRad;
  // Geometry: the ray from the Earth's surface meets the shell at zenith angle z' there.
  const double sin_zp = earth_radius_m / (earth_radius_m + shell_height_m) * std::sin(zenith_rad);
  const double central_angle_rad = zenith_rad - std::asin(sin_zp);
  const double latitude_rad = receiver.latitude_deg * kDegToRad;
  const double azimuth_rad = direction.azimuth_deg * kDegToRad;
  const double sin_lat_p =
      std::sin(latitude_rad) * std::cos(central_angle_rad) +
      std::cos(latitude_rad) * std::sin(central_angle_rad) * std::cos(azimuth_rad);
  const double lat_p_rad = std::asin(std::clamp(sin_lat_p, -1.0, 1.0));
  // atan2 form of the longitude difference: right also when the path passes over a pole.
  const double dlon_rad =
      std::atan2(std::sin(azimuth_rad) * std::sin(central_angle_rad) * std::cos(latitude_rad),
                 std::cos(central_angle_rad) - std::sin(latitude_rad) * sin_lat_p);

  double sin_z_mapping = sin_zp;
  if (mapping == ThinShellMapping::kModifiedSingleLayer) {
    sin_z_mapping =
        earth_radius_m / (earth_radius_m + kMslmShellHeight_m) * std::sin(kMslmAlpha * zenith_rad);
  }
  PiercePoint p;
  p.latitude_deg = lat_p_rad * kRadToDeg;
  p.longitude_deg = normalize_longitude_deg(receiver.longitude_deg + dlon_rad * kRadToDeg);
  p.mapping_factor = 1.0 / std::sqrt(1.0 - sin_z_mapping * sin_z_mapping);
  return p;
}

IonexIonosphere::IonexIonosphere(IonexMaps maps, IonexOptions options)
    : maps_(std::move(maps)), options_(options) {
  const IonexAxis& lon = maps_.longitude;
  if (lon.step_deg != 0.0) {
    const double per_turn = 360.0 / std::abs(lon.step_deg);
    const double period = std::round(per_turn);
    // Global when 360 degrees are a whole number of steps and the grid holds at least one turn
    // (with or without the repeated end point -180 / 180).
    if (std::abs(per_turn - period) < 1e-6 && static_cast<double>(lon.count()) >= period) {
      global_longitude_ = true;
      longitude_period_ = static_cast<size_t>(period);
    }
  }
}

Error IonexIonosphere::time_outside(const GnssTime& t) const {
  const auto& tec = maps_.tec_maps;
  const std::string span = tec.empty()
                               ? std::string("no time (no TEC map)")
                               : cat(tec.front().epoch.to_iso8601(TimeScale::kUtc, 0), " to ",
                                     tec.back().epoch.to_iso8601(TimeScale::kUtc, 0), " UTC");
  return make_error(
      ErrorCode::kOutOfRange,
      cat("IONEX file ", file_name_of(maps_.source), " covers ", span, "; requested ",
          t.to_iso8601(TimeScale::kUtc, 3), " UTC (", t.to_iso8601(TimeScale::kGpst, 3), " GPST)"));
}

Status IonexIonosphere::covers(const GnssTime& begin, const GnssTime& end) const {
  const auto& tec = maps_.tec_maps;
  if (tec.empty() || begin < tec.front().epoch || begin > tec.back().epoch)
    return time_outside(begin);
  if (end < tec.front().epoch || end > tec.back().epoch) return time_outside(end);
  return Ok{};
}

Result<double> IonexIonosphere::spatial(const IonexMap& map, double latitude_deg,
                                        double longitude_deg) const {
  const IonexAxis& lat = maps_.latitude;
  const IonexAxis& lon = maps_.longitude;
  const size_t n_lat = lat.count();
  const size_t n_lon = lon.count();

  double q = (latitude_deg - lat.first_deg) / lat.step_deg;
  const double last_row = static_cast<double>(n_lat - 1);
  if (q < 0.0 || q > last_row) {
    // Beyond the last row of a global map (87.5 deg) the polar cap takes the row's value: better
    // than failing for high-latitude users, and the cap is 2.5 degrees wide.
    const bool near_pole_first =
        std::abs(lat.first_deg) + std::abs(lat.step_deg) >= 90.0 - kGridTolerance_deg;
    const bool near_pole_last =
        std::abs(lat.last_deg) + std::abs(lat.step_deg) >= 90.0 - kGridTolerance_deg;
    if (q < 0.0 && (near_pole_first || q > -kGridTolerance_deg)) {
      q = 0.0;
    } else if (q > last_row && (near_pole_last || q < last_row + kGridTolerance_deg)) {
      q = last_row;
    } else {
      return make_error(
          ErrorCode::kOutOfRange,
          cat("IONEX file ", file_name_of(maps_.source), ": latitude ", fixed(latitude_deg, 3),
              " deg is outside the maps (", lat.first_deg, " to ", lat.last_deg, " deg)"));
    }
  }
  size_t i0 = 0;
  double fq = 0.0;
  if (n_lat > 1) {
    i0 = std::min(static_cast<size_t>(std::floor(q)), n_lat - 2);
    fq = q - static_cast<double>(i0);
  }
  const size_t i1 = n_lat > 1 ? i0 + 1 : i0;

  double p = (longitude_deg - lon.first_deg) / lon.step_deg;
  size_t j0 = 0, j1 = 0;
  double fp = 0.0;
  if (global_longitude_) {
    const double period = static_cast<double>(longitude_period_);
    p = std::fmod(p, period);
    if (p < 0.0) p += period;
    j0 = static_cast<size_t>(std::floor(p));
    fp = p - static_cast<double>(j0);
    j0 %= longitude_period_;  // p rounding up to exactly `period`
    j1 = (j0 + 1) % longitude_period_;
  } else {
    const double last_column = static_cast<double>(n_lon - 1);
    if (p < -kGridTolerance_deg || p > last_column + kGridTolerance_deg) {
      return make_error(
          ErrorCode::kOutOfRange,
          cat("IONEX file ", file_name_of(maps_.source), ": longitude ", fixed(longitude_deg, 3),
              " deg is outside the maps (", lon.first_deg, " to ", lon.last_deg, " deg)"));
    }
    p = std::clamp(p, 0.0, last_column);
    if (n_lon > 1) {
      j0 = std::min(static_cast<size_t>(std::floor(p)), n_lon - 2);
      fp = p - static_cast<double>(j0);
      j1 = j0 + 1;
    }
  }

  // IONEX 1.0 equation (4): bilinear between the four surrounding grid points.
  const struct {
    size_t row, column;
    double weight;
  } corners[4] = {{i0, j0, (1.0 - fq) * (1.0 - fp)},
                  {i0, j1, (1.0 - fq) * fp},
                  {i1, j0, fq * (1.0 - fp)},
                  {i1, j1, fq * fp}};
  double sum = 0.0;
  for (const auto& c : corners) {
    if (c.weight == 0.0) continue;
    const double value = map.values_tecu[c.row * n_lon + c.column];
    if (std::isnan(value)) {
      return make_error(ErrorCode::kNotFound,
                        cat("IONEX file ", file_name_of(maps_.source), ": the map of ",
                            map.epoch.to_iso8601(TimeScale::kUtc, 0), " UTC (line ", map.first_line,
                            ") has no value (9999) at latitude ", lat.at_deg(c.row),
                            " deg, "
                            "longitude ",
                            lon.at_deg(c.column), " deg, needed at ", fixed(latitude_deg, 3),
                            " deg, ", fixed(longitude_deg, 3), " deg"));
    }
    sum += c.weight * value;
  }
  return sum;
}

Result<double> IonexIonosphere::interpolate(const std::vector<IonexMap>& maps, const GnssTime& t,
                                            double latitude_deg, double longitude_deg) const {
  if (maps.empty() || t < maps.front().epoch || t > maps.back().epoch) return time_outside(t);
  if (maps.size() == 1) return spatial(maps.front(), latitude_deg, longitude_deg);
  // First map after t; t equal to the last epoch interpolates in the last interval.
  const auto after =
      std::upper_bound(maps.begin(), maps.end(), t,
                       [](const GnssTime& time, const IonexMap& map) { return time < map.epoch; });
  const size_t i1 = std::min(static_cast<size_t>(after - maps.begin()), maps.size() - 1);
  const IonexMap& m0 = maps[i1 - 1];
  const IonexMap& m1 = maps[i1];
  const double since_m0_s = t - m0.epoch;  // >= 0
  const double since_m1_s = t - m1.epoch;  // <= 0
  const double w1 = since_m0_s / (m1.epoch - m0.epoch);
  const double w0 = 1.0 - w1;

  double longitude0_deg = longitude_deg;
  double longitude1_deg = longitude_deg;
  switch (options_.time_interpolation) {
    case IonexTimeInterpolation::kNearestMap:
      return spatial(since_m0_s <= -since_m1_s ? m0 : m1, latitude_deg, longitude_deg);
    case IonexTimeInterpolation::kLinear:
      break;
    case IonexTimeInterpolation::kRotatedLinear:
      // The ionosphere stays nearly fixed to the Sun: what is at longitude lambda at t was at
      // lambda + 360 deg (t - T_i) / day at the map's epoch T_i.
      longitude0_deg += 360.0 * since_m0_s / kSecondsPerDay;
      longitude1_deg += 360.0 * since_m1_s / kSecondsPerDay;
      break;
  }
  double sum = 0.0;
  if (w0 > 0.0) {
    auto e0 = spatial(m0, latitude_deg, longitude0_deg);
    if (!e0.ok()) return e0.error();
    sum += w0 * *e0;
  }
  if (w1 > 0.0) {
    auto e1 = spatial(m1, latitude_deg, longitude1_deg);
    if (!e1.ok()) return e1.error();
    sum += w1 * *e1;
  }
  return sum;
}

Result<double> IonexIonosphere::vertical_tec_tecu(const GnssTime& t, double latitude_deg,
                                                  double longitude_deg) const {
  return interpolate(maps_.tec_maps, t, latitude_deg, longitude_deg);
}

Result<double> IonexIonosphere::vertical_rms_tecu(const GnssTime& t, double latitude_deg,
                                                  double longitude_deg) const {
  if (maps_.rms_maps.empty()) {
    return make_error(ErrorCode::kNotFound,
                      cat("IONEX file ", file_name_of(maps_.source), " has no RMS maps"));
  }
  return interpolate(maps_.rms_maps, t, latitude_deg, longitude_deg);
}

Result<std::optional<double>> IonexIonosphere::slant_tec_tecu(
    const GnssTime& t, const Geodetic& receiver, const AzimuthElevation& direction) const {
  const auto pierce = thin_shell_pierce_point(receiver, direction, maps_.base_radius_m,
                                              maps_.shell_height_m, options_.mapping);
  if (!pierce) return std::optional<double>{};
  auto vtec = vertical_tec_tecu(t, pierce->latitude_deg, pierce->longitude_deg);
  if (!vtec.ok()) return vtec.error();
  return std::optional<double>{*vtec * pierce->mapping_factor};
}

Result<std::optional<double>> IonexIonosphere::slant_delay_m(const GnssTime& t,
                                                             const Geodetic& receiver,
                                                             const AzimuthElevation& direction,
                                                             double frequency_hz) const {
  auto stec = slant_tec_tecu(t, receiver, direction);
  if (!stec.ok()) return stec.error();
  if (!*stec) return std::optional<double>{};
  return std::optional<double>{ionosphere_group_delay_m(**stec, frequency_hz)};
}

Result<std::optional<double>> IonexIonosphere::delay_l1_m(const GnssTime& t,
                                                          const Geodetic& receiver,
                                                          const AzimuthElevation& direction) const {
  return slant_delay_m(t, receiver, direction, kIonosphereReferenceFrequency_hz);
}

}  // namespace skytrace::atmosphere
