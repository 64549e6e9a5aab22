// RTCM 3.3 (RTCM 10403.3) output: transport framing with CRC-24Q, station messages 1005/1006,
// MSM7 observations (1077 GPS, 1087 GLONASS, 1097 Galileo, 1117 QZSS, 1127 BeiDou) and broadcast
// ephemerides (1019 GPS, 1020 GLONASS, 1042 BeiDou, 1044 QZSS, 1045 Galileo F/NAV, 1046 Galileo
// I/NAV). The observation input is a neutral struct, so io needs no receiver types.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <span>
#include <string>
#include <vector>

#include "skytrace/core/error.hpp"
#include "skytrace/core/satellite.hpp"
#include "skytrace/core/signal.hpp"
#include "skytrace/core/time.hpp"
#include "skytrace/positioning/spp.hpp"
#include "skytrace/orbits/ephemeris.hpp"

namespace skytrace::io {

// ---- Bits and frames ----------------------------------------------------------------------------

// CRC-24Q (polynomial 0x1864CFB, initial value 0) over the bytes, as RTCM 3 and SBAS use it.
[[nodiscard]] std::uint32_t crc24q(std::span<const std::uint8_t> bytes);

// Big-endian bit packing of RTCM data fields, most significant bit first.
class BitWriter {
 public:
  void put_unsigned(std::uint64_t value, int bits);
  // Two's complement.
  void put_signed(std::int64_t value, int bits);
  // Sign bit then magnitude (GLONASS fields DF111-DF135 are coded this way).
  void put_sign_magnitude(std::int64_t value, int bits);
  [[nodiscard]] size_t bit_count() const { return bits_; }
  // The bytes written so far, the last one padded with zero bits.
  [[nodiscard]] const std::vector<std::uint8_t>& bytes() const { return bytes_; }

 private:
  std::vector<std::uint8_t> bytes_;
  size_t bits_ = 0;
};

// Reading fields back (tests, stream checks). A field of 0 bits (or fewer) reads nothing and is 0.
class BitReader {
 public:
  explicit BitReader(std::span<const std::uint8_t> bytes) : bytes_(bytes) {}
  [[nodiscard]] std::uint64_t get_unsigned(int bits);
  [[nodiscard]] std::int64_t get_signed(int bits);
  [[nodiscard]] std::int64_t get_sign_magnitude(int bits);
  [[nodiscard]] size_t position() const { return position_; }
  // Whether a read went past the end (the values read there are 0 bits).
  [[nodiscard]] bool overrun() const { return overrun_; }

