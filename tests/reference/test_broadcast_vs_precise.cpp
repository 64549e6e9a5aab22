// Broadcast ephemerides against precise products of the same day: the independent numbers for
// the orbit layer. ESBC00DNK's merged navigation file of 2020-06-25 against the GRG (CNES/CLS)
// final MGEX orbits and 30-s clocks. Broadcast orbits are antenna phase centres and precise ones
// centres of mass, so the figures include the satellite antenna offsets (decimetres to a metre).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <vector>

#include "skytrace/core/constants.hpp"
#include "skytrace/orbits/broadcast.hpp"
#include "skytrace/orbits/precise.hpp"
#include "skytrace/orbits/rinex_nav.hpp"
#include "test_support.hpp"

namespace skytrace::orbits {
namespace {

double median(std::vector<double> v) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

double rms(const std::vector<double>& v) {
  double sum = 0.0;
  for (double x : v) sum += x * x;
  return v.empty() ? NAN : std::sqrt(sum / static_cast<double>(v.size()));
}

struct SystemFigures {
  std::vector<double> orbit_3d_m;
  std::vector<double> clock_m;  // after removing the per-epoch median of the system
  std::set<SatelliteId> satellites;
};

class BroadcastVsPrecise : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    const auto dir = test::shared_data_dir() / "real/esbc_2020177";
    if (!std::filesystem::exists(dir / "GRG0MGXFIN_20201770000_01D_30S_CLK.CLK")) return;
    auto nav = read_rinex_nav(dir / "ESBC00DNK_R_20201770000_01D_MN.rnx");
    auto sp3 = read_sp3({dir / "GRG0MGXFIN_20201760000_01D_15M_ORB.SP3", dir / "GRG0MGXFIN_20201770000_01D_15M_ORB.SP3"});
    auto clk = read_rinex_clock(dir / "GRG0MGXFIN_20201770000_01D_30S_CLK.CLK");
    ASSERT_TRUE(nav.ok()) << nav.error().message;
    ASSERT_TRUE(sp3.ok()) << sp3.error().message;
    ASSERT_TRUE(clk.ok()) << clk.error().message;
    auto precise = PreciseEphemerides::create(std::move(*sp3), std::move(*clk));
    ASSERT_TRUE(precise.ok()) << precise.error().message;
    const BroadcastEphemerides broadcast(std::move(*nav));
    const double c = constants::kSpeedOfLight_mps;

    const GnssTime start = GnssTime::parse_iso8601("2020-06-25T00:00:00", TimeScale::kGpst).value();
    for (int k = 0; k < 96; ++k) {  // every 15 min: the SP3 grid, so no orbit interpolation error
      const GnssTime t = start + 900.0 * k;
      std::map<GnssSystem, std::vector<std::pair<SatelliteId, double>>> clock_differences;
      for (const SatelliteId& sat : precise->satellites()) {
        // Galileo clocks: the F/NAV record refers to E1/E5a like the IGS products; orbits from
        // the default (I/NAV) record.
        const Signal clock_signal = sat.system == GnssSystem::kGalileo ? Signal{sat.system, '5', 'Q'}
                                                                        : Signal{sat.system, '1', 'C'};
        auto b = broadcast.state(sat, t);
        auto p = precise->orbit(sat, t);
        if (!b || !p) continue;
        figures_[sat.system].orbit_3d_m.push_back((b->position_m - p->position_m).norm());
        figures_[sat.system].satellites.insert(sat);
        auto b_clock = broadcast.state_for_signal(sat, clock_signal, t);
        auto p_clock = precise->clock(sat, t);
        if (b_clock && p_clock) clock_differences[sat.system].emplace_back(sat, c * (b_clock->clock_bias_s - p_clock->bias_s));
      }
      for (auto& [system, differences] : clock_differences) {
        std::vector<double> values;
        for (const auto& d : differences) values.push_back(d.second);
        const double common_m = median(values);
        for (double v : values) figures_[system].clock_m.push_back(v - common_m);
      }
    }
    for (const auto& [system, f] : figures_) {
      std::printf("[ figures ] %-8s %2zu satellites, %5zu satellite-epochs: orbit 3D median %.2f m, p95 %.2f m; "
                  "clock RMS %.2f m\n",
                  std::string(system_name(system)).c_str(), f.satellites.size(), f.orbit_3d_m.size(),
                  median(f.orbit_3d_m),
                  [orbit_3d_m = f.orbit_3d_m] {  // a copy: clang 14 cannot capture a structured binding
                    auto v = orbit_3d_m;
                    std::sort(v.begin(), v.end());
                    return v.empty() ? NAN : v[v.size() * 95 / 100];
                  }(),
                  rms(f.clock_m));
    }
  }

