// Precise orbit and clock products: SP3 orbit files (SP3-a/b/c/d), RINEX clock files (2.0x,
// 3.0x, 3.04 with 9-character names) and a SatelliteStateSource that interpolates them.
//
// Reference point: SP3 positions are those of the satellite centre of mass, whereas broadcast
// orbits of GPS, Galileo, BeiDou and QZSS refer to the antenna phase centre (GLONASS broadcast
// orbits to the centre of mass). The offset is 0 to about 3 m, mostly radial, and depends on the
// satellite block and the frequency. No correction is applied here (no ANTEX file is read): users
// comparing with broadcast orbits or forming observations at the centimetre level must add the
// phase-centre offset themselves.
//
// Clocks: SP3 and RINEX clock values are satellite clock offsets from system time without the
// periodic relativistic term (IGS convention, GLONASS included, unlike GLONASS broadcast clocks);
// PreciseEphemerides reports that term separately as relativistic_s = -2 r.v / c^2 for every
// system, and its rate with the two-body acceleration. SP3 clock-event flags are kept in the
// records but not acted on.
#pragma once

#include <Eigen/Core>

#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "skytrace/core/error.hpp"
#include "skytrace/core/satellite.hpp"
#include "skytrace/core/time.hpp"
#include "skytrace/orbits/satellite_state.hpp"

namespace skytrace::orbits {

// ------------------------------------------------------------------------------------------------
// SP3

// One satellite at one SP3 epoch, converted to SI units (km -> m, microseconds -> s, dm/s -> m/s,
// 1e-4 microseconds/s -> s/s). A value absent from the file or marked missing (position
// 0.000000 or 999999.999999, clock 999999.999999) has its has_* flag false.
struct Sp3Record {
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity_mps = Eigen::Vector3d::Zero();
  double clock_s = 0.0;
  double clock_rate_s_per_s = 0.0;
  bool has_position = false;
  bool has_velocity = false;
  bool has_clock = false;
  bool has_clock_rate = false;
  // Flags of the P record (SP3-c columns 75, 76, 79, 80).
  bool clock_event = false;
  bool clock_predicted = false;
  bool maneuver = false;
  bool orbit_predicted = false;
};

struct Sp3Header {
  char version = 'c';           // 'a', 'b', 'c' or 'd'
  bool has_velocities = false;  // 'V' in the first line: V records follow the P records
  GnssTime first_epoch;         // on the GPST timeline
  int declared_epoch_count = 0; // as written (trimmed files hold fewer)
  std::string data_used;        // "ORBIT", "u+U", ...
  std::string coordinate_system;  // "IGb14", "ITRF2014", ...
  std::string orbit_type;       // "FIT", "EXT", "BCT", "HLM"
  std::string agency;
  double interval_s = 0.0;      // epoch interval from the "##" line
  std::string file_type;        // first "%c" line: "G", "R", "E", "C", "J", "M", ...
  std::string time_system;      // as written: "GPS", "GLO", "GAL", "BDT", "UTC", "TAI", ...
  TimeScale time_scale = TimeScale::kGpst;  // scale the epochs were converted from
  std::vector<SatelliteId> satellites;      // header satellite list (LEOs "Lnn" are skipped)
  std::vector<int> accuracy_exponents;      // per listed satellite: accuracy 2^e mm, 0 = unknown
  std::vector<std::string> comments;        // "/*" lines without the marker
};

// SP3 content of one or more files as one time series on the GPST timeline.
struct Sp3Data {
  std::vector<std::string> sources;  // files read, in merge order
  Sp3Header header;                  // header of the first file
  double interval_s = 0.0;           // nominal epoch spacing (largest of the merged files)
  std::vector<GnssTime> epochs;      // strictly increasing
  std::vector<SatelliteId> satellites;          // sorted; every satellite with any record
  std::vector<std::vector<Sp3Record>> records;  // records[satellite index][epoch index]

