// Global ionosphere maps in IONEX 1.0/1.1 (Schaer, Gurtner, Feltens 1998): reader, interpolation
// of vertical TEC in space and time, and the thin-shell (single layer) slant delay.
//
// Time: IONEX epochs are in UT (the spec's "EPOCH OF FIRST MAP: epoch of first TEC map (UT)");
// they are read as UTC and held on the GPST timeline, so a GPST request is shifted by the leap
// seconds (17 s in 2016) before the maps are interpolated.
#pragma once

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "skytrace/atmosphere/ionosphere.hpp"
#include "skytrace/core/error.hpp"
#include "skytrace/core/frames.hpp"
#include "skytrace/core/time.hpp"

namespace skytrace::atmosphere {

// One axis of the map grid as the header gives it: first, last and a signed step in degrees.
struct IonexAxis {
  double first_deg = 0.0;
  double last_deg = 0.0;
  double step_deg = 0.0;
  [[nodiscard]] size_t count() const;  // number of grid points, both ends included
  [[nodiscard]] double at_deg(size_t index) const {
    return first_deg + static_cast<double>(index) * step_deg;
  }
};

// One TEC or RMS map: vertical TEC (or its RMS) in TECU on the header's grid, row-major with the
// latitude index outermost (values[lat_index * longitude.count() + lon_index]); NaN where the file
// has 9999 (no value).
struct IonexMap {
  GnssTime epoch;  // on the GPST timeline (the file's UT epoch converted)
  std::vector<double> values_tecu;
  size_t first_line = 0;  // 1-based line of START OF ... MAP, for messages
};

enum class IonexMappingFunction { kNone, kCosZ, kQFactor };

struct IonexMaps {
  std::string source;                    // file name, for messages
  std::string version;                   // "1.0", "1.1"
  std::string satellite_system;          // "GPS", "GLO", "MIX", ... as written
  std::string program;                   // PGM / RUN BY / DATE, as written
  std::vector<std::string> description;  // DESCRIPTION lines
  std::vector<std::string> comments;     // COMMENT lines of the header

  GnssTime first_epoch;     // EPOCH OF FIRST MAP (GPST timeline)
  GnssTime last_epoch;      // EPOCH OF LAST MAP (GPST timeline)
  double interval_s = 0.0;  // INTERVAL, 0 when the spacing varies
  int map_count = 0;        // # OF MAPS IN FILE
  IonexMappingFunction mapping_function = IonexMappingFunction::kNone;
  double elevation_cutoff_deg = 0.0;
  double base_radius_m = 6371e3;  // BASE RADIUS (the file gives km)
  int map_dimension = 2;
  double shell_height_m = 450e3;  // HGT1 (= HGT2 for 2-D maps; the file gives km)
  IonexAxis latitude;
  IonexAxis longitude;
  int exponent = -1;  // header EXPONENT: values are in 10^exponent TECU (a map may override it)

