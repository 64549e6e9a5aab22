// The scenario: everything a run needs, as typed values with defaults. Parsed from YAML; every key
// is documented in docs/scenario.md. Unknown keys and bad values are errors naming the key path
// and the line.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "skytrace/core/error.hpp"
#include "skytrace/core/path_query.hpp"
#include "skytrace/core/signal.hpp"
#include "skytrace/core/time.hpp"

namespace skytrace::sim {

struct TimeSettings {
  GnssTime start;
  TimeScale scale = TimeScale::kGpst;  // the scale `start` was written in
  double duration_s = 3600.0;
  double interval_s = 30.0;
};

// A static receiver position in one of three forms.
struct PositionSetting {
  enum class Kind { kEcef, kLla, kWorldEnu };
  Kind kind = Kind::kEcef;
  Eigen::Vector3d value = Eigen::Vector3d::Zero();  // m | (deg, deg, m) | m in the world frame
};

// A trajectory file: CSV rows of time and position (see docs/scenario.md).
struct TrajectorySetting {
  std::filesystem::path file;
  PositionSetting::Kind frame = PositionSetting::Kind::kEcef;
  TimeScale time_scale = TimeScale::kGpst;
};

// receiver.rtk: the receiver computes an RTK solution from its own carrier phases and the
// corrections of a base (docs/scenario.md).
struct RtkSettings {
  std::string base;  // another receiver of the same scenario
  // How the corrections reach the rover: each base epoch arrives latency_s after its time; the base
  // sends every interval_s (0: every epoch); none arrive during the outages (seconds after the
  // scenario's start, [from, to)). The engine's age of corrections and its limit follow.
  double latency_s = 0.0;
  double interval_s = 0.0;
  std::vector<std::pair<double, double>> outages_s;
  // Two antennas on one body: the base moves, its position at each epoch is its own fix, and the
  // rover reports the heading and pitch of the baseline (fix.csv, NMEA HDT/THS).
  bool moving_base = false;
};

// Limits of what a receiver, a trajectory or a moving model may be given: beyond them an input is
// a typo or a jump, not a place or a motion.
// Faster than a low Earth orbit is no robot, vehicle or aircraft.
inline constexpr double kMaxAntennaSpeed_mps = 2e4;
// A world's local frame holds to a few hundred km: nothing in it lies farther from its origin.
inline constexpr double kMaxWorldDistance_m = 1e6;
// Seconds after time.start in a trajectory or moving-model CSV: longer than any scenario (366 days).
inline constexpr double kMaxSecondsFromStart_s = 400.0 * 86400.0;

struct ReceiverSettings {
  std::string name = "SKYT";  // marker name in RINEX
  std::optional<PositionSetting> position;
  std::optional<TrajectorySetting> trajectory;
  double antenna_height_m = 0.0;  // antenna reference point above the marker (RINEX DELTA H)
  Eigen::Vector2d antenna_offset_en_m = Eigen::Vector2d::Zero();  // RINEX DELTA E/N
  double elevation_mask_deg = 5.0;
  std::string profile = "ideal";
  // The antenna profile (name, path or IGS name; receiver/antenna.hpp); empty: the receiver
  // profile's default_antenna.
  std::string antenna;
  std::vector<Signal> signals;
  std::string receiver_type = "SKYTRACE";
  std::string antenna_type = "";  // IGS name (RINEX ANT # / TYPE), e.g. "TRM59800.00     NONE"
  // receiver.antex: an ANTEX file whose calibration of the antenna (antex_antenna_name) moves each
  // frequency's phase centre off the reference point (docs/models/antenna.md).
  std::optional<std::filesystem::path> antex;
  std::optional<RtkSettings> rtk;
};

struct EphemerisSettings {
  std::vector<std::filesystem::path> navigation;
  std::vector<std::filesystem::path> precise_orbits;
  std::vector<std::filesystem::path> precise_clocks;
  bool nominal = false;  // the built-in nominal constellation (no file needed)
};

struct ModelSettings {
  std::string ionosphere = "klobuchar";      // none | klobuchar | ionex
  std::optional<std::filesystem::path> ionex_file;  // the IONEX map for `ionex`
  std::string troposphere = "saastamoinen";  // none | saastamoinen | unb3m
  std::string receiver_clock = "ideal";      // ideal | profile | tcxo | ocxo
  bool noise = false;
  bool multipath = false;
  // With multipath: reflectors within this radius, reflection order (0-2), knife-edge diffraction.
  double multipath_radius_m = 150.0;
  int multipath_order = 1;
  double multipath_order2_radius_m = 0.0;  // double bounces between facets this close (0: multipath_radius_m)
  bool diffraction = true;
  // Diffuse scattering off rough facades for blocked satellites (effective roughness; 0: none), and
  // the distance from the antenna within which facades scatter (docs/multipath.md).
  double scattering_coefficient = 0.0;
  int scattering_lobe_exponent = 0;  // 0: Lambertian; n: directive lobe ((1 + cos psi) / 2)^n
  double scattering_radius_m = 100.0;
  // A receiver at a fixed position searches the world's paths once per sky cell of this size that a
  // satellite passes through (PathSearchSettings::static_sky_cell_deg; 0: at every epoch).
  double static_sky_cell_deg = 0.05;
  // A receiver that moves (a trajectory, a live pose) searches its second-order and scattered paths
  // once per cube of this size (m) it enters (PathSearchSettings::moving_cell_m; 0: at every epoch).
  double moving_cell_m = 4.0;
  // Residual fields the models leave, shared by the receivers (docs/models/atmosphere-residuals.md):
  // gradients in parts per million of the distance (0: none), correlation lengths.
  double ionosphere_residual_ppm = 0.0;
  double ionosphere_residual_length_km = 300.0;
  double troposphere_residual_ppm = 0.0;
  double troposphere_residual_length_km = 50.0;
  // Fast fading of direct rays through vegetation, with noise (docs/models/foliage-fading.md): the
  // canopy's diffuse power at full extinction and the wind's Doppler spread at L1.
  bool foliage_fading = true;
  double foliage_diffuse_db = -12.0;
  double foliage_wind_spread_hz = 0.5;
};

// A mesh file placed in the world frame (world.meshes).
struct MeshSetting {
  std::filesystem::path file;
  std::string name;  // objects are named NAME/node; default: the file name
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d rpy_deg = Eigen::Vector3d::Zero();  // roll, pitch, yaw as in an SDF <pose>
  double scale = 1.0;
  std::string up_axis = "auto";   // auto | y | z
  std::string kind = "building";  // of nodes no rule or name classifies: building | tree | ground | other
  MaterialClass material = MaterialClass::kConcrete;
};

// world.materials: objects any of whose names match `match` get the class (and kind).
struct MaterialRuleSetting {
  std::string match;
  MaterialClass material_class = MaterialClass::kConcrete;
  std::optional<double> attenuation_db_per_m;  // vegetation only
  std::optional<std::string> kind;             // building | tree | ground | other
};

// world.moving: a model that follows a CSV of time, x, y, z (world frame, m) and yaw (deg).
struct MovingModelSetting {
  std::string model;
  std::filesystem::path trajectory;
  TimeScale time_scale = TimeScale::kGpst;  // of ISO times in the CSV
};

struct WorldSettings {
  std::optional<std::filesystem::path> sdf;
  std::vector<std::filesystem::path> model_paths;
  std::optional<std::filesystem::path> osm;  // .osm / .osm.pbf extract
  // City-model footprints with heights (GeoJSON, GeoPackage, ... through GDAL) and the attribute
  // that holds the height (empty: height, measuredHeight, ... or storeys, world/loaders.hpp).
  std::optional<std::filesystem::path> footprints;
  std::string footprint_height_field;
  // A CityJSON city model (its heights above mean sea level unless cityjson_height_offset_m).
  std::optional<std::filesystem::path> cityjson;
  std::optional<double> cityjson_height_offset_m;
  // A CityGML city model (1.0-3.0; its heights above mean sea level unless citygml_height_offset_m).
  std::optional<std::filesystem::path> citygml;
  std::optional<double> citygml_height_offset_m;
  // A digital elevation model as the ground (any GDAL raster; heights above mean sea level unless
  // dem_height_offset_m).
  std::optional<std::filesystem::path> dem;
  std::optional<double> dem_height_offset_m;
  std::vector<MeshSetting> meshes;
  std::vector<MaterialRuleSetting> materials;
  std::vector<MovingModelSetting> moving;
  std::optional<double> vegetation_attenuation_db_per_m;  // default of vegetation no rule sets
  std::optional<double> vegetation_hull_tolerance_m;      // simplification of vegetation hulls
  // The city beyond the model's extent: a wall this high above the ground around the objects'
  // horizontal bounds, which blocks (no reflection, no diffraction) what leaves the model below it.
  std::optional<double> surroundings_height_m;
  // Overrides of the world's <spherical_coordinates>.
  std::optional<double> latitude_deg, longitude_deg, elevation_m, heading_deg;
  [[nodiscard]] bool any() const { return sdf || osm || footprints || cityjson || citygml || dem || !meshes.empty(); }
};

// IQ samples (output.iq; `skytrace iq`): complex baseband of the first receiver's antenna, one file
// per band, with a GNSS-SDR configuration that processes them (docs/iq.md).
struct IqSettings {
  double sample_rate_hz = 4e6;
  std::string format = "sc8";  // sc8 | sc16 | gr_complex: interleaved int8, int16 or float32 I/Q
  std::vector<std::string> bands = {"L1"};  // L1: GPS L1 C/A (iq_bands() lists them all)
};

// A band `skytrace iq` writes: the signal whose observations it takes from the first receiver,
// and the complex sample rate its main lobes need.
struct IqBand {
  const char* name;         // L1 | E1 | G1 | B1
  const char* signal;       // G1C | E1C | R1C | C2I
  const char* description;  // "GPS L1 C/A", ...
  double min_sample_rate_hz;
};
[[nodiscard]] const std::vector<IqBand>& iq_bands();
[[nodiscard]] const IqBand* find_iq_band(const std::string& name);

struct OutputSettings {
  std::string rinex_version = "3.04";  // 3.04 | 4.00
  bool fix = true;     // fix.csv: the position engine on the first receiver's observations
  bool nmea = false;   // fix.nmea: NMEA 0183 sentences of that fix
  bool rtcm3 = false;  // obs.rtcm3: RTCM 3 MSM7 observations, station and ephemeris messages
  bool mcap = false;   // bag/: a rosbag2 folder (MCAP) with the ROS 2 topics of every receiver
  // lz4 | zstd | none: LZ4 frames by default, the fastest to write (an hour of ESBC at 1 Hz: bag
  // 36 MB with lz4, 22 MB with zstd at 0.3 s more CPU; scripts/bench-mcap).
  std::string mcap_compression = "lz4";
  // csv.zst | csv: truth.csv and paths.csv as zstd-compressed CSV (truth.csv.zst, paths.csv.zst:
  // about 11 % of the plain bytes, read as they are by pandas, polars and DuckDB) or as plain CSV
  // (docs/adr/0004-truth-format.md).
  std::string truth_format = "csv.zst";
  std::optional<IqSettings> iq;
};

struct Scenario {
  std::filesystem::path source;  // the YAML file (empty when built in code)
  std::string name = "scenario";
  TimeSettings time;
  std::vector<ReceiverSettings> receivers;  // at least one
  EphemerisSettings ephemeris;
  ModelSettings models;
  WorldSettings world;
  OutputSettings output;
  std::uint64_t seed = 1;
};

// Reads a scenario file; relative paths inside are resolved against the file's folder.
// The index of the receiver named `name` (a live receiver serves one of a scenario's receivers);
// an error naming the receivers there are otherwise.
[[nodiscard]] Result<size_t> find_receiver(const Scenario& scenario, std::string_view name);

// A key set from outside the file: the assignment ("models.ionosphere=none",
// "ephemeris.precise_orbits=[]": a key path and a YAML value) and the option the user gave for it,
// which messages about the value name ("--set models.ionosphere=none", "--sample-rate 1e308").
struct ScenarioOverride {
  std::string assignment, option;
};

// Assignments given as `--set ASSIGNMENT`.
[[nodiscard]] std::vector<ScenarioOverride> overrides_given_with_set(const std::vector<std::string>& assignments);

// `overrides` replace or add keys before the scenario is checked: assignments given as
// `--set ASSIGNMENT`, or (the _with_options forms) each with the option it came from.
[[nodiscard]] Result<Scenario> load_scenario(const std::filesystem::path& path,
                                             const std::vector<std::string>& overrides = {});
[[nodiscard]] Result<Scenario> load_scenario_with_options(const std::filesystem::path& path,
                                                          const std::vector<ScenarioOverride>& overrides);
// Parses scenario text; `name` is used in messages and `base_dir` resolves relative paths.
[[nodiscard]] Result<Scenario> parse_scenario(const std::string& text, const std::string& name,
                                              const std::filesystem::path& base_dir,
                                              const std::vector<std::string>& overrides = {});
[[nodiscard]] Result<Scenario> parse_scenario_with_options(const std::string& text, const std::string& name,
                                                           const std::filesystem::path& base_dir,
                                                           const std::vector<ScenarioOverride>& overrides);
// The effective configuration (defaults filled in) as YAML-compatible JSON text, for summary.json.
[[nodiscard]] std::string scenario_to_json(const Scenario& scenario);

}  // namespace skytrace::sim