 private:
  std::span<const std::uint8_t> bytes_;
  size_t position_ = 0;
  bool overrun_ = false;
};

// One transport frame: 0xD3, 6 reserved zero bits, 10-bit length, the message, CRC-24Q.
// The message must not exceed 1023 bytes.
[[nodiscard]] Result<std::vector<std::uint8_t>> rtcm3_frame(std::span<const std::uint8_t> message);

// A frame found in a byte stream.
struct Rtcm3Frame {
  int message_number = 0;
  std::vector<std::uint8_t> message;  // without header and CRC
};
// Splits a byte stream into frames, skipping bytes until a preamble with a correct CRC.
[[nodiscard]] std::vector<Rtcm3Frame> rtcm3_split_frames(std::span<const std::uint8_t> stream);

// ---- Station ------------------------------------------------------------------------------------

struct RtcmStation {
  int station_id = 0;                                           // 0-4095
  Eigen::Vector3d arp_ecef_m = Eigen::Vector3d::Zero();         // antenna reference point
  double antenna_height_m = 0.0;                                // ARP above the marker (1006)
  bool gps = true, glonass = true, galileo = true;              // service indicators
  bool single_receiver_oscillator = true;                       // DF142: all signals share one clock
};
// Message 1005 (no height) or 1006 (with antenna height), framed.
[[nodiscard]] Result<std::vector<std::uint8_t>> rtcm3_station(const RtcmStation& station, int message_number = 1006);

// ---- MSM7 observations --------------------------------------------------------------------------

// One signal as a receiver reports it. Absent values are sent as "invalid".
struct RtcmSignalObservation {
  Signal signal;
  std::optional<double> pseudorange_m;
  std::optional<double> phase_cycles;  // sign of the pseudorange (RINEX convention)
  std::optional<double> doppler_hz;    // positive for an approaching satellite
  double cn0_dbhz = 0.0;               // 0: not given
  double lock_time_s = 0.0;            // continuous carrier tracking time
  bool half_cycle = false;             // half-cycle ambiguity not resolved
};

struct RtcmSatelliteObservation {
  SatelliteId satellite;
  int glonass_channel = 0;  // frequency channel k (GLONASS only)
  std::vector<RtcmSignalObservation> signals;
};

struct RtcmEpoch {
  GnssTime time;  // epoch tag (receiver clock, GPST)
  std::vector<RtcmSatelliteObservation> satellites;
};

// The MSM message family base of a system (1070 GPS, 1080 GLONASS, 1090 Galileo, 1110 QZSS,
// 1120 BeiDou), nullopt for systems without MSM (NavIC in RTCM 3.3, SBAS: 1100 family not sent).
[[nodiscard]] std::optional<int> msm_base(GnssSystem system);
// The RTCM 3.3 MSM signal ID (1-32) of a signal, nullopt when the table has none.
[[nodiscard]] std::optional<int> msm_signal_id(const Signal& signal);
// The DF407 lock-time indicator (extended resolution, 0-704) for a lock time, and its minimum lock
// time in seconds.
[[nodiscard]] int msm_lock_time_indicator(double lock_time_s);
[[nodiscard]] double msm_lock_time_min_s(int indicator);

// Encodes epochs into MSM7 messages. Keeps, per carrier arc, the integer number of cycles taken off
// the phase so that the phase range stays within DF406's +-1171 m of the rough range: RTCM phase
// ranges have an arbitrary but constant ambiguity per arc. When code and carrier drift apart beyond
// that, the offset is renewed and the lock time restarts (a receiver signals a slip the same way).
class Msm7Encoder {
 public:
  explicit Msm7Encoder(int station_id) : station_id_(station_id) {}

  // The framed messages of one epoch: per system GPS, GLONASS, Galileo, QZSS, BeiDou (split when
  // more than 64 cells or 1023 bytes), the multiple-message bit set on all but the last.
  [[nodiscard]] Result<std::vector<std::vector<std::uint8_t>>> encode(const RtcmEpoch& epoch);
  // Signals left out because RTCM 3.3 has no MSM ID for them, or the system no MSM.
  [[nodiscard]] const std::set<Signal>& dropped_signals() const { return dropped_; }

 private:
  struct Arc {
    std::int64_t offset_cycles = 0;
    double last_lock_time_s = 0.0;
    GnssTime offset_since;  // the lock time reported is at most the time since the offset was set
  };
  int station_id_ = 0;
  std::map<std::pair<SatelliteId, Signal>, Arc> arcs_;
  std::set<Signal> dropped_;
};

// ---- Ephemerides --------------------------------------------------------------------------------

// 1019 (GPS LNAV), 1042 (BeiDou D1/D2), 1044 (QZSS LNAV), 1045 (Galileo F/NAV), 1046 (Galileo
// I/NAV), framed. CNAV records and NavIC have no message here (kUnsupported).
[[nodiscard]] Result<std::vector<std::uint8_t>> rtcm3_ephemeris(const orbits::KeplerEphemeris& ephemeris);
// 1020, framed.
[[nodiscard]] Result<std::vector<std::uint8_t>> rtcm3_ephemeris(const orbits::GlonassEphemeris& ephemeris);
// The message number a record is sent in, nullopt when none.
[[nodiscard]] std::optional<int> rtcm3_ephemeris_message(const orbits::KeplerEphemeris& ephemeris);

// ---- A stream -----------------------------------------------------------------------------------

struct Rtcm3StreamSettings {
  int station_id = 0;
  double station_interval_s = 10.0;    // 1006 at the first epoch and then at this interval
  double ephemeris_interval_s = 60.0;  // a record in use is sent when new, then at this interval
};

// What a reference receiver streams: 1006, MSM7 of every epoch, and the ephemerides in use.
class Rtcm3Stream {
 public:
  Rtcm3Stream(Rtcm3StreamSettings settings, RtcmStation station);