  // Records of a satellite aligned with `epochs`, or nullptr when the satellite is absent.
  [[nodiscard]] const std::vector<Sp3Record>* series(const SatelliteId& satellite) const;
  // Number of satellites of a system with at least one position.
  [[nodiscard]] size_t satellite_count(GnssSystem system) const;
  // Adds the epochs and satellites of `other` (e.g. the day before). An epoch present in both
  // keeps this object's record of a satellite when it holds a position, else takes `other`'s.
  void merge(const Sp3Data& other);
};

// Reads an SP3-a/b/c/d file, plain or gzip-compressed. Epochs are converted to GPST from the time
// system of the "%c" line (GPS, GAL, QZS, IRN: as GPST; BDT: +14 s; TAI: -19 s; UTC and GLO: UTC
// with leap seconds, since GLO time tags in IGS formats are UTC(SU) without the 3 h offset).
// Errors name the file, the line and the field.
[[nodiscard]] Result<Sp3Data> read_sp3(const std::filesystem::path& path);
// Reads several SP3 files (e.g. the day before, the day and the day after) and merges them.
[[nodiscard]] Result<Sp3Data> read_sp3(const std::vector<std::filesystem::path>& paths);
// Parses SP3 content held in memory; `name` is used in error messages.
[[nodiscard]] Result<Sp3Data> parse_sp3(const std::string& name, std::string content);

// ------------------------------------------------------------------------------------------------
// RINEX clock

struct ClockSample {
  GnssTime time;          // on the GPST timeline
  double bias_s = 0.0;    // satellite clock offset from system time
  double sigma_s = -1.0;  // formal error when given, else negative
};

struct RinexClockData {
  std::vector<std::string> sources;
  double version = 0.0;
  std::string time_system = "GPS";  // TIME SYSTEM ID as written (GPS when absent)
  TimeScale time_scale = TimeScale::kGpst;
  std::string analysis_center;
  std::vector<SatelliteId> listed_satellites;  // PRN LIST of the header
  // AS records per satellite, sorted by time without duplicates. AR (receiver) records and the
  // other record types are skipped.
  std::map<SatelliteId, std::vector<ClockSample>> satellite_clocks;

  [[nodiscard]] const std::vector<ClockSample>* series(const SatelliteId& satellite) const;
  // Adds the samples of `other`; at a time present in both this object's sample is kept.
  void merge(const RinexClockData& other);
};

// Reads a RINEX clock file (2.0x, 3.0x, 3.04+), plain or gzip-compressed. Times are converted to
// GPST from TIME SYSTEM ID (GPS when absent; GLO read as UTC, as in RINEX). Errors name the file,
// the line and the field.
[[nodiscard]] Result<RinexClockData> read_rinex_clock(const std::filesystem::path& path);
[[nodiscard]] Result<RinexClockData> read_rinex_clock(const std::vector<std::filesystem::path>& paths);
[[nodiscard]] Result<RinexClockData> parse_rinex_clock(const std::string& name, std::string content);

// ------------------------------------------------------------------------------------------------
// Interpolation

// Frame in which the SP3 samples are interpolated.
//
// Measured by leaving out SP3 epochs of real files and interpolating at them (10 points,
// tests/reference/test_precise_real_files.cpp), RMS where the window is centred:
//   15-min spacing (CODE and GFZ 5-min files thinned): Earth-fixed and inertial 0.7-1.2 mm for GPS,
//     GLONASS, BeiDou, QZSS but 4.5-5.7 mm for Galileo (E14/E18, e = 0.16: 4 cm at perigee);
//     inertial + two-body reference 0.7-1.2 mm for every system, which is the 1 mm resolution of
//     the files themselves. Edge intervals (one-sided window): 2-3 mm against up to 5 cm.
//   30-min spacing (GRG thinned): Earth-fixed 1.6 m (GPS 15 cm), inertial 2.0 m (GPS 6 cm),
//     inertial + two-body reference 1.3 cm (GPS 4 mm).
// Earth-fixed interpolation is therefore fine at the mm level for 15-min products of
// near-circular orbits (the Earth rotation only raises the highest frequency of the tabulated
// motion from n to n + omega_E, about 1.5 times), but not for eccentric orbits, coarser spacing
// or near the ends of the data; hence the default below. Extrapolation (allowed up to one
// interval) stays poor with any scheme: 0.1 m RMS at 5-10 min beyond 15-min data, metres at
// 15 min beyond 30-min data. Load the neighbouring days instead.
enum class InterpolationFrame {
  // Interpolate the Earth-fixed coordinates as tabulated.
  kEarthFixed,
  // Rotate every sample about z by the Earth rotation between its epoch and t (into the
  // Earth-fixed frame frozen at t, which is inertial for this purpose), interpolate there and
  // take the velocity relative to the rotating frame.
  kInertial,
};

struct PreciseOptions {
  // Number of samples of the Lagrange polynomial (degree + 1), centred on t: 2..20.
  int interpolation_points = 10;
  InterpolationFrame frame = InterpolationFrame::kInertial;
  // In the inertial frame, interpolate the residuals from the two-body (Keplerian) orbit through
  // a first estimate at t rather than the coordinates themselves (iterated to 0.01 mm).
  bool two_body_reference = true;
  // Interpolate the V records for the velocity when every sample of the window holds one; else
  // the velocity is the derivative of the position polynomial.
  bool use_velocity_records = true;
  // With a clock file: take the SP3 clock for satellites (or times) the clock file lacks. Off by
  // default because mixing clock sources of different analyses biases ranges.
  bool sp3_clock_fallback = false;
};

// Position, velocity and clock from precise products. Positions: Lagrange interpolation over
// `interpolation_points` samples centred on t, refused across missing samples and epoch gaps and
// more than one interval beyond the data. Velocity: derivative of the same polynomial (or the V
// records). Clock: linear interpolation between neighbouring samples at most two intervals apart
// (RINEX clock file when given, else SP3), drift from the same line.
class PreciseEphemerides final : public SatelliteStateSource {
 public:
  [[nodiscard]] static Result<PreciseEphemerides> create(Sp3Data orbits,
                                                         std::optional<RinexClockData> clocks = std::nullopt,
                                                         PreciseOptions options = {});

