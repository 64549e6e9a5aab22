// A nominal multi-GNSS constellation built from the published constellation designs, as broadcast
// navigation records, so that a scenario runs without any downloaded navigation file.
//
// The orbits are Keplerian (circular, except QZSS quasi-zenith orbits) and physically consistent:
// evaluating a generated record with the ICD algorithm gives the designed radius, inclination and
// period, and geostationary satellites stay over their longitude. They are not the real satellites
// of any day. Sources of the designs:
//   GPS      GPS SPS Performance Standard (5th ed., April 2020; same table since the 2001 edition):
//            baseline 24-slot constellation, RAAN and argument of latitude of slots A1..F4 at the
//            defined epoch 1993-07-01 00:00 UTC, Greenwich hour angle 18h36m14.4s; a = 26559.7 km,
//            i = 55 deg, e = 0 (D3 is 35.156 deg; some books print 35.136). Slots A1..F4 carry PRNs
//            G01..G24 in that order.
//            The node is given the regression that keeps each slot's ground track repeating every
//            two revolutions (about -9.3e-9 rad/s, close to the real J2 regression), so the table
//            holds at any date as GPS station-keeping keeps it.
//   Galileo  Walker 24/3/1, a = 29600 km, i = 56 deg (Galileo OS SDD, reference constellation);
//            E01..E24, plane A/B/C = E01-08/E09-16/E17-24; node regression for the 17-revolution /
//            10-day ground-track repeat. The phase of the pattern against the Earth is arbitrary.
//   BeiDou   BDS-3 as described by the China Satellite Navigation Office:
//            24 MEO in Walker 24/3/1, a = 27906 km, i = 55 deg, PRNs C19-C30, C32-C37, C41-C46
//            (13-revolution / 7-day repeat); 3 IGSO C38-C40, a geosynchronous, i = 55 deg, one
//            figure-8 ground track crossing the equator at 118 E, 120 deg apart; 3 GEO C59 at
//            140 E, C60 at 80 E, C61 at 110.5 E. GEO records use the BDS-SIS-ICD GEO convention
//            (elements in a frame tilted by 5 deg) and the D2 message; the others D1.
//   GLONASS  GLONASS ICD Edition 5.1 (2008): 24 slots in 3 planes 120 deg apart, 8 slots 45 deg
//            apart in argument of latitude, planes shifted by 15 deg, a = 25510 km, i = 64.8 deg;
//            slots 1-8 plane 1, 9-16 plane 2, 17-24 plane 3, numbered against the direction of
//            motion. Frequency channels per slot as assigned by the GLONASS IAC (antipodal slots k
//            and k+4 share a channel): 1:+1 2:-4 3:+5 4:+6 9:-2 10:-7 11:0 12:-1 17:+4 18:-3 19:+3
//            20:+2 (as in the ESBC00DNK 2020-06-25 navigation file).
//            State vectors every 30 min (t_b at hh:15 and hh:45 UTC), lunisolar acceleration 0: the
//            Keplerian design state at the first t_b (speed trimmed so that the mean radius under
//            J2 is the design's; the radius then stays within 0.92 km of it), each later state
//            integrated from the previous record as receivers do (PZ-90 with J2, evaluate_glonass),
//            so neighbouring records join within a millimetre (design states at every t_b would
//            jump by ~15 m at each switch). The GLONASS orbits follow the design at the start of
//            the span and drift from it by J2 (node about -0.03 deg/day) over it.
//   QZSS     qzss.go.jp "Quasi-Zenith Satellite Orbit" and JAXA's QZS-1 orbit report (2010-09-27):
//            3 quasi-zenith orbits J01-J03 (a geosynchronous, e = 0.075, i = 41 deg, argument of
//            perigee 270 deg, figure-8 centred on 135 E, 8 h apart on one ground track) and the
//            QZS-3 GEO J07 at 127 E.
//   NavIC    NavIC SPS ICD (ISRO, 2017): GEO I03 at 83 E, I06 at 32.5 E, I07 at 131.5 E; IGSO
//            (i = 29 deg) I01, I02 crossing the equator at 55 E and I04, I05 at 111.75 E. ISRO has
//            published no phasing of the two IGSOs sharing a ground track; they are a quarter of a
//            sidereal day apart here.
// Ionosphere: GPS Klobuchar coefficients broadcast on 2004-01-01 (a moderately active day; the
// default set of RTKLIB's ionmodel).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "skytrace/core/error.hpp"
#include "skytrace/core/satellite.hpp"
#include "skytrace/core/time.hpp"
#include "skytrace/orbits/ephemeris.hpp"

namespace skytrace::orbits {

enum class NominalOrbitType : std::uint8_t { kMeo, kIgso, kGeo, kQzo };

// The design orbit of one satellite: Keplerian elements whose node moves at a constant inertial
// rate. Angles of the node are Earth-fixed longitudes, so the design is tied to the Earth's
// rotation (mean motion from the system's GM, Earth rotation rate of the system's ICD).
struct NominalOrbit {
  SatelliteId satellite;
  NominalOrbitType type = NominalOrbitType::kMeo;
  std::string slot;  // "A1", "plane 2 slot 3", "GEO 140.0E", "IGSO 118.0E"
  double semi_major_axis_m = 0.0;
  double eccentricity = 0.0;
  double inclination_rad = 0.0;
  double argument_of_perigee_rad = 0.0;
  GnssTime reference_epoch;
  // Earth-fixed longitude of the ascending node and mean anomaly at reference_epoch.
  double node_longitude_rad = 0.0;
  double mean_anomaly_rad = 0.0;
  double node_rate_rad_per_s = 0.0;  // inertial rate of the node (broadcast OMEGA DOT)
  double gm_m3ps2 = 0.0;
  double earth_rotation_radps = 0.0;
  int glonass_channel = 0;  // GLONASS only

  [[nodiscard]] double mean_motion_rad_per_s() const;
};

// Earth-fixed position and velocity of a design orbit (pure Keplerian motion plus node rate).
struct NominalState {
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity_mps = Eigen::Vector3d::Zero();
};

// The design orbits of the given systems (SBAS has none), in system and satellite order.
[[nodiscard]] std::vector<NominalOrbit> nominal_orbits(const std::vector<GnssSystem>& systems);
[[nodiscard]] NominalState nominal_state(const NominalOrbit& orbit, const GnssTime& t);

// The systems with a nominal constellation: G R E C J I.
[[nodiscard]] std::vector<GnssSystem> nominal_systems();

struct NominalConstellationOptions {
  std::vector<GnssSystem> systems = nominal_systems();
  // Seed of the per-satellite clock polynomials and group delays (same seed, same records).
  std::uint64_t seed = 1;
  // Records cover [start - margin, start + duration + margin] (Galileo from its last toe before,
  // as a Galileo record is only used after its toe).
  double margin_s = 7200.0;
};

// Broadcast records of the nominal constellation: Keplerian records every 2 h (GPS LNAV, Galileo
// I/NAV with data source 517 and F/NAV with 258, QZSS LNAV, NavIC LNAV; BeiDou D1/D2 every hour),
// GLONASS state vectors every 30 min, all healthy, with small clock polynomials (bias within
// +-0.3 ms, drift within +-5e-12 s/s, continuous across records) and group delays within +-10 ns;
// GPS Klobuchar coefficients and GPS - UTC of `start`. Errors: a non-finite or negative duration
// or margin, a span longer than 366 days, or SBAS among the systems.
[[nodiscard]] Result<NavigationData> make_nominal_constellation(
    const GnssTime& start, double duration_s, const NominalConstellationOptions& options = {});

}  // namespace skytrace::orbits