  void SetUp() override {
    if (figures_.empty()) GTEST_SKIP() << "ESBC 2020-177 data absent under " << test::shared_data_dir();
  }

  static inline std::map<GnssSystem, SystemFigures> figures_;
};

TEST_F(BroadcastVsPrecise, GpsOrbitsAndClocks) {
  const auto& f = figures_[GnssSystem::kGps];
  EXPECT_GE(f.satellites.size(), 28u);
  EXPECT_LE(median(f.orbit_3d_m), 3.0);
  EXPECT_LE(rms(f.clock_m), 1.5);
}

TEST_F(BroadcastVsPrecise, GalileoOrbitsAndClocks) {
  const auto& f = figures_[GnssSystem::kGalileo];
  EXPECT_GE(f.satellites.size(), 20u);
  EXPECT_LE(median(f.orbit_3d_m), 2.0);
  EXPECT_LE(rms(f.clock_m), 1.0);
}

TEST_F(BroadcastVsPrecise, GlonassOrbits) {
  const auto& f = figures_[GnssSystem::kGlonass];
  EXPECT_GE(f.satellites.size(), 20u);
  EXPECT_LE(median(f.orbit_3d_m), 5.0);
}

TEST_F(BroadcastVsPrecise, BeiDouAndQzssOrbits) {
  // GRG has no BeiDou GEO (C01-C05) in this product; the MEO and IGSO satellites it has must agree
  // as broadcast orbits do (a few metres).
  const auto& c = figures_[GnssSystem::kBeiDou];
  if (!c.orbit_3d_m.empty()) {
    EXPECT_LE(median(c.orbit_3d_m), 5.0);
  }
  const auto& j = figures_[GnssSystem::kQzss];
  if (!j.orbit_3d_m.empty()) {
    EXPECT_LE(median(j.orbit_3d_m), 5.0);
  }
}

}  // namespace
}  // namespace skytrace::orbits

namespace skytrace::orbits {
namespace {

// BeiDou GEO satellites (C01-C05) need the special rotation of the BDS ICD; GFZ's 2016-06-06
// product has four of them, with the merged broadcast file of that day.
TEST(BroadcastVsPreciseBeiDou, GeoAndOtherSatellitesAgreeWithGfzOrbits) {
  const auto dir = test::shared_data_dir() / "real/smartloc_berlin_potsdamer_platz_2016158";
  const auto nav_path = SKYTRACE_SHARED_FILE("real/smartloc_berlin_potsdamer_platz_2016158/BRDC00WRD_U_20161580000_01D_MN.rnx");
  auto nav = read_rinex_nav(nav_path);
  auto sp3 = read_sp3(dir / "gbm19001.sp3");
  ASSERT_TRUE(nav.ok()) << nav.error().message;
  ASSERT_TRUE(sp3.ok()) << sp3.error().message;
  auto precise = PreciseEphemerides::create(std::move(*sp3));
  ASSERT_TRUE(precise.ok()) << precise.error().message;
  const BroadcastEphemerides broadcast(std::move(*nav));
  std::vector<double> geo_m, other_m;
  std::set<SatelliteId> geo_satellites;
  const GnssTime start = GnssTime::parse_iso8601("2016-06-06T00:00:00", TimeScale::kGpst).value();
  for (int k = 0; k < 288; ++k) {
    const GnssTime t = start + 300.0 * k;
    for (const SatelliteId& sat : precise->satellites()) {
      if (sat.system != GnssSystem::kBeiDou) continue;
      auto b = broadcast.state(sat, t);
      auto p = precise->orbit(sat, t);
      if (!b || !p) continue;
      const double d = (b->position_m - p->position_m).norm();
      if (is_beidou_geo(sat)) {
        geo_m.push_back(d);
        geo_satellites.insert(sat);
      } else {
        other_m.push_back(d);
      }
    }
  }
  auto p95 = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v.empty() ? NAN : v[v.size() * 95 / 100];
  };
  std::printf("[ figures ] BeiDou GEO %zu satellites, %zu epochs: 3D median %.2f m, p95 %.2f m; IGSO/MEO %zu epochs: "
              "median %.2f m, p95 %.2f m\n",
              geo_satellites.size(), geo_m.size(), median(geo_m), p95(geo_m), other_m.size(), median(other_m),
              p95(other_m));
  EXPECT_GE(geo_satellites.size(), 3u);
  // A wrong GEO rotation puts the satellite thousands of kilometres away; broadcast GEO orbits are
  // good to a few metres.
  EXPECT_LE(median(geo_m), 10.0);
  EXPECT_LE(median(other_m), 5.0);
}

}  // namespace
}  // namespace skytrace::orbits
