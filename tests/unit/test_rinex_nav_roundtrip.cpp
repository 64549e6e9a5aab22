// RINEX navigation round trip: read -> format_rinex3_nav -> read gives back every field of every
// record (relative 1e-11: the writer keeps 13 significant digits) and the header values. Run on
// the real ESBC00DNK 2020-06-25 mixed file (RINEX 3.05: the GLONASS fourth line, which RINEX 3.04
// lacks, is the only thing not carried over) and on a day of the nominal constellation.
#include <algorithm>
#include <cmath>
#include <string>

#include "skytrace/orbits/nominal.hpp"
#include "skytrace/orbits/rinex_nav.hpp"
#include "test_support.hpp"

namespace skytrace::orbits {
namespace {

constexpr double kRelative = 1e-11;

::testing::AssertionResult near_rel(const char* a_expr, const char* b_expr, double a, double b) {
  const double scale = std::max(std::fabs(a), std::fabs(b));
  if (a == b || std::fabs(a - b) <= kRelative * scale) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << a_expr << " = " << a << " vs " << b_expr << " = " << b
                                       << " (relative " << std::fabs(a - b) / scale << ")";
}
#define EXPECT_REL(a, b) EXPECT_PRED_FORMAT2(near_rel, a, b)

int system_rank(GnssSystem system) {
  return static_cast<int>(std::find(kAllSystems.begin(), kAllSystems.end(), system) -
                          kAllSystems.begin());
}

// The order the writer uses: system, satellite, Galileo I/NAV before F/NAV, toe (stable).
void sort_like_writer(NavigationData& data) {
  std::stable_sort(data.kepler.begin(), data.kepler.end(),
                   [](const KeplerEphemeris& a, const KeplerEphemeris& b) {
                     const auto key = [](const KeplerEphemeris& e) {
                       return std::make_tuple(system_rank(e.satellite.system), e.satellite.number,
                                              e.message == NavMessage::kGalileoFnav ? 1 : 0);
                     };
                     if (key(a) != key(b)) return key(a) < key(b);
                     return a.toe < b.toe;
                   });
  auto by_satellite_toe = [](const auto& a, const auto& b) {
    if (a.satellite != b.satellite) return a.satellite < b.satellite;
    return a.toe < b.toe;
  };
  std::stable_sort(data.glonass.begin(), data.glonass.end(), by_satellite_toe);
  std::stable_sort(data.sbas.begin(), data.sbas.end(), by_satellite_toe);
}

void expect_same_kepler(const KeplerEphemeris& a, const KeplerEphemeris& b) {
  SCOPED_TRACE(a.satellite.to_string() + " toe " + a.toe.to_iso8601(TimeScale::kGpst, 0) +
               " from " + a.source);
  EXPECT_EQ(a.satellite, b.satellite);
  EXPECT_EQ(a.message, b.message);
  EXPECT_EQ(a.toc, b.toc);
  EXPECT_EQ(a.toe, b.toe);
  EXPECT_EQ(a.week, b.week);
  EXPECT_REL(a.toe_sow, b.toe_sow);
  EXPECT_REL(a.af0_s, b.af0_s);
  EXPECT_REL(a.af1_s_per_s, b.af1_s_per_s);
  EXPECT_REL(a.af2_s_per_s2, b.af2_s_per_s2);
  EXPECT_REL(a.sqrt_a_sqrtm, b.sqrt_a_sqrtm);
  EXPECT_REL(a.eccentricity, b.eccentricity);
  EXPECT_REL(a.i0_rad, b.i0_rad);
  EXPECT_REL(a.omega0_rad, b.omega0_rad);
  EXPECT_REL(a.omega_rad, b.omega_rad);
  EXPECT_REL(a.m0_rad, b.m0_rad);
  EXPECT_REL(a.delta_n_rad_per_s, b.delta_n_rad_per_s);
  EXPECT_REL(a.idot_rad_per_s, b.idot_rad_per_s);
  EXPECT_REL(a.omega_dot_rad_per_s, b.omega_dot_rad_per_s);
  EXPECT_REL(a.cuc_rad, b.cuc_rad);
  EXPECT_REL(a.cus_rad, b.cus_rad);
  EXPECT_REL(a.crc_m, b.crc_m);
  EXPECT_REL(a.crs_m, b.crs_m);
  EXPECT_REL(a.cic_rad, b.cic_rad);
  EXPECT_REL(a.cis_rad, b.cis_rad);
  EXPECT_REL(a.group_delays.tgd_s, b.group_delays.tgd_s);
  EXPECT_REL(a.group_delays.bgd_e1e5a_s, b.group_delays.bgd_e1e5a_s);
  EXPECT_REL(a.group_delays.bgd_e1e5b_s, b.group_delays.bgd_e1e5b_s);
  EXPECT_REL(a.group_delays.tgd1_s, b.group_delays.tgd1_s);
  EXPECT_REL(a.group_delays.tgd2_s, b.group_delays.tgd2_s);
  EXPECT_EQ(a.iode, b.iode);
  EXPECT_EQ(a.iodc, b.iodc);
  EXPECT_EQ(a.health, b.health);
  EXPECT_REL(a.accuracy_m, b.accuracy_m);
  EXPECT_REL(a.fit_interval_h, b.fit_interval_h);
  EXPECT_EQ(a.data_source, b.data_source);
  EXPECT_EQ(a.codes_on_l2, b.codes_on_l2);
  EXPECT_EQ(a.l2p_data_flag, b.l2p_data_flag);
  EXPECT_REL(a.transmission_time_sow, b.transmission_time_sow);
}

void expect_same_vector(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  for (Eigen::Index i = 0; i < 3; ++i) EXPECT_REL(a[i], b[i]);
}

void expect_same_glonass(const GlonassEphemeris& a, const GlonassEphemeris& b) {
  SCOPED_TRACE(a.satellite.to_string() + " t_b " + a.toe.to_iso8601(TimeScale::kUtc, 0) + " from " +
               a.source);
  EXPECT_EQ(a.satellite, b.satellite);
  EXPECT_EQ(a.toe, b.toe);
  EXPECT_REL(a.minus_tau_n_s, b.minus_tau_n_s);
  EXPECT_REL(a.gamma_n, b.gamma_n);
  EXPECT_REL(a.message_frame_time_s, b.message_frame_time_s);
  expect_same_vector(a.position_m, b.position_m);
  expect_same_vector(a.velocity_mps, b.velocity_mps);
  expect_same_vector(a.acceleration_mps2, b.acceleration_mps2);
  EXPECT_EQ(a.health, b.health);
  EXPECT_EQ(a.frequency_channel, b.frequency_channel);
  EXPECT_REL(a.age_days, b.age_days);
  EXPECT_FALSE(b.delta_tau_n_s.has_value());  // RINEX 3.04 has no fourth GLONASS line
}

void expect_same_sbas(const SbasEphemeris& a, const SbasEphemeris& b) {
  SCOPED_TRACE(a.satellite.to_string() + " t0 " + a.toe.to_iso8601(TimeScale::kGpst, 0) + " from " +
               a.source);
  EXPECT_EQ(a.satellite, b.satellite);
  EXPECT_EQ(a.toe, b.toe);
  EXPECT_REL(a.agf0_s, b.agf0_s);
  EXPECT_REL(a.agf1_s_per_s, b.agf1_s_per_s);
  EXPECT_REL(a.transmission_time_sow, b.transmission_time_sow);
  expect_same_vector(a.position_m, b.position_m);
  expect_same_vector(a.velocity_mps, b.velocity_mps);
  expect_same_vector(a.acceleration_mps2, b.acceleration_mps2);
  EXPECT_EQ(a.health, b.health);
  EXPECT_REL(a.accuracy_m, b.accuracy_m);
  EXPECT_EQ(a.iodn, b.iodn);
}

void expect_same_klobuchar(const std::optional<KlobucharCoefficients>& a,
                           const std::optional<KlobucharCoefficients>& b) {
  ASSERT_EQ(a.has_value(), b.has_value());
  if (!a) return;
  for (size_t i = 0; i < 4; ++i) {
    EXPECT_REL(a->alpha[i], b->alpha[i]);
    EXPECT_REL(a->beta[i], b->beta[i]);
  }
}

// Writes `original`, reads the text back and compares everything.
void expect_round_trip(NavigationData original) {
  const std::string text = format_rinex3_nav(original);
  auto read_back = parse_rinex_nav("round-trip.rnx", text);
  ASSERT_TRUE(read_back.ok()) << read_back.error().message;
  const NavigationData& copy = *read_back;
  sort_like_writer(original);

  ASSERT_EQ(copy.kepler.size(), original.kepler.size());
  ASSERT_EQ(copy.glonass.size(), original.glonass.size());
  ASSERT_EQ(copy.sbas.size(), original.sbas.size());
  for (size_t i = 0; i < original.kepler.size(); ++i)
    expect_same_kepler(original.kepler[i], copy.kepler[i]);
  for (size_t i = 0; i < original.glonass.size(); ++i)
    expect_same_glonass(original.glonass[i], copy.glonass[i]);
  for (size_t i = 0; i < original.sbas.size(); ++i)
    expect_same_sbas(original.sbas[i], copy.sbas[i]);

  expect_same_klobuchar(original.ionosphere.gps, copy.ionosphere.gps);
  expect_same_klobuchar(original.ionosphere.qzss, copy.ionosphere.qzss);
  expect_same_klobuchar(original.ionosphere.beidou, copy.ionosphere.beidou);
  expect_same_klobuchar(original.ionosphere.navic, copy.ionosphere.navic);
  ASSERT_EQ(original.ionosphere.galileo.has_value(), copy.ionosphere.galileo.has_value());
  if (original.ionosphere.galileo) {
    EXPECT_REL(original.ionosphere.galileo->ai0_sfu, copy.ionosphere.galileo->ai0_sfu);
    EXPECT_REL(original.ionosphere.galileo->ai1_sfu_per_deg,
               copy.ionosphere.galileo->ai1_sfu_per_deg);
    EXPECT_REL(original.ionosphere.galileo->ai2_sfu_per_deg2,
               copy.ionosphere.galileo->ai2_sfu_per_deg2);
  }
  ASSERT_EQ(copy.time_corrections.size(), original.time_corrections.size());
  for (size_t i = 0; i < original.time_corrections.size(); ++i) {
    const auto& a = original.time_corrections[i];
    const auto& b = copy.time_corrections[i];
    EXPECT_EQ(a.type, b.type);
    EXPECT_REL(a.a0_s, b.a0_s);
    EXPECT_REL(a.a1_s_per_s, b.a1_s_per_s);
    EXPECT_EQ(a.reference_time, b.reference_time) << a.type;
  }
  EXPECT_EQ(original.leap_seconds, copy.leap_seconds);
}

TEST(RinexNavRoundTrip, RealEsbcMixedFile) {
  const auto path = SKYTRACE_SHARED_FILE("real/esbc_2020177/ESBC00DNK_R_20201770000_01D_MN.rnx");
  auto original = read_rinex_nav(path);
  ASSERT_TRUE(original.ok()) << original.error().message;
  // The file holds G, R, E, C, J and S records and GAL/GPSA/GPSB, GAGP/GAUT/GPUT header lines.
  EXPECT_GT(original->kepler.size(), 2000u);
  EXPECT_GT(original->glonass.size(), 400u);
  EXPECT_GT(original->sbas.size(), 2000u);
  EXPECT_EQ(original->time_corrections.size(), 3u);
  expect_round_trip(std::move(*original));
}

TEST(RinexNavRoundTrip, NominalConstellation) {
  const GnssTime start =
      GnssTime::from_calendar(CalendarTime{2020, 6, 27, 23, 0, 0.0}, TimeScale::kGpst);
  // Across the GPS week change of Saturday/Sunday, where transmission times turn negative.
  auto data = make_nominal_constellation(start, 3 * 3600.0);
  ASSERT_TRUE(data.ok()) << data.error().message;
  expect_round_trip(std::move(*data));
}

}  // namespace
}  // namespace skytrace::orbits
