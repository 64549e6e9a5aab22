// A live receiver (sim::LiveSession) behind an interface of plain C++17 types. ROS 1's generated
// messages do not compile as C++20 (they use std::allocator<void>::rebind, removed in C++20) while
// skytrace's headers need C++20, so the ROS node and its tests are C++17 code that reaches the
// simulator only through this header. Times are seconds after the receiver's start time.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace skytrace::sim {
class LiveSession;
struct LiveEpoch;
class EpochSink;
}  // namespace skytrace::sim

namespace skytrace::live {

using Vec3 = std::array<double, 3>;
using Mat3 = std::array<double, 9>;  // row-major

struct SignalView {
  std::string code;  // RINEX 3 observation code: "1C", "5Q"
  double carrier_hz = 0.0;
  double pseudorange_m = 0.0;
  double carrier_phase_cycles = 0.0;
  double doppler_hz = 0.0;
  double cn0_dbhz = 0.0;
  bool loss_of_lock = false;
  bool half_cycle_unresolved = false;
  double lock_time_s = 0.0;
};

enum class SkyStatus { kTracked, kBelowMask, kNoEphemeris, kNoSignal, kBlocked, kAttenuated };

struct SatelliteView {
  std::string id;   // "G05"
  char system = 'G';
  int prn = 0;      // ranging-code PRN (GLONASS: slot)
  int glonass_channel = 0;
  SkyStatus status = SkyStatus::kTracked;
  std::string detail;  // why it is not tracked (the blocking object, ...)
  double azimuth_deg = 0.0;
  double elevation_deg = 0.0;
  double vegetation_path_m = 0.0;
  double vegetation_attenuation_db = 0.0;
  bool nlos = false;       // tracked on reflected or diffracted paths only (models.multipath)
  bool multipath = false;  // the direct path with reflections beside it
  bool used_in_fix = false;
  Vec3 direction_world{};  // unit vector from the antenna to the satellite, world frame
  std::vector<SignalView> signals;  // tracked signals
};

struct FixView {
  int type = 0;  // 0 none, 2 2D, 3 3D
  // The solution: "none", "2d", "3d", "dgnss", "rtk_float", "rtk_fixed" (fix.csv's fix column).
  std::string solution = "none";
  // Differential or RTK: corrections of a base in the solution (NavSatFix STATUS_GBAS_FIX).
  bool differential = false;
  std::string message;
  double latitude_deg = 0.0;
  double longitude_deg = 0.0;
  double height_m = 0.0;  // above the WGS84 ellipsoid
  Mat3 covariance_enu_m2{};
  bool velocity_valid = false;
  Vec3 velocity_enu_mps{};
  Mat3 velocity_covariance_enu_m2ps2{};
  int satellites_used = 0;
  std::string systems_used;  // RINEX letters of the constellations in the solution, e.g. "GREC"
};

struct EpochView {
  double time_s = 0.0;  // seconds after the start time
  int gps_week = 0;     // the receiver time tag in GPST
  double gps_tow_s = 0.0;
  std::string time_iso;  // the tag, ISO 8601 GPST
  bool restarted = false;
  bool pose_stale = false;
  Vec3 antenna_world_m{};  // true antenna position, world frame
  std::vector<SatelliteView> satellites;  // every satellite of the receiver's systems
  FixView fix;
  std::vector<std::string> nmea;  // the epoch's NMEA sentences, without CR LF
};

// SIGINT and SIGTERM for a live loop (core/cancellation's install_live_stop_handlers): they ask the
// loop to stop (stop_requested()), and a watchdog ends the process should the loop not end within a
// second. disarm_stop_watchdog() once the loop has ended, before the outputs are finished.
void install_stop_handlers();
[[nodiscard]] bool stop_requested();
void disarm_stop_watchdog();

struct ReceiverOptions {
  std::string scenario_path;
  std::string start_time;                // ISO 8601; empty: the scenario's start
  std::string start_time_scale = "GPST";
  double pose_timeout_s = 1.0;
  std::string receiver_name;  // one receiver of a scenario with several; empty: the first
  // RTK: the fixes come from the RTK engine with the base corrections given to add_base_rtcm3()
  // or read from `rtk_base`.
  bool rtk = false;
  // RTK from a base's RTCM 3 stream: HOST:PORT or ntrip://[USER[:PASSWORD]@]HOST[:PORT]/MOUNTPOINT
  // (sim::RtkBaseLink), read before every step; sets rtk.
  std::string rtk_base;
  // Where the link's messages go (connected, refused, ...): level 0 info, 1 warning, 2 error.
  std::function<void(int, const std::string&)> log;
};

class Receiver {
 public:
  // nullptr with `error` set (naming the file or option) when the scenario cannot be loaded.
  [[nodiscard]] static std::unique_ptr<Receiver> create(const ReceiverOptions& options, std::string& error);
  ~Receiver();
  Receiver(const Receiver&) = delete;
  Receiver& operator=(const Receiver&) = delete;