  struct Orbit {
    Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
    Eigen::Vector3d velocity_mps = Eigen::Vector3d::Zero();
  };
  struct Clock {
    double bias_s = 0.0;
    double drift_s_per_s = 0.0;
  };
  [[nodiscard]] Result<Orbit> orbit(const SatelliteId& satellite, const GnssTime& t) const;
  [[nodiscard]] Result<Clock> clock(const SatelliteId& satellite, const GnssTime& t) const;

  [[nodiscard]] Result<SatelliteState> state(const SatelliteId& satellite, const GnssTime& t) const override;
  // The state of an orbit and clock: with the periodic relativistic term that IGS clocks exclude.
  [[nodiscard]] static SatelliteState state_from(const Orbit& orbit, const Clock& clock);
  // A PreciseOrbitCache over this source.
  [[nodiscard]] std::unique_ptr<SatelliteStateSource> sequential_view() const override;

  // First and last SP3 epoch, and first and last sample of the clock file (any satellite; nullopt
  // without a clock file), on the GPST timeline.
  struct Span {
    GnssTime first;
    GnssTime last;
  };
  [[nodiscard]] Span orbit_span() const;
  [[nodiscard]] std::optional<Span> clock_file_span() const;

  // Where, within [from, to], orbit() or clock() of a satellite fail: spans between the last time
  // that works and the next (clamped to [from, to]), found by evaluating at every sample time of
  // the products in the span and halfway between consecutive ones, plus at from and to (whether a
  // value can be formed changes only at sample times; at the ends of the data the one interval of
  // extrapolation the interpolation allows counts as served). in_orbits / in_clocks: whether the
  // products hold the satellite at all (a satellite they lack fails over all of [from, to]).
  struct Coverage {
    bool in_orbits = false;
    bool in_clocks = false;
    std::vector<Span> orbit_gaps;
    std::vector<Span> clock_gaps;
    [[nodiscard]] bool complete() const { return orbit_gaps.empty() && clock_gaps.empty(); }
  };
  [[nodiscard]] Coverage coverage(const SatelliteId& satellite, const GnssTime& from, const GnssTime& to) const;
  // Satellites with positions (and, with a clock file and no fallback, with clock samples).
  [[nodiscard]] std::vector<SatelliteId> satellites() const override;
  [[nodiscard]] std::string_view name() const override { return "precise"; }

  [[nodiscard]] const Sp3Data& orbits() const { return orbits_; }
  [[nodiscard]] const std::optional<RinexClockData>& clocks() const { return clocks_; }
  [[nodiscard]] const PreciseOptions& options() const { return options_; }

 private:
  PreciseEphemerides(Sp3Data orbits, std::optional<RinexClockData> clocks, PreciseOptions options);

  [[nodiscard]] Result<Clock> sp3_clock(const SatelliteId& satellite, const GnssTime& t) const;
  [[nodiscard]] Result<Clock> file_clock(const SatelliteId& satellite, const std::vector<ClockSample>& samples,
                                         const GnssTime& t) const;
  [[nodiscard]] std::string orbit_coverage() const;

  Sp3Data orbits_;
  std::optional<RinexClockData> clocks_;
  PreciseOptions options_;
  // Clock file: per-satellite nominal sample spacing and the span of the whole file.
  std::map<SatelliteId, double> clock_interval_s_;
  GnssTime clock_first_;
  GnssTime clock_last_;
};

}  // namespace skytrace::orbits
