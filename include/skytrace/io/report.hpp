// The run report: one self-contained HTML page (inline CSS and SVG, no script, no external URL)
// with a polar sky plot of the sky mask and the satellite tracks, the number of tracked satellites
// over time per system, C/N0 over time, the position fix of every receiver (solution type, error
// against the truth over time and as a distribution, satellites used, HDOP, the track from above)
// and the scenario summary; and the sky plot alone as an SVG document.
//
// The builder knows nothing of the simulation types: the run loop feeds one ReportSample per
// satellite and epoch. Memory stays bounded however long the run: each track keeps at most about
// max_points_per_track points (every other point is dropped when the track is full, status changes
// are kept preferentially) and the satellite-count series is thinned the same way.
//
// Sky plot geometry (so that figures can be checked): the plot's centre is the zenith at SVG
// coordinates (0, 0), the horizon is the circle of radius 100, north is up and east right:
//   x = r sin(azimuth), y = -r cos(azimuth), r = 100 (90 - elevation) / 90.
// Samples below the horizon are not drawn.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <map>
#include <string_view>
#include <string>
#include <utility>
#include <vector>

#include "skytrace/core/satellite.hpp"
#include "skytrace/core/error_histogram.hpp"
#include "skytrace/core/time.hpp"

namespace skytrace::io {

struct ReportSample {
  GnssTime time;
  SatelliteId satellite;
  double azimuth_deg = 0.0;    // clockwise from north
  double elevation_deg = 0.0;
  // "tracked", "blocked", "attenuated" (vegetation dropped every signal), "below_mask",
  // "no_ephemeris", "no_signal", ... (the receiver layer's status names).
  std::string status;
  double cn0_dbhz = std::numeric_limits<double>::quiet_NaN();  // first signal's C/N0 when tracked
  double vegetation_attenuation_db = 0.0;
  // models.multipath: "los", "multipath" (direct plus reflected or diffracted paths), "nlos"
  // (received only off reflections or diffraction); empty without the model.
  std::string path_kind;
  // Whose sky: each receiver gets its own sky plot, satellite counts, C/N0 and path-type charts, in
  // the order first seen; empty counts as the first receiver's.
  std::string receiver;
};

struct ReportMeta {
  std::string scenario_name;
  std::string receiver_name;
  GnssTime start;
  GnssTime end;
  double interval_s = 0.0;
  std::vector<std::pair<std::string, std::string>> summary_rows;  // key, value, in order
  // Obstruction elevation at azimuths 0, step, 2 step, ... (deg); empty: open sky.
  std::vector<double> sky_mask_elevation_deg;
  double sky_mask_azimuth_step_deg = 0.0;
  // The other receivers' masks at their start, by receiver name, at the same azimuth step.
  std::map<std::string, std::vector<double>> receiver_sky_masks_deg;
  std::vector<std::string> warnings;
  // The world seen from above, in the frame of the fixes' top views (east and north metres from
  // the first true position the report saw): objects' outlines; drawn with the receivers' tracks.
  struct MapOutline {
    enum class Kind : std::uint8_t { kBuilding, kTree, kOther } kind = Kind::kOther;
    std::vector<std::pair<double, double>> east_north_m;
  };
  std::vector<MapOutline> world_outlines;
};

// How a sample is drawn on the sky plot.
enum class TrackClass : std::uint8_t {
  kLineOfSight,     // tracked, no vegetation on the path (green)
  kVegetation,      // tracked through vegetation (orange)
  kVegetationLost,  // "attenuated": vegetation dropped every signal (brown)
  kBlocked,         // "blocked" (red)
  kOther,           // below the mask, no ephemeris, ... (grey)
  kMultipath,       // tracked with reflected or diffracted paths beside the direct one (blue)
  kNlos,            // tracked without a direct path, off reflections or diffraction (purple)
};
[[nodiscard]] TrackClass classify(const ReportSample& sample);

class ReportBuilder {
 public:
  explicit ReportBuilder(double max_points_per_track = 2000);

  // Samples of one satellite are expected in time order (one older than that satellite's latest
  // is counted in ignored_samples() and otherwise ignored); epochs in time order for the counts.
  void add(const ReportSample& sample);