  std::vector<IonexMap> tec_maps;  // sorted by epoch
  std::vector<IonexMap> rms_maps;  // sorted by epoch; empty when the file has none
};

// Reads an IONEX file (plain or gzip). Differential code bias blocks (AUX DATA) and height maps are
// skipped; 3-D maps (HGT1 != HGT2) are unsupported. Errors name the file, the line and the field.
[[nodiscard]] Result<IonexMaps> read_ionex(const std::filesystem::path& path);
// Parses IONEX content held in memory; `name` is used in error messages.
[[nodiscard]] Result<IonexMaps> parse_ionex(const std::string& name, std::string content);

// IONEX 1.0 section "interpolation", equations (1) to (3).
enum class IonexTimeInterpolation {
  kNearestMap,     // (1) the map nearest in time
  kLinear,         // (2) linear between the two maps around t, at the same Earth-fixed longitude
  kRotatedLinear,  // (3) linear between the two maps rotated by the Earth's rotation since their
                   // epochs: E_i at longitude lambda + 360 deg (t - T_i) / 86400 s, as the
                   // ionosphere stays nearly fixed to the Sun (the spec's recommendation)
};

// Slant-to-vertical mapping of the single-layer (thin-shell) model.
enum class ThinShellMapping {
  // SLM: 1 / cos z' with sin z' = R / (R + H) sin z, R and H from the file (the IONEX COSZ
  // mapping).
  kSingleLayer,
  // MSLM (CODE, Schaer): sin z' = R / (R + 506.7 km) sin(0.9782 z), shell at 506.7 km; fits the
  // JPL extended slab model better at low elevation.
  kModifiedSingleLayer,
};

// Where a ray crosses the shell and its slant factor.
struct PiercePoint {
  double latitude_deg = 0.0;
  double longitude_deg = 0.0;   // (-180, 180]
  double mapping_factor = 1.0;  // slant TEC / vertical TEC = 1 / cos z'
};

// Thin-shell pierce point on a spherical Earth of radius earth_radius_m with the shell at
// shell_height_m above it, for a receiver at `receiver` (its geodetic latitude used as spherical,
// its height neglected as the IONEX formula does) looking in `direction`. nullopt below the
// horizon.
[[nodiscard]] std::optional<PiercePoint> thin_shell_pierce_point(
    const Geodetic& receiver, const AzimuthElevation& direction, double earth_radius_m,
    double shell_height_m, ThinShellMapping mapping = ThinShellMapping::kSingleLayer);

inline constexpr double kMslmShellHeight_m = 506.7e3;
inline constexpr double kMslmAlpha = 0.9782;

struct IonexOptions {
  IonexTimeInterpolation time_interpolation = IonexTimeInterpolation::kRotatedLinear;
  ThinShellMapping mapping = ThinShellMapping::kSingleLayer;
};

// Evaluation of a set of maps. Space: bilinear in latitude and longitude between the four grid
// points around the point (IONEX 1.0 equation (4)); longitudes wrap around on global maps; beyond
// the last latitude row of a map reaching within one step of a pole the row's value is used.
// Time: per IonexOptions. Errors (kOutOfRange) name the file, its time span and the requested time
// in UTC, or the point; a missing grid value (9999) used by the interpolation is an error too.
class IonexIonosphere final : public IonosphereModel {
 public:
  explicit IonexIonosphere(IonexMaps maps, IonexOptions options = {});

  // Vertical TEC (TECU) at a point of the shell at time t (GPST timeline).
  [[nodiscard]] Result<double> vertical_tec_tecu(const GnssTime& t, double latitude_deg,
                                                 double longitude_deg) const;
  // The RMS map value interpolated the same way; an error when the file has no RMS maps.
  [[nodiscard]] Result<double> vertical_rms_tecu(const GnssTime& t, double latitude_deg,
                                                 double longitude_deg) const;
  // Slant TEC (TECU) along the ray: vertical TEC at the pierce point times the mapping factor.
  [[nodiscard]] Result<std::optional<double>> slant_tec_tecu(
      const GnssTime& t, const Geodetic& receiver, const AzimuthElevation& direction) const;
  // Group delay in metres on `frequency_hz`: 40.3e16 * STEC / f^2.
  [[nodiscard]] Result<std::optional<double>> slant_delay_m(const GnssTime& t,
                                                            const Geodetic& receiver,
                                                            const AzimuthElevation& direction,
                                                            double frequency_hz) const;

  // IonosphereModel: slant_delay_m on 1575.42 MHz.
  [[nodiscard]] Result<std::optional<double>> delay_l1_m(
      const GnssTime& t, const Geodetic& receiver,
      const AzimuthElevation& direction) const override;
  [[nodiscard]] std::string_view name() const override { return "ionex"; }

  // Ok when every instant of [begin, end] lies within the maps (for checks before a run).
  [[nodiscard]] Status covers(const GnssTime& begin, const GnssTime& end) const;

  [[nodiscard]] const IonexMaps& maps() const { return maps_; }
  [[nodiscard]] const IonexOptions& options() const { return options_; }

 private:
  [[nodiscard]] Result<double> interpolate(const std::vector<IonexMap>& maps, const GnssTime& t,
                                           double latitude_deg, double longitude_deg) const;
  [[nodiscard]] Result<double> spatial(const IonexMap& map, double latitude_deg,
                                       double longitude_deg) const;
  [[nodiscard]] Error time_outside(const GnssTime& t) const;

  IonexMaps maps_;
  IonexOptions options_;
  bool global_longitude_ = false;  // the longitude axis spans 360 degrees in whole steps
  size_t longitude_period_ = 0;    // grid points per 360 degrees when global_longitude_
};

}  // namespace skytrace::atmosphere