  // The bytes of one epoch. `kepler` and `glonass` are the records in use (sent when first seen,
  // then the newest of each satellite again at the interval); records without an RTCM message are
  // skipped.
  [[nodiscard]] Result<std::vector<std::uint8_t>> epoch(const RtcmEpoch& observations,
                                                        std::span<const orbits::KeplerEphemeris* const> kepler,
                                                        std::span<const orbits::GlonassEphemeris* const> glonass);
  [[nodiscard]] const std::set<Signal>& dropped_signals() const { return msm_.dropped_signals(); }

 private:
  Rtcm3StreamSettings settings_;
  RtcmStation station_;
  Msm7Encoder msm_;
  std::optional<GnssTime> last_station_;
  // Per record: when it was last sent.
  std::map<const void*, GnssTime> sent_;
};

// ---- Decoding -----------------------------------------------------------------------------------

// The signal of an MSM signal ID (1-32) of a system, nullopt when RTCM 3.3 defines none.
[[nodiscard]] std::optional<Signal> msm_signal(GnssSystem system, int signal_id);

// Reads what a reference station streams: 1005/1006 (its antenna reference point) and MSM4-MSM7
// observations of GPS, GLONASS, Galileo, QZSS and BeiDou, gathered into epochs (the MSMs of one
// instant end with the one whose multiple-message bit is 0, or at the next instant). Frames are
// found in any byte stream (garbage between them, frames split across feed() calls, bad CRCs
// skipped and counted); other messages are counted and ignored.
class Rtcm3Decoder {
 public:
  // `reference`: an instant within half a week of the data, to place GPS/Galileo/BeiDou times of
  // week and GLONASS days (e.g. the start of the navigation data or of the rover's observations).
  explicit Rtcm3Decoder(GnssTime reference) : reference_(reference) {}
  void feed(std::span<const std::uint8_t> bytes);
  // The epoch being gathered, when the stream ends.
  void finish();
  // Complete epochs in stream order since the last call.
  [[nodiscard]] std::vector<RtcmEpoch> take_epochs();
  [[nodiscard]] const std::optional<RtcmStation>& station() const { return station_; }

  struct Counts {
    size_t frames = 0;              // with a good CRC
    size_t msm_messages = 0;
    size_t station_messages = 0;
    size_t other_messages = 0;      // ephemerides, 1230, ... (not used)
    size_t malformed_messages = 0;  // shorter than their masks and fields say
    size_t unknown_signal_cells = 0;  // MSM cells of signal IDs RTCM 3.3 (or skytrace) does not define
    size_t skipped_bytes = 0;       // garbage and frames with a bad CRC
  };
  [[nodiscard]] const Counts& counts() const { return counts_; }

 private:
  void decode(std::span<const std::uint8_t> message, int message_number);
  void decode_station(std::span<const std::uint8_t> message, int message_number);
  void decode_msm(std::span<const std::uint8_t> message, int message_number);
  GnssTime reference_;
  std::vector<std::uint8_t> pending_;  // bytes not yet part of a complete frame
  std::optional<RtcmEpoch> current_;
  std::vector<RtcmEpoch> done_;
  std::optional<RtcmStation> station_;
  Counts counts_;
};

// A reference station's epochs as the position engines take them. The loss-of-lock flag comes from
// the lock time, as RTKLIB derives it: set when a signal's lock time is shorter than at its previous
// epoch, or when the signal is new.
class RtcmMeasurementConverter {
 public:
  [[nodiscard]] positioning::EpochMeasurements convert(const RtcmEpoch& epoch);

 private:
  std::map<std::pair<SatelliteId, Signal>, double> last_lock_time_s_;
};

}  // namespace skytrace::io
