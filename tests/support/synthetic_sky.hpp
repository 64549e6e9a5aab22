// A synthetic sky for positioning tests: Keplerian records that put satellites in chosen directions
// from a site at a chosen epoch, and an exact light-time forward model of their own, so that a
// solver must return the truth to numerical precision.
#pragma once

#include <cmath>
#include <numbers>

#include "skytrace/atmosphere/models.hpp"
#include "skytrace/core/constants.hpp"
#include "skytrace/core/frames.hpp"
#include "skytrace/orbits/broadcast.hpp"

namespace skytrace::test::synthetic {

constexpr double kC = constants::kSpeedOfLight_mps;
constexpr double kOmega = constants::kEarthRotationRateGps_radps;
constexpr double kRad = std::numbers::pi / 180.0;

inline const GnssTime kToe = GnssTime::from_week_tow(TimeScale::kGpst, 2100, 0.0);
inline const GnssTime kTag = kToe + 10.0;  // Galileo records must be older than the epoch
inline const Geodetic kSite{48.1, 11.6, 520.0};

struct SkyPoint {
  double azimuth_deg, elevation_deg;
};

// A polar circular (or slightly eccentric) orbit that puts the satellite in direction `sky` from
// kSite, 20200 km away, at kTag minus a typical flight time.
inline orbits::KeplerEphemeris make_ephemeris(SatelliteId sat, SkyPoint sky, double eccentricity = 0.0) {
  const Eigen::Vector3d site = geodetic_to_ecef(kSite);
  const double az = sky.azimuth_deg * kRad, el = sky.elevation_deg * kRad;
  const Eigen::Vector3d enu(std::cos(el) * std::sin(az), std::cos(el) * std::cos(az), std::sin(el));
  // Range such that the satellite is on a sphere of radius 26560 km.
  const Eigen::Vector3d d = enu_to_ecef(enu, kSite) - site;
  const double b = site.dot(d), radius = 26560e3;
  const double range = -b + std::sqrt(b * b - site.squaredNorm() + radius * radius);
  const Eigen::Vector3d target = site + range * d;
  const double tk = (kTag - kToe) - range / kC;
  orbits::KeplerEphemeris e;
  e.satellite = sat;
  e.message = sat.system == GnssSystem::kGalileo ? orbits::NavMessage::kGalileoInav : orbits::NavMessage::kGpsLnav;
  e.toc = e.toe = kToe;
  e.week = 2100;
  e.toe_sow = 0.0;
  e.af0_s = 1e-5 * (sat.number % 7 - 3);
  e.af1_s_per_s = 1e-11 * (sat.number % 5 - 2);
  e.sqrt_a_sqrtm = std::sqrt(radius);
  e.eccentricity = eccentricity;
  e.i0_rad = std::numbers::pi / 2.0;
  const double gm = sat.system == GnssSystem::kGalileo ? constants::kGmGalileo_m3ps2 : constants::kGmGps_m3ps2;
  const double n = std::sqrt(gm / (radius * radius * radius));
  e.m0_rad = std::asin(target.z() / target.norm()) - n * tk;
  e.omega0_rad = std::atan2(target.y(), target.x()) + kOmega * tk;
  e.group_delays.tgd_s = 4e-9 * (sat.number % 3);
  e.group_delays.bgd_e1e5b_s = 2e-9;
  e.group_delays.bgd_e1e5a_s = 1.5e-9;
  e.accuracy_m = 2.0;
  return e;
}

struct Truth {
  Eigen::Vector3d position_m = geodetic_to_ecef(kSite);
  Eigen::Vector3d velocity_mps = Eigen::Vector3d::Zero();
  double clock_s = 1e-4;              // receiver clock against GPST
  double drift_s_per_s = 2e-8;
  double galileo_offset_s = 25e-9;    // inter-system bias of Galileo
  bool atmosphere = false;
};

inline const orbits::KlobucharCoefficients kKlobuchar{{1.1176e-08, 7.4506e-09, -5.9605e-08, -5.9605e-08},
                                               {9.0112e+04, 1.6384e+04, -1.9661e+05, -6.5536e+04}};

// Geometric range at true reception time t for a receiver at r: light time by fixed-point iteration,
// the satellite taken at transmission and rotated into the frame at reception.
inline double light_time_range(const orbits::KeplerEphemeris& eph, const GnssTime& t, const Eigen::Vector3d& r,
                        orbits::SatelliteState* state, Eigen::Vector3d* rotated) {
  double tau = 0.07;
  double range = 0.0;
  for (int i = 0; i < 20; ++i) {
    *state = orbits::evaluate_kepler(eph, t - tau);
    const double a = kOmega * tau;
    *rotated = Eigen::Vector3d(std::cos(a) * state->position_m.x() + std::sin(a) * state->position_m.y(),
                               -std::sin(a) * state->position_m.x() + std::cos(a) * state->position_m.y(),
                               state->position_m.z());
    range = (*rotated - r).norm();
    tau = range / kC;
  }
  return range;
}

}  // namespace skytrace::test::synthetic