  // A receiver's solution at an epoch, by fix.csv's name: "none", "2d", "3d", "dgnss",
  // "rtk_float", "rtk_fixed" (unknown names count as "none"). Epochs in time order per receiver.
  // Kept as runs of one type: memory grows with the changes, and stops at kMaxFixRuns per receiver
  // (the counts stay exact).
  // With `error`: the fix against the receiver's true antenna position at that epoch, for the
  // "Position fix" section (errors over time and their distribution, satellites used, HDOP, the
  // track seen from above). Points for the charts are thinned like the tracks (at most
  // max_points_per_track per receiver); the error percentiles come from histograms of every
  // epoch (log-spaced bins 2.3 % wide), so memory stays bounded however long the run.
  struct FixError {
    double east_m = 0.0, north_m = 0.0, up_m = 0.0;  // fix minus truth, local east-north-up
    // The fix and the truth in the top view's frame: east and north metres from one origin (the
    // first receiver's first true position), the same for every receiver of the report.
    double fix_east_m = 0.0, fix_north_m = 0.0;
    double truth_east_m = 0.0, truth_north_m = 0.0;
    int satellites_used = 0;
    double hdop = 0.0;
  };
  void add_fix(const std::string& receiver, const GnssTime& time, std::string_view type,
               const FixError* error = nullptr);
  static constexpr size_t kMaxFixRuns = 20000;

  // The self-contained page.
  [[nodiscard]] std::string html(const ReportMeta& meta) const;
  // The sky plot alone, as a standalone SVG document (same drawing as in the page).
  [[nodiscard]] std::string sky_plot_svg(const ReportMeta& meta) const;

  [[nodiscard]] size_t ignored_samples() const { return ignored_samples_; }
  // Points currently held for a satellite's track of the first receiver (0 if unknown): shows the
  // memory bound.
  [[nodiscard]] size_t track_points(const SatelliteId& satellite) const;

  struct TrackPoint {
    double time_s = 0.0;  // GPST seconds since the GPS epoch (plots only)
    float azimuth_deg = 0.0F;
    float elevation_deg = 0.0F;
    float cn0_dbhz = 0.0F;  // NaN when not tracked
    TrackClass track_class = TrackClass::kOther;
  };
  struct Track {
    std::vector<TrackPoint> points;  // decimated history
    TrackPoint latest;               // the newest sample, kept or not (labels sit there)
    size_t samples_seen = 0;
    size_t stride = 1;  // every stride-th sample is kept (plus status changes)
    // Status changes are kept beyond the stride until they alone would fill the track (a status
    // flickering at every sample): from then on plain decimation.
    bool keep_changes = true;
  };
  struct FixPoint {
    double time_s = 0.0;
    float horizontal_m = 0.0F, up_m = 0.0F;
    float fix_east_m = 0.0F, fix_north_m = 0.0F, truth_east_m = 0.0F, truth_north_m = 0.0F;
    float hdop = 0.0F;
    std::uint8_t satellites_used = 0;
    std::uint8_t type = 0;  // index in kFixTypes order
  };
  // Solution types of one receiver as runs (start time, type index in kFixTypes order).
  struct FixRuns {
    std::string receiver;
    std::vector<std::pair<double, int>> runs;
    double last_time_s = 0.0;
    std::array<std::size_t, 6> epochs_per_type{};
    double first_time_s = std::numeric_limits<double>::quiet_NaN();
    double first_fix_time_s = std::numeric_limits<double>::quiet_NaN();    // first 2D/3D or better
    double first_fixed_time_s = std::numeric_limits<double>::quiet_NaN();  // first rtk_fixed
    bool truncated = false;
    // Fixes compared with the truth.
    std::vector<FixPoint> points;  // thinned: every point_stride-th
    size_t point_stride = 1;
    size_t compared = 0;
    ErrorHistogram horizontal_histogram, vertical_histogram;  // |up| for vertical
    double satellites_used_sum = 0.0, hdop_sum = 0.0;
  };
  struct CountPoint {
    double time_s = 0.0;
    std::array<std::uint16_t, kAllSystems.size()> tracked{};  // per GnssSystem
  };

  // One receiver's satellites: tracks and the tracked count per epoch.
  struct SatelliteView {
    std::string receiver;
    std::map<SatelliteId, Track> tracks;
    std::vector<CountPoint> counts;  // decimated, in time order
    CountPoint pending;              // the epoch being filled
    bool has_pending = false;
    size_t epochs_seen = 0;
    size_t count_stride = 1;
    std::array<bool, kAllSystems.size()> systems_seen{};
  };

 private:
  void flush_pending_epoch(SatelliteView& view) const;
  void compact_track(Track& track) const;
  [[nodiscard]] std::string satellite_sections(const SatelliteView& view, size_t index, const ReportMeta& meta, double t0_s,
                                               double t1_s) const;

  size_t max_points_;
  std::vector<SatelliteView> views_;  // per receiver, in the order first seen
  size_t ignored_samples_ = 0;
  std::vector<FixRuns> fix_runs_;  // per receiver, in the order first seen
};

namespace detail {
// Label of a time-axis tick at time_s (seconds of GPST since the GPS epoch, as the charts count):
// the date when step_s is a day or more, "MM-DD hh:mm" over spans above a day, "hh:mm" for whole-
// minute steps, else "hh:mm:ss". The time is rounded to the second before it is split.
[[nodiscard]] std::string time_axis_label(double time_s, double step_s, double span_s);
}  // namespace detail

}  // namespace skytrace::io