  // The antenna reference point at `time_s`, world frame. Returns an error message, empty when used.
  // Thread-safe with respect to step().
  [[nodiscard]] std::string set_antenna_pose_world(double time_s, const Vec3& position_m,
                                                   const std::optional<Vec3>& velocity_mps = std::nullopt);
  // A moving base's antenna (the receiver's rtk.moving_base: two antennas on one body, the fix
  // then carries the heading of the baseline), as set_antenna_pose_world. An error message when
  // the receiver has no moving base.
  [[nodiscard]] std::string set_base_antenna_pose_world(double time_s, const Vec3& position_m,
                                                        const std::optional<Vec3>& velocity_mps = std::nullopt);
  [[nodiscard]] bool has_moving_base() const;
  // A movable model of the world; quaternion w, x, y, z. Returns an error message, empty when used.
  [[nodiscard]] std::string set_object_pose(const std::string& name, const Vec3& position_m,
                                            const std::array<double, 4>& rotation_wxyz);

  // The epoch at `time_s` (a time before the previous one restarts tracking). False with `error`.
  [[nodiscard]] bool step(double time_s, EpochView& out, std::string& error);
  // The same without the view, for C++20 callers that read last_epoch() (the ROS 2 node).
  [[nodiscard]] bool step(double time_s, std::string& error);

  // The simulator behind the view, for C++20 callers (they include skytrace/sim/live.hpp): the
  // session, and the epoch of the last step (nullptr before the first).
  [[nodiscard]] const sim::LiveSession& session() const;
  [[nodiscard]] const sim::LiveEpoch* last_epoch() const;

  // RTCM 3 bytes of a base station (any framing: messages are found in the bytes), for RTK. Returns
  // a note when something is wrong with the stream (no 1005/1006 yet), empty otherwise.
  [[nodiscard]] std::string add_base_rtcm3(const std::uint8_t* bytes, size_t size);

  // Outputs of the receiver, every one a sink of its epochs (sim::LiveOutputs): the publishers
  // added below, and the files named by parameters (file_parameters(): name and description,
  // e.g. "rinex_out"; empty paths are left out). Opened once, before the first step; returns an
  // error message naming the parameter, empty when opened.
  [[nodiscard]] static std::vector<std::pair<std::string, std::string>> file_parameters();
  [[nodiscard]] std::string open_outputs(const std::vector<std::pair<std::string, std::string>>& parameter_paths,
                                         double interval_s);
  // A publisher of C++17 code (the ROS 1 node): called with the view of every epoch. After open_outputs().
  void add_publisher(std::function<void(const EpochView&)> publish);
  // A publisher of C++20 code (the ROS 2 node). After open_outputs().
  void add_publisher(std::unique_ptr<sim::EpochSink> publisher);
  // Steps and hands the epoch to the outputs; `notes` receives what did not stop the receiver
  // (an epoch left out of the files, a file given up after a write error).
  [[nodiscard]] bool step_outputs(double time_s, std::string& error, std::vector<std::string>& notes);
  struct FinishedOutputs {
    std::vector<std::string> written;  // "rinex_out /path/obs.rnx"
    std::vector<std::string> errors;
  };
  // Completes the files and moves them into place.
  [[nodiscard]] FinishedOutputs finish_outputs();

  // Coordinates in the world frame (the Gazebo world's, or east-north-up at the first marker).
  [[nodiscard]] Vec3 world_from_geodetic(double latitude_deg, double longitude_deg, double height_m) const;
  [[nodiscard]] Vec3 world_from_ecef(const Vec3& ecef_m) const;
  // Seconds after the start time of a GPST week and time of week (message time tags).
  [[nodiscard]] double time_s_of_gps(int gps_week, double gps_tow_s) const;
  [[nodiscard]] std::string scenario_name() const;
  // Warnings from loading the scenario (e.g. satellites the precise products lack), for the log.
  [[nodiscard]] std::vector<std::string> warnings() const;
  [[nodiscard]] double scenario_duration_s() const;

 private:
  struct Impl;
  explicit Receiver(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace skytrace::live
