// Broadcast ephemeris evaluation, group delays and ephemeris selection.
//
// Real records are copied by hand from the ESBC00DNK_R_20201770000_01D_MN.rnx navigation file of
// 2020-06-25 (shared data, real/esbc_2020177) and checked against the GRGS final orbit of the same
// day (GRG0MGXFIN_20201770000_01D_15M_ORB.SP3, GPST, centre of mass): broadcast orbits agree with
// precise ones to a few metres (antenna offsets and broadcast orbit error).
#include <Eigen/Geometry>

#include <cmath>
#include <numbers>

#include "skytrace/core/constants.hpp"
#include "skytrace/orbits/broadcast.hpp"
#include "test_support.hpp"

namespace skytrace::orbits {
namespace {

namespace k = skytrace::constants;

GnssTime gpst(int year, int month, int day, int hour, int minute, double second) {
  return GnssTime::from_calendar(CalendarTime{year, month, day, hour, minute, second}, TimeScale::kGpst);
}

// G07, toc = toe = 2020-06-25 12:00:00 GPST (GPS week 2111, toe 388800 s).
KeplerEphemeris gps_g07() {
  KeplerEphemeris e;
  e.satellite = SatelliteId{GnssSystem::kGps, 7};
  e.message = NavMessage::kGpsLnav;
  e.toc = GnssTime::from_week_tow(TimeScale::kGpst, 2111, 388800.0);
  e.toe = e.toc;
  e.week = 2111;
  e.toe_sow = 388800.0;
  e.af0_s = -3.125914372504e-04;
  e.af1_s_per_s = -8.753886504564e-12;
  e.iode = 36;
  e.crs_m = 3.750000000000e-01;
  e.delta_n_rad_per_s = 5.106998441270e-09;
  e.m0_rad = -2.196298569634e+00;
  e.cuc_rad = -2.980232238770e-07;
  e.eccentricity = 1.403154002037e-02;
  e.cus_rad = 5.675479769707e-06;
  e.sqrt_a_sqrtm = 5.153651992798e+03;
  e.cic_rad = 2.533197402954e-07;
  e.omega0_rad = -5.655694076531e-01;
  e.cis_rad = -8.381903171539e-08;
  e.i0_rad = 9.530046994424e-01;
  e.crc_m = 2.629687500000e+02;
  e.omega_rad = -2.385949900139e+00;
  e.omega_dot_rad_per_s = -8.173197589343e-09;
  e.idot_rad_per_s = 1.078616357272e-10;
  e.accuracy_m = 2.0;
  e.group_delays.tgd_s = -1.117587089539e-08;
  e.iodc = 36;
  e.fit_interval_h = 4.0;
  return e;
}

// E01 I/NAV (data source 517) and F/NAV (258) of 2020-06-25 12:00:00 GPST, week 2111.
KeplerEphemeris galileo_e01(NavMessage message) {
  KeplerEphemeris e;
  e.satellite = SatelliteId{GnssSystem::kGalileo, 1};
  e.message = message;
  e.toc = GnssTime::from_week_tow(TimeScale::kGpst, 2111, 388800.0);
  e.toe = e.toc;
  e.week = 2111;
  e.toe_sow = 388800.0;
  const bool inav = message == NavMessage::kGalileoInav;
  e.af0_s = inav ? -8.850500453264e-04 : -8.850492304191e-04;
  e.af1_s_per_s = -7.929656931083e-12;
  e.iode = 8;
  e.crs_m = 1.781250000000e+00;
  e.delta_n_rad_per_s = 2.977624029993e-09;
  e.m0_rad = -2.577558800824e+00;
  e.cuc_rad = -3.725290298462e-09;
  e.eccentricity = 9.957980364561e-05;
  e.cus_rad = 9.289011359215e-06;
  e.sqrt_a_sqrtm = 5.440600597382e+03;
  e.cic_rad = 2.235174179077e-08;
  e.omega0_rad = 2.120892490885e-01;
  e.cis_rad = -3.166496753693e-08;
  e.i0_rad = 9.827980823536e-01;
  e.crc_m = 1.513437500000e+02;
  e.omega_rad = -2.737701822876e+00;
  e.omega_dot_rad_per_s = -5.396653363703e-09;
  e.idot_rad_per_s = -4.978778814693e-10;
  e.data_source = inav ? 517 : 258;
  e.accuracy_m = 3.12;
  e.group_delays.bgd_e1e5a_s = -1.862645149231e-09;
  e.group_delays.bgd_e1e5b_s = inav ? -2.095475792885e-09 : 0.0;
  return e;
}

// C05 (GEO, D2) and C11 (MEO, D1) of 2020-06-25 12:00:00 BDT (BDT week 755, toe 388800 s).
KeplerEphemeris beidou_c05() {
  KeplerEphemeris e;
  e.satellite = SatelliteId{GnssSystem::kBeiDou, 5};
  e.message = NavMessage::kBeiDouD2;
  e.toc = GnssTime::from_week_tow(TimeScale::kBdt, 755, 388800.0);
  e.toe = e.toc;
  e.week = 755;
  e.toe_sow = 388800.0;
  e.af0_s = -5.188415525481e-04;
  e.af1_s_per_s = -6.705658250894e-11;
  e.iode = 1;
  e.crs_m = -7.423281250000e+02;
  e.delta_n_rad_per_s = 6.364907981108e-09;
  e.m0_rad = 2.546968722968e+00;
  e.cuc_rad = -2.396851778030e-05;
  e.eccentricity = 3.758134553209e-04;
  e.cus_rad = 6.952323019505e-06;
  e.sqrt_a_sqrtm = 6.493356378555e+03;
  e.cic_rad = 1.001171767712e-07;
  e.omega0_rad = 2.662878535580e-01;
  e.cis_rad = 6.984919309616e-08;
  e.i0_rad = 6.499528221725e-02;
  e.crc_m = -2.130312500000e+02;
  e.omega_rad = 1.431258377153e+00;
  e.omega_dot_rad_per_s = -5.347722754118e-09;
  e.idot_rad_per_s = -6.732423289596e-10;
  e.group_delays.tgd1_s = 1.000000000000e-10;
  e.group_delays.tgd2_s = -9.300000000000e-09;
  return e;
}

KeplerEphemeris beidou_c11() {
  KeplerEphemeris e;
  e.satellite = SatelliteId{GnssSystem::kBeiDou, 11};
  e.message = NavMessage::kBeiDouD1;
  e.toc = GnssTime::from_week_tow(TimeScale::kBdt, 755, 388800.0);
  e.toe = e.toc;
  e.week = 755;
  e.toe_sow = 388800.0;
  e.af0_s = -4.506245022640e-04;
  e.af1_s_per_s = -2.404831889180e-11;
  e.af2_s_per_s2 = -4.065758146821e-20;
  e.iode = 10;
  e.crs_m = 8.617187500000e+01;
  e.delta_n_rad_per_s = 3.445500661790e-09;
  e.m0_rad = 2.356934551190e+00;
  e.cuc_rad = 4.188623279333e-06;
  e.eccentricity = 1.845736987889e-03;
  e.cus_rad = 3.980007022619e-06;
  e.sqrt_a_sqrtm = 5.282602237701e+03;
  e.cic_rad = -4.516914486885e-08;
  e.omega0_rad = 1.881039771828e+00;
  e.cis_rad = -4.097819328308e-08;
  e.i0_rad = 9.899110943419e-01;
  e.crc_m = 2.905156250000e+02;
  e.omega_rad = -2.140728248324e+00;
  e.omega_dot_rad_per_s = -6.802069047764e-09;
  e.idot_rad_per_s = 7.286017777600e-11;
  e.group_delays.tgd1_s = 4.000000000000e-09;
  e.group_delays.tgd2_s = 1.100000000000e-09;
  return e;
}

// R02 with t_b = 2020-06-25 12:15:00 UTC (12:15:18 GPST), channel -4.
GlonassEphemeris glonass_r02() {
  GlonassEphemeris e;
  e.satellite = SatelliteId{GnssSystem::kGlonass, 2};
  e.toe = GnssTime::from_calendar(CalendarTime{2020, 6, 25, 12, 15, 0.0}, TimeScale::kUtc);
  e.minus_tau_n_s = 4.332726821303e-04;
  e.gamma_n = 1.818989403546e-12;
  e.message_frame_time_s = 3.888000000000e+05;
  e.position_m = Eigen::Vector3d(-9.983247070312e+03, 5.047906738281e+03, 2.296504052734e+04) * 1e3;
  e.velocity_mps = Eigen::Vector3d(-2.054879188538e+00, -2.364778518677e+00, -3.791494369507e-01) * 1e3;
  e.acceleration_mps2 = Eigen::Vector3d(9.313225746155e-10, 0.0, -2.793967723846e-09) * 1e3;
  e.frequency_channel = -4;
  return e;
}

// Central difference of a function of time, step h_s either side.
template <typename F>
auto central_difference(F f, const GnssTime& t, double h_s) -> decltype(f(t)) {
  return (f(t + h_s) - f(t - h_s)) / (2.0 * h_s);  // evaluated here: no Eigen expression of temporaries
}

void expect_velocity_is_derivative_of_position(const KeplerEphemeris& eph, const GnssTime& t) {
  const SatelliteState s = evaluate_kepler(eph, t);
  const Eigen::Vector3d fd_mps =
      central_difference([&](const GnssTime& x) -> Eigen::Vector3d { return evaluate_kepler(eph, x).position_m; }, t, 1.0);
  // Truncation of the 1-s central difference: jerk h^2 / 6 ~ 1e-5 m/s (MEO) and far less for GEO.
  EXPECT_LT((s.velocity_mps - fd_mps).norm(), 1e-4) << eph.satellite.to_string() << " dt " << (t - eph.toe);
}

// ---------------------------------------------------------------- Keplerian evaluation

TEST(BroadcastKepler, GpsRadiusLiesBetweenPerigeeAndApogee) {
  const KeplerEphemeris eph = gps_g07();
  const double a_m = eph.sqrt_a_sqrtm * eph.sqrt_a_sqrtm;
  for (double dt_s : {-7200.0, -1800.0, 0.0, 900.0, 7200.0}) {
    const SatelliteState s = evaluate_kepler(eph, eph.toe + dt_s);
    // Harmonic radius corrections |Crs|, |Crc| < 300 m.
    EXPECT_GT(s.position_m.norm(), a_m * (1.0 - eph.eccentricity) - 300.0);
    EXPECT_LT(s.position_m.norm(), a_m * (1.0 + eph.eccentricity) + 300.0);
    // Earth-fixed speed of a GPS satellite: 3.9 km/s inertial minus up to 1.9 km/s of omega x r.
    EXPECT_GT(s.velocity_mps.norm(), 2000.0);
    EXPECT_LT(s.velocity_mps.norm(), 4200.0);
  }
}

TEST(BroadcastKepler, GpsAndGalileoAgreeWithPreciseOrbitToAFewMetres) {
  struct Case {
    KeplerEphemeris eph;
    GnssTime t;
    Eigen::Vector3d sp3_km;
    double sp3_clock_us;
  };
  const Case cases[] = {
      {gps_g07(), gpst(2020, 6, 25, 12, 0, 0), {-6945.099222, -14068.115087, 21704.860378}, -312.592497},
      {gps_g07(), gpst(2020, 6, 25, 12, 15, 0), {-5033.274175, -15516.284083, 21189.041223}, -312.600269},
      {galileo_e01(NavMessage::kGalileoInav), gpst(2020, 6, 25, 12, 0, 0), {-14819.317591, -15656.395751, 20287.373001}, -885.049933},
      {galileo_e01(NavMessage::kGalileoInav), gpst(2020, 6, 25, 12, 15, 0), {-12936.360125, -15406.490768, 21716.121806}, -885.057058},
  };
  for (const Case& c : cases) {
    const SatelliteState s = evaluate_kepler(c.eph, c.t);
    const double error_m = (s.position_m - c.sp3_km * 1e3).norm();
    // Measured 0.59, 0.64 m (G07) and 0.69, 0.68 m (E01); clocks 1.1 and -0.1 ns.
    EXPECT_LT(error_m, 1.5) << c.eph.satellite.to_string() << " at " << c.t.to_iso8601(TimeScale::kGpst);
    RecordProperty(c.eph.satellite.to_string() + "_" + c.t.to_iso8601(TimeScale::kGpst, 0) + "_error_m", std::to_string(error_m));
    RecordProperty(c.eph.satellite.to_string() + "_" + c.t.to_iso8601(TimeScale::kGpst, 0) + "_clock_ns",
                   std::to_string(s.clock_bias_s * 1e9 - c.sp3_clock_us * 1e3));
    // SP3 clocks exclude the periodic relativistic term, as clock_bias_s does. Broadcast clock
    // error plus the GRG clock datum: a few ns.
    EXPECT_NEAR(s.clock_bias_s * 1e6, c.sp3_clock_us, 0.003) << c.eph.satellite.to_string();
  }
}

TEST(BroadcastKepler, VelocityIsTheDerivativeOfPosition) {
  for (const KeplerEphemeris& eph : {gps_g07(), galileo_e01(NavMessage::kGalileoInav), beidou_c05(), beidou_c11()}) {
    for (double dt_s : {-5400.0, 0.0, 3.5, 4000.0}) expect_velocity_is_derivative_of_position(eph, eph.toe + dt_s);
  }
}

TEST(BroadcastKepler, CnavRateTermsEnterRadiusAndStayConsistent) {
  const KeplerEphemeris legacy = gps_g07();
  KeplerEphemeris cnav = legacy;
  cnav.message = NavMessage::kGpsCnav;
  cnav.a_dot_m_per_s = 0.02;
  const GnssTime t = legacy.toe + 3600.0;
  const SatelliteState a = evaluate_kepler(legacy, t);
  const SatelliteState b = evaluate_kepler(cnav, t);
  // A_k = A0 + A_dot tk with the mean motion still from A0: only r = A_k (1 - e cos E) + dr changes,
  // by A_dot tk (1 - e cos E), where cos E follows from the relativistic term's derivative.
  const double rel_scale_s = k::kRelativisticF_s_per_sqrtm * legacy.eccentricity * legacy.sqrt_a_sqrtm;
  const double sin_e = a.relativistic_s / rel_scale_s;
  const double cos_e = std::sqrt(1.0 - sin_e * sin_e) * (a.relativistic_drift_s_per_s / rel_scale_s > 0 ? 1.0 : -1.0);
  EXPECT_NEAR(b.position_m.norm() - a.position_m.norm(), 0.02 * 3600.0 * (1.0 - legacy.eccentricity * cos_e), 1e-6);
  EXPECT_LT((evaluate_kepler(cnav, legacy.toe).position_m - evaluate_kepler(legacy, legacy.toe).position_m).norm(), 1e-9);
  cnav.delta_n_dot_rad_per_s2 = 1e-13;
  expect_velocity_is_derivative_of_position(cnav, t);
  expect_velocity_is_derivative_of_position(cnav, legacy.toe - 5000.0);
  // A mean-motion rate moves the satellite along track by about r * delta_n_dot tk^2 / 2 = 17 m.
  const double along_m = (evaluate_kepler(cnav, t).position_m - b.position_m).norm();
  EXPECT_NEAR(along_m, a.position_m.norm() * 0.5e-13 * 3600.0 * 3600.0, 1.0);
}

TEST(BroadcastKepler, ClockDriftIsTheDerivativeOfTheClock) {
  KeplerEphemeris eph = beidou_c11();  // has a non-zero af2
  eph.af2_s_per_s2 = 3e-18;            // make the quadratic term visible
  eph.toc = eph.toe - 600.0;
  for (double dt_s : {-3000.0, 0.0, 2500.0}) {
    const GnssTime t = eph.toe + dt_s;
    const SatelliteState s = evaluate_kepler(eph, t);
    const double t_rel_s = t - eph.toc;
    EXPECT_DOUBLE_EQ(s.clock_bias_s, eph.af0_s + eph.af1_s_per_s * t_rel_s + eph.af2_s_per_s2 * t_rel_s * t_rel_s);
    const double fd_clock = central_difference([&](const GnssTime& x) { return evaluate_kepler(eph, x).clock_bias_s; }, t, 10.0);
    EXPECT_NEAR(s.clock_drift_s_per_s, fd_clock, 1e-20);
    const double fd_rel = central_difference([&](const GnssTime& x) { return evaluate_kepler(eph, x).relativistic_s; }, t, 1.0);
    EXPECT_NEAR(s.relativistic_drift_s_per_s, fd_rel, 1e-16);  // |drift| ~ 5e-12
  }
}

TEST(BroadcastKepler, RelativisticTermEqualsMinusTwoRDotVOverCSquared) {
  // -2 r.v / c^2 holds in the inertial frame; r . v is the same with the Earth-fixed velocity
  // because v_inertial = v_ecef + omega x r and r . (omega x r) = 0. For a pure Kepler orbit
  // r . v = sqrt(GM A) e sin E exactly; harmonic corrections (Crc = 263 m here) break it by up to
  // 45 ps, delta-n by about Delta n / n = 3.5e-5 of the term (measured 1.1 ps; 3e-18 s without).
  KeplerEphemeris eph = gps_g07();
  eph.crs_m = eph.crc_m = eph.cus_rad = eph.cuc_rad = eph.cis_rad = eph.cic_rad = 0.0;
  const Eigen::Vector3d omega(0.0, 0.0, k::kEarthRotationRateGps_radps);
  const double c2 = k::kSpeedOfLight_mps * k::kSpeedOfLight_mps;
  for (double dt_s : {-7000.0, -2000.0, 0.0, 1234.5, 6000.0}) {
    const SatelliteState s = evaluate_kepler(eph, eph.toe + dt_s);
    const Eigen::Vector3d v_inertial = s.velocity_mps + omega.cross(s.position_m);
    const double expected_s = -2.0 * s.position_m.dot(v_inertial) / c2;
    EXPECT_NEAR(s.relativistic_s, expected_s, 2e-12) << dt_s;
    EXPECT_NEAR(s.position_m.dot(s.velocity_mps), s.position_m.dot(v_inertial), 1e-3);
  }
  eph.delta_n_rad_per_s = 0.0;
  for (double dt_s : {-7000.0, 0.0, 6000.0}) {
    const SatelliteState s = evaluate_kepler(eph, eph.toe + dt_s);
    EXPECT_NEAR(s.relativistic_s, -2.0 * s.position_m.dot(s.velocity_mps) / c2, 1e-15) << dt_s;
  }
  // Magnitude: F e sqrt(A) = 32 ns for this record.
  EXPECT_NEAR(std::abs(k::kRelativisticF_s_per_sqrtm * eph.eccentricity * eph.sqrt_a_sqrtm), 32.1e-9, 0.1e-9);
}

TEST(BroadcastKepler, KeplerEquationSolvedForHighEccentricity) {
  KeplerEphemeris eph = gps_g07();
  eph.crs_m = eph.crc_m = eph.cus_rad = eph.cuc_rad = eph.cis_rad = eph.cic_rad = 0.0;
  eph.eccentricity = 0.75;
  eph.delta_n_rad_per_s = 0.0;
  const double a_m = eph.sqrt_a_sqrtm * eph.sqrt_a_sqrtm;
  const double n_radps = std::sqrt(k::kGmGps_m3ps2 / (a_m * a_m * a_m));
  const double rel_scale_s = k::kRelativisticF_s_per_sqrtm * eph.eccentricity * eph.sqrt_a_sqrtm;
  for (double dt_s : {-3000.0, 100.0, 5000.0}) {
    const SatelliteState s = evaluate_kepler(eph, eph.toe + dt_s);
    // Recover E from r = A (1 - e cos E) and the sign of sin E; then M = E - e sin E must hold.
    const double cos_e = (1.0 - s.position_m.norm() / a_m) / eph.eccentricity;
    const double sin_e = s.relativistic_s / rel_scale_s;
    const double ecc_anomaly = std::atan2(sin_e, cos_e);
    const double mean_anomaly = std::remainder(eph.m0_rad + n_radps * dt_s, 2.0 * std::numbers::pi);
    EXPECT_NEAR(std::remainder(ecc_anomaly - eph.eccentricity * sin_e - mean_anomaly, 2.0 * std::numbers::pi), 0.0, 1e-9);
  }
}

TEST(BroadcastKepler, BeidouGeoIsFixedOverItsSlotAndMeoPathDiffers) {
  const KeplerEphemeris geo = beidou_c05();
  ASSERT_TRUE(is_beidou_geo(geo.satellite));
  double max_lat_deg = 0.0;
  double max_speed_mps = 0.0;
  for (double dt_s = -43200.0; dt_s <= 43200.0; dt_s += 1800.0) {
    const SatelliteState s = evaluate_kepler(geo, geo.toe + dt_s);
    const double lon_deg = std::atan2(s.position_m.y(), s.position_m.x()) * 180.0 / std::numbers::pi;
    const double lat_deg = std::asin(s.position_m.z() / s.position_m.norm()) * 180.0 / std::numbers::pi;
    // C05 is the GEO at 58.75 deg E (BeiDou constellation status).
    EXPECT_NEAR(lon_deg, 58.75, 0.5) << dt_s;
    EXPECT_NEAR(s.position_m.norm(), 42164.2e3, 30e3) << dt_s;
    max_lat_deg = std::max(max_lat_deg, std::abs(lat_deg));
    max_speed_mps = std::max(max_speed_mps, s.velocity_mps.norm());
  }
  // A GEO with a few degrees of inclination draws a narrow figure of eight: latitude within the
  // inclination, Earth-fixed speed up to r omega i. The broadcast i0 (3.7 deg) is measured from
  // the ICD's reference plane tilted by 5 deg: the wrong sign of that tilt would give ~8.7 deg.
  EXPECT_LT(max_lat_deg, 5.0);
  EXPECT_GT(max_lat_deg, 0.5);
  EXPECT_LT(max_speed_mps, 42164e3 * 7.292115e-5 * max_lat_deg * std::numbers::pi / 180.0 * 1.1 + 5.0);
  RecordProperty("max_latitude_deg", std::to_string(max_lat_deg));
  // The same elements through the MEO/IGSO path (a non-GEO number) land elsewhere entirely.
  KeplerEphemeris as_igso = geo;
  as_igso.satellite.number = 6;
  ASSERT_FALSE(is_beidou_geo(as_igso.satellite));
  const SatelliteState geo_state = evaluate_kepler(geo, geo.toe + 600.0);
  const SatelliteState igso_state = evaluate_kepler(as_igso, geo.toe + 600.0);
  EXPECT_GT((geo_state.position_m - igso_state.position_m).norm(), 1000e3);
  EXPECT_GT(igso_state.velocity_mps.norm(), 40.0);  // a 0-inclination orbit seen without the GEO rotation

  const SatelliteState meo = evaluate_kepler(beidou_c11(), beidou_c11().toe + 600.0);
  EXPECT_NEAR(meo.position_m.norm(), 27906e3, 60e3);
}

TEST(BroadcastKepler, BeidouGeoNumbers) {
  for (int n : {1, 2, 3, 4, 5, 59, 60, 61, 62, 63}) {
    EXPECT_TRUE(is_beidou_geo(SatelliteId{GnssSystem::kBeiDou, static_cast<std::uint8_t>(n)})) << n;
  }
  for (int n : {6, 18, 46, 58, 64}) {
    EXPECT_FALSE(is_beidou_geo(SatelliteId{GnssSystem::kBeiDou, static_cast<std::uint8_t>(n)})) << n;
  }
  EXPECT_FALSE(is_beidou_geo(SatelliteId{GnssSystem::kGps, 1}));
}

TEST(BroadcastKepler, BeidouUsesBdtSecondsOfWeek) {
  // Moving toe by the BDT-GPST offset in its representation (toe_sow is the BDT value; the code
  // derives it from the GnssTime) must not matter: evaluate at toe itself for two whole weeks apart.
  KeplerEphemeris eph = beidou_c11();
  const SatelliteState a = evaluate_kepler(eph, eph.toe);
  eph.toe = eph.toe + 604800.0;
  eph.toc = eph.toc + 604800.0;
  const SatelliteState b = evaluate_kepler(eph, eph.toe);
  EXPECT_LT((a.position_m - b.position_m).norm(), 1e-6);
}

// ---------------------------------------------------------------- GLONASS and SBAS

TEST(BroadcastGlonass, AtToeReturnsTheBroadcastState) {
  const GlonassEphemeris eph = glonass_r02();
  const SatelliteState s = evaluate_glonass(eph, eph.toe);
  EXPECT_EQ(s.position_m, eph.position_m);
  EXPECT_EQ(s.velocity_mps, eph.velocity_mps);
  EXPECT_DOUBLE_EQ(s.clock_bias_s, eph.minus_tau_n_s);
  EXPECT_EQ(s.relativistic_s, 0.0);
}

TEST(BroadcastGlonass, ToeIsEighteenSecondsAfterTheUtcEpochInGpst) {
  const GlonassEphemeris eph = glonass_r02();
  EXPECT_DOUBLE_EQ(eph.toe - gpst(2020, 6, 25, 12, 15, 0), 18.0);
}

TEST(BroadcastGlonass, AgreesWithPreciseOrbitBothDirections) {
  const GlonassEphemeris eph = glonass_r02();
  // GRG SP3 R02 at 12:00:00 and 12:15:00 GPST: 918 s and 18 s before t_b. Measured 2.55 and 2.51 m
  // (GLONASS broadcast orbits are good to a few metres), clock -1.75 ns.
  const SatelliteState back = evaluate_glonass(eph, gpst(2020, 6, 25, 12, 0, 0));
  const SatelliteState near = evaluate_glonass(eph, gpst(2020, 6, 25, 12, 15, 0));
  EXPECT_LT((back.position_m - Eigen::Vector3d(-8172.416679, 7296.471839, 23080.994405) * 1e3).norm(), 4.0);
  EXPECT_LT((near.position_m - Eigen::Vector3d(-9946.286393, 5090.506183, 22971.778412) * 1e3).norm(), 4.0);
  RecordProperty("back_918s_error_m", std::to_string((back.position_m - Eigen::Vector3d(-8172.416679, 7296.471839, 23080.994405) * 1e3).norm()));
  RecordProperty("near_18s_error_m", std::to_string((near.position_m - Eigen::Vector3d(-9946.286393, 5090.506183, 22971.778412) * 1e3).norm()));
  RecordProperty("clock_error_ns", std::to_string(back.clock_bias_s * 1e9 - 433272.764));
  // SP3 clock 433.272764 us at 12:00; broadcast -tau_n + gamma_n dt.
  EXPECT_NEAR(back.clock_bias_s * 1e6, 433.272764, 0.005);
  EXPECT_DOUBLE_EQ(back.clock_drift_s_per_s, eph.gamma_n);
  EXPECT_DOUBLE_EQ(back.clock_bias_s, eph.minus_tau_n_s + eph.gamma_n * (-918.0));
}

TEST(BroadcastGlonass, ForwardThenBackwardReturnsToTheStart) {
  const GlonassEphemeris eph = glonass_r02();
  for (double dt_s : {900.0, -900.0, 1234.5}) {
    const SatelliteState there = evaluate_glonass(eph, eph.toe + dt_s);
    GlonassEphemeris restarted = eph;
    restarted.toe = eph.toe + dt_s;
    restarted.position_m = there.position_m;
    restarted.velocity_mps = there.velocity_mps;
    const SatelliteState back = evaluate_glonass(restarted, eph.toe);
    // RK4 with 60-s steps is not exactly time-reversible: measured 11 um and 2.3 nm/s.
    EXPECT_LT((back.position_m - eph.position_m).norm(), 1e-4) << dt_s;
    EXPECT_LT((back.velocity_mps - eph.velocity_mps).norm(), 1e-8) << dt_s;
  }
}

// The cache of full-step states gives exactly what the plain integration gives, in any order of
// evaluation times (forward, backward, repeated, out of order), the step boundaries included.
TEST(BroadcastGlonass, OrbitCacheIsBitIdenticalToTheIntegration) {
  const GlonassEphemeris eph = glonass_r02();
  GlonassOrbitCache cache;
  for (double dt_s : {0.0, 1.0, 0.067, 59.999999, 60.0, 60.000001, 899.93, 120.0, -0.5, -60.0, -61.25, -1799.0, 1800.0,
                      300.07, 1e-10, -1e-10}) {
    const SatelliteState plain = evaluate_glonass(eph, eph.toe + dt_s);
    const SatelliteState cached = cache.evaluate(eph, eph.toe + dt_s);
    EXPECT_EQ(cached.position_m, plain.position_m) << dt_s;
    EXPECT_EQ(cached.velocity_mps, plain.velocity_mps) << dt_s;
    EXPECT_EQ(cached.clock_bias_s, plain.clock_bias_s) << dt_s;
  }
  // Another record in the same cache keeps its own nodes.
  GlonassEphemeris other = eph;
  other.position_m.x() += 1000.0;
  EXPECT_EQ(cache.evaluate(other, other.toe + 700.0).position_m, evaluate_glonass(other, other.toe + 700.0).position_m);
  EXPECT_EQ(cache.evaluate(eph, eph.toe + 700.0).position_m, evaluate_glonass(eph, eph.toe + 700.0).position_m);
}

// A time far from t_b (a pseudorange of 1e308 m puts the transmission there) gives NaNs at once
// instead of integrating for ever; a day is still integrated.
TEST(BroadcastGlonass, PropagationIsBoundedToADay) {
  const GlonassEphemeris eph = glonass_r02();
  GlonassOrbitCache cache;
  for (double dt_s : {86400.5, -86400.5, 1e20, -1e300}) {
    EXPECT_FALSE(evaluate_glonass(eph, eph.toe + dt_s).position_m.allFinite()) << dt_s;
    EXPECT_FALSE(cache.evaluate(eph, eph.toe + dt_s).position_m.allFinite()) << dt_s;
  }
  EXPECT_TRUE(cache.evaluate(eph, eph.toe + 86400.0).position_m.allFinite());
}

TEST(BroadcastGlonass, VelocityIsTheDerivativeOfPosition) {
  const GlonassEphemeris eph = glonass_r02();
  for (double dt_s : {-700.0, 300.0}) {
    const GnssTime t = eph.toe + dt_s;
    const Eigen::Vector3d fd =
        central_difference([&](const GnssTime& x) -> Eigen::Vector3d { return evaluate_glonass(eph, x).position_m; }, t, 1.0);
    EXPECT_LT((evaluate_glonass(eph, t).velocity_mps - fd).norm(), 1e-4);
  }
}

TEST(BroadcastSbas, SecondOrderPolynomial) {
  SbasEphemeris eph;
  eph.satellite = SatelliteId{GnssSystem::kSbas, 23};
  eph.toe = gpst(2020, 6, 25, 12, 0, 0);
  eph.position_m = Eigen::Vector3d(40e6, 10e6, 1e5);
  eph.velocity_mps = Eigen::Vector3d(1.0, -2.0, 0.5);
  eph.acceleration_mps2 = Eigen::Vector3d(1e-4, 2e-4, -3e-4);
  eph.agf0_s = 1e-7;
  eph.agf1_s_per_s = 2e-12;
  const SatelliteState s = evaluate_sbas(eph, eph.toe + 100.0);
  EXPECT_NEAR(s.position_m.x(), 40e6 + 100.0 + 0.5, 1e-6);
  EXPECT_NEAR(s.position_m.y(), 10e6 - 200.0 + 1.0, 1e-6);
  EXPECT_NEAR(s.position_m.z(), 1e5 + 50.0 - 1.5, 1e-6);
  EXPECT_NEAR(s.velocity_mps.z(), 0.5 - 0.03, 1e-12);
  EXPECT_DOUBLE_EQ(s.clock_bias_s, 1e-7 + 2e-10);
  EXPECT_DOUBLE_EQ(s.clock_drift_s_per_s, 2e-12);
}

// ---------------------------------------------------------------- group delays

Signal sig(GnssSystem system, char band, char attribute) { return Signal{system, band, attribute}; }

TEST(BroadcastGroupDelay, Gps) {
  // gamma = (f1/f2)^2 = (154/120)^2, (f1/f5)^2 = (154/115)^2.
  const double gamma12 = (154.0 / 120.0) * (154.0 / 120.0);
  const double gamma15 = (154.0 / 115.0) * (154.0 / 115.0);
  KeplerEphemeris lnav = gps_g07();
  const double tgd = lnav.group_delays.tgd_s;
  EXPECT_DOUBLE_EQ(group_delay_s(lnav, sig(GnssSystem::kGps, '1', 'C')), tgd);
  EXPECT_DOUBLE_EQ(group_delay_s(lnav, sig(GnssSystem::kGps, '1', 'W')), tgd);
  EXPECT_NEAR(group_delay_s(lnav, sig(GnssSystem::kGps, '2', 'W')), gamma12 * tgd, 1e-20);
  EXPECT_NEAR(group_delay_s(lnav, sig(GnssSystem::kGps, '2', 'L')), gamma12 * tgd, 1e-20);
  EXPECT_NEAR(group_delay_s(lnav, sig(GnssSystem::kGps, '5', 'Q')), gamma15 * tgd, 1e-20);
  // The ionosphere-free L1/L2 P(Y) combination is free of group delay: the clock's definition.
  EXPECT_NEAR((gamma12 * group_delay_s(lnav, sig(GnssSystem::kGps, '1', 'W')) -
               group_delay_s(lnav, sig(GnssSystem::kGps, '2', 'W'))) / (gamma12 - 1.0), 0.0, 1e-20);

  KeplerEphemeris cnav = lnav;
  cnav.message = NavMessage::kGpsCnav;
  cnav.group_delays.isc_l1ca_s = 1e-9;
  cnav.group_delays.isc_l2c_s = -2e-9;
  cnav.group_delays.isc_l5i5_s = 3e-9;
  cnav.group_delays.isc_l5q5_s = 4e-9;
  EXPECT_DOUBLE_EQ(group_delay_s(cnav, sig(GnssSystem::kGps, '1', 'C')), tgd - 1e-9);
  EXPECT_DOUBLE_EQ(group_delay_s(cnav, sig(GnssSystem::kGps, '2', 'L')), tgd + 2e-9);
  EXPECT_NEAR(group_delay_s(cnav, sig(GnssSystem::kGps, '2', 'W')), gamma12 * tgd, 1e-20);
  EXPECT_DOUBLE_EQ(group_delay_s(cnav, sig(GnssSystem::kGps, '5', 'I')), tgd - 3e-9);
  EXPECT_DOUBLE_EQ(group_delay_s(cnav, sig(GnssSystem::kGps, '5', 'Q')), tgd - 4e-9);
}

TEST(BroadcastGroupDelay, GalileoInavFnavAndCrossTerms) {
  const double gamma15 = (154.0 / 115.0) * (154.0 / 115.0);
  const double gamma17 = (154.0 / 118.0) * (154.0 / 118.0);
  const KeplerEphemeris inav = galileo_e01(NavMessage::kGalileoInav);
  const KeplerEphemeris fnav = galileo_e01(NavMessage::kGalileoFnav);
  const double bgd_a = -1.862645149231e-09;
  const double bgd_b = -2.095475792885e-09;
  EXPECT_DOUBLE_EQ(group_delay_s(inav, sig(GnssSystem::kGalileo, '1', 'C')), bgd_b);
  EXPECT_NEAR(group_delay_s(inav, sig(GnssSystem::kGalileo, '7', 'Q')), gamma17 * bgd_b, 1e-20);
  EXPECT_DOUBLE_EQ(group_delay_s(fnav, sig(GnssSystem::kGalileo, '1', 'C')), bgd_a);
  EXPECT_NEAR(group_delay_s(fnav, sig(GnssSystem::kGalileo, '5', 'Q')), gamma15 * bgd_a, 1e-20);
  // E5a from I/NAV: with hardware delays d1, d5, d7 chosen to reproduce both BGDs, the E5a delay
  // relative to the E1/E5b ionosphere-free clock is d5 - (gamma17 d1 - d7) / (gamma17 - 1).
  const double d1 = 5e-9;
  const double d7 = d1 - bgd_b * (1.0 - gamma17);  // BGD(E1,E5b) = (d1 - d7) / (1 - gamma17)
  const double d5 = d1 - bgd_a * (1.0 - gamma15);  // BGD(E1,E5a) = (d1 - d5) / (1 - gamma15)
  const double if17 = (gamma17 * d1 - d7) / (gamma17 - 1.0);
  const double if15 = (gamma15 * d1 - d5) / (gamma15 - 1.0);
  EXPECT_NEAR(group_delay_s(inav, sig(GnssSystem::kGalileo, '1', 'C')), d1 - if17, 1e-20);
  EXPECT_NEAR(group_delay_s(inav, sig(GnssSystem::kGalileo, '5', 'Q')), d5 - if17, 1e-20);
  EXPECT_NEAR(group_delay_s(inav, sig(GnssSystem::kGalileo, '7', 'Q')), d7 - if17, 1e-20);
  EXPECT_NEAR(group_delay_s(fnav, sig(GnssSystem::kGalileo, '5', 'Q')), d5 - if15, 1e-20);
  // F/NAV carries no BGD(E1,E5b): with it (as a combined record would) E5b is exact as well.
  KeplerEphemeris fnav_full = fnav;
  fnav_full.group_delays.bgd_e1e5b_s = bgd_b;
  EXPECT_NEAR(group_delay_s(fnav_full, sig(GnssSystem::kGalileo, '7', 'Q')), d7 - if15, 1e-20);
  EXPECT_DOUBLE_EQ(group_delay_s(fnav, sig(GnssSystem::kGalileo, '7', 'Q')), bgd_a);
  EXPECT_EQ(group_delay_s(inav, sig(GnssSystem::kGalileo, '6', 'C')), 0.0);
}

TEST(BroadcastGroupDelay, BeidouNavicGlonass) {
  const KeplerEphemeris c05 = beidou_c05();
  EXPECT_DOUBLE_EQ(group_delay_s(c05, sig(GnssSystem::kBeiDou, '2', 'I')), 1e-10);
  EXPECT_DOUBLE_EQ(group_delay_s(c05, sig(GnssSystem::kBeiDou, '7', 'I')), -9.3e-9);
  EXPECT_EQ(group_delay_s(c05, sig(GnssSystem::kBeiDou, '6', 'I')), 0.0);
  KeplerEphemeris cnav1 = c05;
  cnav1.message = NavMessage::kBeiDouCnav1;
  cnav1.group_delays.tgd_b1cp_s = 2e-9;
  cnav1.group_delays.isc_b1cd_s = 0.5e-9;
  cnav1.group_delays.tgd_b2ap_s = -3e-9;
  cnav1.group_delays.isc_b2ad_s = 0.25e-9;
  cnav1.group_delays.tgd_b2bi_s = 7e-9;
  EXPECT_DOUBLE_EQ(group_delay_s(cnav1, sig(GnssSystem::kBeiDou, '1', 'P')), 2e-9);
  EXPECT_DOUBLE_EQ(group_delay_s(cnav1, sig(GnssSystem::kBeiDou, '1', 'D')), 2.5e-9);
  EXPECT_DOUBLE_EQ(group_delay_s(cnav1, sig(GnssSystem::kBeiDou, '5', 'P')), -3e-9);
  EXPECT_DOUBLE_EQ(group_delay_s(cnav1, sig(GnssSystem::kBeiDou, '5', 'D')), -2.75e-9);
  EXPECT_DOUBLE_EQ(group_delay_s(cnav1, sig(GnssSystem::kBeiDou, '7', 'D')), 7e-9);

  KeplerEphemeris navic = gps_g07();
  navic.satellite = SatelliteId{GnssSystem::kNavic, 2};
  navic.message = NavMessage::kNavicLnav;
  navic.group_delays.tgd_s = 4e-9;
  EXPECT_DOUBLE_EQ(group_delay_s(navic, sig(GnssSystem::kNavic, '5', 'A')), 4e-9);
  // (f_L5 / f_S)^2 = (115 / 243.6)^2 in units of 10.23 MHz.
  EXPECT_NEAR(group_delay_s(navic, sig(GnssSystem::kNavic, '9', 'A')), (115.0 / 243.6) * (115.0 / 243.6) * 4e-9, 1e-21);

  GlonassEphemeris r02 = glonass_r02();
  EXPECT_EQ(group_delay_s(r02, sig(GnssSystem::kGlonass, '2', 'C')), 0.0);
  r02.delta_tau_n_s = -2.8e-9;
  EXPECT_EQ(group_delay_s(r02, sig(GnssSystem::kGlonass, '1', 'C')), 0.0);
  EXPECT_DOUBLE_EQ(group_delay_s(r02, sig(GnssSystem::kGlonass, '2', 'C')), -2.8e-9);
}

TEST(BroadcastGroupDelay, PreferredMessages) {
  EXPECT_EQ(preferred_message(sig(GnssSystem::kGalileo, '1', 'C')), NavMessage::kGalileoInav);
  EXPECT_EQ(preferred_message(sig(GnssSystem::kGalileo, '7', 'Q')), NavMessage::kGalileoInav);
  EXPECT_EQ(preferred_message(sig(GnssSystem::kGalileo, '8', 'Q')), NavMessage::kGalileoInav);
  EXPECT_EQ(preferred_message(sig(GnssSystem::kGalileo, '5', 'Q')), NavMessage::kGalileoFnav);
  EXPECT_EQ(preferred_message(sig(GnssSystem::kGps, '1', 'C')), std::nullopt);
  EXPECT_EQ(preferred_message(sig(GnssSystem::kGps, '5', 'Q')), NavMessage::kGpsCnav);
  EXPECT_EQ(preferred_message(sig(GnssSystem::kQzss, '1', 'L')), NavMessage::kQzssCnav2);
  EXPECT_EQ(preferred_message(sig(GnssSystem::kBeiDou, '2', 'I')), std::nullopt);
  EXPECT_EQ(preferred_message(sig(GnssSystem::kBeiDou, '1', 'P')), NavMessage::kBeiDouCnav1);
  EXPECT_EQ(preferred_message(sig(GnssSystem::kGlonass, '1', 'C')), std::nullopt);
}

// ---------------------------------------------------------------- selection

KeplerEphemeris gps_at(int number, const GnssTime& toe, int health = 0) {
  KeplerEphemeris e = gps_g07();
  e.satellite.number = static_cast<std::uint8_t>(number);
  e.toe = toe;
  e.toc = toe;
  e.health = health;
  return e;
}

TEST(BroadcastSelection, ClosestToeWithinWindowPreferringLaterOnTies) {
  NavigationData data;
  const GnssTime day = gpst(2020, 6, 25, 0, 0, 0);
  for (int h : {0, 2, 4}) data.kepler.push_back(gps_at(1, day + h * 3600.0));
  data.kepler.push_back(gps_at(1, day + 6 * 3600.0, 63));  // unhealthy (NAV data bad, code 31)
  data.kepler.back().iode = 99;
  const BroadcastEphemerides eph(data);
  const SatelliteId g01{GnssSystem::kGps, 1};
  auto toe_h = [&](double t_h) { return (eph.select_kepler(g01, day + t_h * 3600.0).value()->toe - day) / 3600.0; };
  EXPECT_EQ(toe_h(2.0 + 50.0 / 60.0), 2.0);
  EXPECT_EQ(toe_h(3.0 + 10.0 / 60.0), 4.0);
  EXPECT_EQ(toe_h(3.0), 4.0);   // tie: the later toe
  EXPECT_EQ(toe_h(1.0), 2.0);   // tie again
  EXPECT_EQ(toe_h(-1.5), 0.0);  // before the first, inside its window
  EXPECT_EQ(toe_h(5.9), 4.0);   // the unhealthy 6-h record is skipped
  EXPECT_EQ(toe_h(6.0), 4.0);   // 2.0 h away: still inside the 2-h window

  const auto late = eph.select_kepler(g01, day + 6.5 * 3600.0);
  ASSERT_FALSE(late.ok());
  EXPECT_EQ(late.error().code, ErrorCode::kOutOfRange);
  EXPECT_EQ(late.error().message,
            "no ephemeris for G01 at 2020-06-25T06:30:00 GPST (nearest healthy record toe 2020-06-25T04:00:00, 2.5 h "
            "away; limit 2.0 h); 1 unhealthy record(s) within the limit (health 63)");
  const auto early = eph.select_kepler(g01, day - 2.5 * 3600.0);
  ASSERT_FALSE(early.ok());
  EXPECT_EQ(early.error().code, ErrorCode::kOutOfRange);
}

TEST(BroadcastSelection, ErrorMessages) {
  NavigationData data;
  data.kepler.push_back(gps_at(5, gpst(2020, 6, 25, 6, 0, 0)));
  data.kepler.push_back(gps_at(2, gpst(2020, 6, 25, 6, 0, 0), 63));
  data.kepler.push_back(gps_at(2, gpst(2020, 6, 25, 8, 0, 0), 63));
  data.kepler.push_back(galileo_e01(NavMessage::kGalileoInav));
  const BroadcastEphemerides eph(data);
  const GnssTime noon = gpst(2020, 6, 25, 12, 0, 0);

  const auto far = eph.select_kepler(SatelliteId{GnssSystem::kGps, 5}, noon);
  ASSERT_FALSE(far.ok());
  EXPECT_EQ(far.error().message,
            "no ephemeris for G05 at 2020-06-25T12:00:00 GPST (nearest healthy record toe 2020-06-25T06:00:00, 6.0 h "
            "away; limit 2.0 h)");

  const auto none = eph.state(SatelliteId{GnssSystem::kGalileo, 99}, noon);
  ASSERT_FALSE(none.ok());
  EXPECT_EQ(none.error().code, ErrorCode::kNotFound);
  EXPECT_EQ(none.error().message, "no ephemeris at all for E99");

  const auto sick = eph.select_kepler(SatelliteId{GnssSystem::kGps, 2}, gpst(2020, 6, 25, 7, 0, 0));
  ASSERT_FALSE(sick.ok());
  EXPECT_EQ(sick.error().code, ErrorCode::kNotFound);
  EXPECT_EQ(sick.error().message,
            "no healthy ephemeris for G02 at 2020-06-25T07:00:00 GPST: all 2 records are unhealthy (health 63)");

  const auto wrong_message = eph.select_kepler(SatelliteId{GnssSystem::kGalileo, 1}, noon, NavMessage::kGalileoFnav);
  ASSERT_FALSE(wrong_message.ok());
  EXPECT_EQ(wrong_message.error().message, "no FNAV ephemeris for E01 (its 1 record(s) are INAV)");

  const auto mismatch = eph.state_for_signal(SatelliteId{GnssSystem::kGps, 5}, sig(GnssSystem::kGalileo, '1', 'C'), noon);
  ASSERT_FALSE(mismatch.ok());
  EXPECT_EQ(mismatch.error().code, ErrorCode::kInvalidArgument);
}

TEST(BroadcastSelection, FitIntervalWidensTheGpsWindow) {
  NavigationData data;
  data.kepler.push_back(gps_at(3, gpst(2020, 6, 25, 0, 0, 0)));
  data.kepler.back().fit_interval_h = 6.0;
  const BroadcastEphemerides eph(data);
  EXPECT_TRUE(eph.select_kepler(SatelliteId{GnssSystem::kGps, 3}, gpst(2020, 6, 25, 2, 59, 0)).ok());
  EXPECT_FALSE(eph.select_kepler(SatelliteId{GnssSystem::kGps, 3}, gpst(2020, 6, 25, 3, 1, 0)).ok());
  EXPECT_EQ(validity_half_window_s(gps_g07()), 7200.0);
  EXPECT_EQ(validity_half_window_s(galileo_e01(NavMessage::kGalileoInav)), 14400.0);
  EXPECT_EQ(validity_half_window_s(beidou_c11()), 3600.0);  // hourly uploads: no stale BDS-2 orbits
}

TEST(BroadcastSelection, SameToeTakesTheLastRecordRead) {
  NavigationData data;
  data.kepler.push_back(gps_at(9, gpst(2020, 6, 25, 2, 0, 0)));
  data.kepler.back().iode = 1;
  data.kepler.push_back(gps_at(9, gpst(2020, 6, 25, 2, 0, 0)));
  data.kepler.back().iode = 2;
  const BroadcastEphemerides eph(data);
  EXPECT_EQ(eph.select_kepler(SatelliteId{GnssSystem::kGps, 9}, gpst(2020, 6, 25, 1, 0, 0)).value()->iode, 2);
  EXPECT_EQ(eph.select_kepler(SatelliteId{GnssSystem::kGps, 9}, gpst(2020, 6, 25, 3, 0, 0)).value()->iode, 2);
}

TEST(BroadcastSelection, GalileoMessagesFollowTheSignal) {
  NavigationData data;
  KeplerEphemeris fnav = galileo_e01(NavMessage::kGalileoFnav);
  fnav.toe = fnav.toe + 600.0;  // the F/NAV record is 10 min newer
  fnav.toc = fnav.toe;
  data.kepler.push_back(fnav);
  data.kepler.push_back(galileo_e01(NavMessage::kGalileoInav));
  const BroadcastEphemerides eph(data);
  const SatelliteId e01{GnssSystem::kGalileo, 1};
  const GnssTime t = gpst(2020, 6, 25, 12, 11, 0);
  EXPECT_EQ(eph.select_kepler(e01, t).value()->message, NavMessage::kGalileoFnav);  // any: closest
  EXPECT_EQ(eph.select_kepler(e01, t, NavMessage::kGalileoInav).value()->message, NavMessage::kGalileoInav);

  const double gamma15 = (154.0 / 115.0) * (154.0 / 115.0);
  const double gamma17 = (154.0 / 118.0) * (154.0 / 118.0);
  // E1 and E5b from I/NAV, E5a from F/NAV; state() defaults to I/NAV as RTKLIB does for E1.
  EXPECT_DOUBLE_EQ(eph.group_delay_for_signal(e01, sig(GnssSystem::kGalileo, '1', 'C'), t).value(), -2.095475792885e-09);
  EXPECT_NEAR(eph.group_delay_for_signal(e01, sig(GnssSystem::kGalileo, '5', 'Q'), t).value(), gamma15 * -1.862645149231e-09, 1e-20);
  const SatelliteState e1 = eph.state_for_signal(e01, sig(GnssSystem::kGalileo, '1', 'C'), t).value();
  const SatelliteState e5a = eph.state_for_signal(e01, sig(GnssSystem::kGalileo, '5', 'Q'), t).value();
  const SatelliteState any = eph.state(e01, t).value();
  EXPECT_DOUBLE_EQ(e1.clock_bias_s, evaluate_kepler(galileo_e01(NavMessage::kGalileoInav), t).clock_bias_s);
  EXPECT_DOUBLE_EQ(e5a.clock_bias_s, evaluate_kepler(fnav, t).clock_bias_s);
  EXPECT_DOUBLE_EQ(any.clock_bias_s, e1.clock_bias_s);

  // Only I/NAV: E5a falls back to it, with the E5a delay relative to the E1/E5b clock.
  NavigationData inav_only;
  inav_only.kepler.push_back(galileo_e01(NavMessage::kGalileoInav));
  const BroadcastEphemerides only(inav_only);
  EXPECT_NEAR(only.group_delay_for_signal(e01, sig(GnssSystem::kGalileo, '5', 'Q'), t).value(),
              -2.095475792885e-09 + (gamma15 - 1.0) * -1.862645149231e-09, 1e-20);
  EXPECT_TRUE(only.state_for_signal(e01, sig(GnssSystem::kGalileo, '5', 'Q'), t).ok());
  // Only F/NAV: E1 and E5b fall back to it.
  NavigationData fnav_only;
  fnav_only.kepler.push_back(galileo_e01(NavMessage::kGalileoFnav));
  const BroadcastEphemerides only_f(fnav_only);
  EXPECT_DOUBLE_EQ(only_f.group_delay_for_signal(e01, sig(GnssSystem::kGalileo, '1', 'C'), t).value(), -1.862645149231e-09);
  EXPECT_DOUBLE_EQ(only_f.group_delay_for_signal(e01, sig(GnssSystem::kGalileo, '7', 'Q'), t).value(),
                   -1.862645149231e-09 + (gamma17 - 1.0) * 0.0);
  EXPECT_TRUE(only_f.state(e01, t).ok());
  // Neither message within its window: the error tells why, in terms of any message.
  const auto stale = only_f.state_for_signal(e01, sig(GnssSystem::kGalileo, '1', 'C'), t + 5.0 * 3600.0);
  ASSERT_FALSE(stale.ok());
  EXPECT_EQ(stale.error().message,
            "no ephemeris for E01 at 2020-06-25T17:11:00 GPST (nearest healthy record toe 2020-06-25T12:00:00, 5.2 h "
            "away; limit 4.0 h)");
}

TEST(BroadcastSelection, GalileoRecordsOnlyAfterTheirToe) {
  // Galileo data sets are transmitted after their toe (RTKLIB skips toe >= t as well): a record
  // whose toe is 1 s ahead is not yet available even though it is the closest.
  NavigationData data;
  KeplerEphemeris next = galileo_e01(NavMessage::kGalileoInav);
  next.toe = next.toe + 600.0;
  next.toc = next.toe;
  next.iode = 9;
  data.kepler.push_back(galileo_e01(NavMessage::kGalileoInav));
  data.kepler.push_back(next);
  const BroadcastEphemerides eph(data);
  const SatelliteId e01{GnssSystem::kGalileo, 1};
  EXPECT_EQ(eph.select_kepler(e01, gpst(2020, 6, 25, 12, 9, 59)).value()->iode, 8);
  EXPECT_EQ(eph.select_kepler(e01, gpst(2020, 6, 25, 12, 10, 0)).value()->iode, 8);
  EXPECT_EQ(eph.select_kepler(e01, gpst(2020, 6, 25, 12, 10, 1)).value()->iode, 9);
  const auto early = eph.select_kepler(e01, gpst(2020, 6, 25, 11, 59, 0), NavMessage::kGalileoInav);
  ASSERT_FALSE(early.ok());
  EXPECT_EQ(early.error().message,
            "no INAV ephemeris for E01 at 2020-06-25T11:59:00 GPST: every record has its toe at or after that time "
            "(Galileo data sets are transmitted after their toe)");
}

TEST(BroadcastSelection, GlonassSbasWindowsChannelsAndSatellites) {
  NavigationData data;
  data.glonass.push_back(glonass_r02());
  SbasEphemeris s23;
  s23.satellite = SatelliteId{GnssSystem::kSbas, 23};
  s23.toe = gpst(2020, 6, 25, 12, 1, 52);
  s23.position_m = Eigen::Vector3d(35944.6e3, 22044.14e3, 0.0);
  s23.health = 63;  // as the ESBC file has it: MT17 health unavailable, URA unknown
  data.sbas.push_back(s23);
  SbasEphemeris s36 = s23;
  s36.satellite.number = 36;
  s36.health = 1;  // MT17 says ranging off
  data.sbas.push_back(s36);
  data.kepler.push_back(gps_g07());
  const BroadcastEphemerides eph(data);
  const SatelliteId r02{GnssSystem::kGlonass, 2};
  const GnssTime tb = glonass_r02().toe;
  EXPECT_TRUE(eph.state(r02, tb + 1860.0).ok());
  EXPECT_TRUE(eph.state(r02, tb - 1860.0).ok());
  const auto stale = eph.state(r02, tb + 1861.0);
  ASSERT_FALSE(stale.ok());
  EXPECT_NE(stale.error().message.find("limit 0.5 h"), std::string::npos) << stale.error().message;
  EXPECT_EQ(eph.glonass_channel(r02), -4);
  EXPECT_EQ(eph.glonass_channel(SatelliteId{GnssSystem::kGlonass, 3}), std::nullopt);
  EXPECT_DOUBLE_EQ(eph.group_delay_for_signal(r02, sig(GnssSystem::kGlonass, '1', 'C'), tb).value(), 0.0);

  const SatelliteId s23_id{GnssSystem::kSbas, 23};
  EXPECT_TRUE(eph.state(s23_id, s23.toe + 360.0).ok());
  EXPECT_FALSE(eph.state(s23_id, s23.toe + 361.0).ok());
  EXPECT_FALSE(eph.state(SatelliteId{GnssSystem::kSbas, 36}, s23.toe).ok());

  const std::vector<SatelliteId> expected = {SatelliteId{GnssSystem::kGps, 7}, r02, s23_id,
                                             SatelliteId{GnssSystem::kSbas, 36}};
  EXPECT_EQ(eph.satellites(), expected);
  EXPECT_EQ(eph.name(), "broadcast");
}

TEST(BroadcastSelection, StateUsesTheSelectedRecord) {
  NavigationData data;
  data.kepler.push_back(beidou_c05());
  data.kepler.push_back(beidou_c11());
  const BroadcastEphemerides eph(data);
  const GnssTime t = beidou_c05().toe + 100.0;
  const SatelliteState direct = evaluate_kepler(beidou_c05(), t);
  const SatelliteState via = eph.state(SatelliteId{GnssSystem::kBeiDou, 5}, t).value();
  EXPECT_EQ(direct.position_m, via.position_m);
  EXPECT_DOUBLE_EQ(eph.group_delay_for_signal(SatelliteId{GnssSystem::kBeiDou, 11}, sig(GnssSystem::kBeiDou, '2', 'I'), t).value(), 4e-9);
  // B1C prefers a CNAV1 record; with only D1 it falls back and the delay is what D1 carries (0).
  EXPECT_EQ(eph.group_delay_for_signal(SatelliteId{GnssSystem::kBeiDou, 11}, sig(GnssSystem::kBeiDou, '1', 'P'), t).value(), 0.0);
}

}  // namespace
}  // namespace skytrace::orbits
