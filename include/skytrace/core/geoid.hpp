// Geoid undulation (height of the geoid above the WGS 84 ellipsoid) from a gridded model in the
// GTX format (NOAA VDatum / PROJ: big-endian header of south-west origin, spacing, rows, columns,
// then float32 undulations in metres, rows from south to north), interpolated bilinearly. The
// default model is EGM96 on a 15' grid as Debian's proj-data ships it
// (/usr/share/proj/egm96_15.gtx, 4 MB): what receivers use for mean-sea-level heights in GGA.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "skytrace/core/error.hpp"

namespace skytrace {

class GeoidGrid {
 public:
  // Reads a GTX file; errors name the file and what is wrong (size, spacing, coverage).
  [[nodiscard]] static Result<GeoidGrid> load_gtx(const std::filesystem::path& path);

  // N (m): ellipsoidal height = orthometric height + N. Longitudes wrap; latitudes outside the
  // grid take its nearest row. NaN for a cell the model marks missing (-88.8888).
  [[nodiscard]] double undulation_m(double latitude_deg, double longitude_deg) const;

  [[nodiscard]] const std::string& name() const { return name_; }

 private:
  std::string name_;  // the file's name, e.g. "egm96_15.gtx"
  double south_deg_ = 0.0, west_deg_ = 0.0, step_lat_deg_ = 0.0, step_lon_deg_ = 0.0;
  int rows_ = 0, columns_ = 0;
  bool wraps_ = false;  // the columns cover 360 degrees
  std::vector<float> undulations_m_;
};

// The geoid of NMEA heights: the GTX file named by the environment variable SKYTRACE_GEOID (or
// none when it is "none"), else /usr/share/proj/egm96_15.gtx when installed. Loaded once per
// process; nullptr when there is none (then GGA gives ellipsoidal heights with separation 0).
// `default_geoid_note()` says which, for logs and summary.json.
[[nodiscard]] const GeoidGrid* default_geoid();
[[nodiscard]] std::string default_geoid_note();

}  // namespace skytrace
