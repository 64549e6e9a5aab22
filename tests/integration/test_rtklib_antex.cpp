// End to end, the receiver antenna's phase centre (receiver.antex): a noise-free base/rover pair of
// the nominal constellation (no data needed), the rover's antenna with decimetre offsets and
// millimetre elevation-dependent variations from an ANTEX file written here. RTKLIB's rnx2rtkp in
// static RTK (GPS L1+L2) must put the rover back on its reference point when given the same ANTEX
// file (antenna named by the RINEX header, ant1-anttype=*), exactly as well as for a pair without
// any antenna model, and off by about the offsets when not. (rnx2rtkp's single-point mode applies
// no receiver antenna model, so the relative mode is the check.)
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "process.hpp"
#include "rtklib.hpp"
#include "skytrace/core/frames.hpp"
#include "test_support.hpp"

namespace skytrace {
namespace {

std::string record(const std::string& content, const std::string& label) {
  std::string line = content;
  line.resize(60, ' ');
  return line + label + "\n";
}

// SKYTEST1 NONE: G01 north 1.5, east -2.0, up 90 mm; G02 north 0.5, east 1.0, up 120 mm; NOAZI
// variations over zenith 0-90 by 5 degrees, a few millimetres.
std::string antex_text() {
  std::string text = record("     1.4            M", "ANTEX VERSION / SYST") + record("A", "PCV TYPE / REFANT") +
                     record("", "END OF HEADER") + record("", "START OF ANTENNA") +
                     record("SKYTEST1        NONE", "TYPE / SERIAL NO") + record("     0.0", "DAZI") +
                     record("     0.0  90.0   5.0", "ZEN1 / ZEN2 / DZEN") + record("     2", "# OF FREQUENCIES");
  struct Block {
    const char* code;
    double north_mm, east_mm, up_mm, quadratic_mm, linear_mm;
  };
  for (const Block& b : {Block{"G01", 1.5, -2.0, 90.0, -3.0, 1.5}, Block{"G02", 0.5, 1.0, 120.0, -4.0, 0.0}}) {
    char offsets[40];
    std::snprintf(offsets, sizeof offsets, "%10.2f%10.2f%10.2f", b.north_mm, b.east_mm, b.up_mm);
    std::string noazi = "   NOAZI";
    for (int zenith_deg = 0; zenith_deg <= 90; zenith_deg += 5) {
      const double x = zenith_deg / 90.0;
      char cell[16];
      std::snprintf(cell, sizeof cell, "%8.2f", b.quadratic_mm * x * x + b.linear_mm * x);
      noazi += cell;
    }
    text += record(std::string("   ") + b.code, "START OF FREQUENCY") + record(offsets, "NORTH / EAST / UP") + noazi +
            "\n" + record(std::string("   ") + b.code, "END OF FREQUENCY");
  }
  return text + record("", "END OF ANTENNA");
}

const Geodetic kBase{48.1, 11.6, 520.0};
const Geodetic kRover{48.105, 11.61, 530.0};

std::string pair_scenario(bool rover_antex) {
  return std::string("name: antex-pair\n"
                     "time:\n  start: 2026-03-01T12:00:00\n  scale: GPST\n  duration_s: 1800\n  interval_s: 30\n"
                     "receivers:\n"
                     "  - name: BASE\n    position:\n      lla_deg_m: [48.1, 11.6, 520.0]\n"
                     "    elevation_mask_deg: 5\n    profile: ideal\n    signals: [G1C, G2W]\n"
                     "  - name: ROVR\n    position:\n      lla_deg_m: [48.105, 11.61, 530.0]\n"
                     "    elevation_mask_deg: 5\n    profile: ideal\n    signals: [G1C, G2W]\n"
                     "    antenna_type: \"SKYTEST1        NONE\"\n") +
         (rover_antex ? "    antex: test.atx\n" : "") +
         "ephemeris:\n  nominal: true\n"
         "models:\n  ionosphere: klobuchar\n  troposphere: saastamoinen\n  receiver_clock: ideal\n  noise: false\n";
}

struct Outcome {
  size_t epochs = 0, fixed = 0;
  Eigen::Vector3d last_error_enu_m = Eigen::Vector3d::Zero();  // of the last (converged) epoch
};

// rnx2rtkp static RTK of `out_dir`'s pair, with or without the ANTEX file for the rover.
Outcome rtk(const std::filesystem::path& dir, const std::filesystem::path& out_dir, bool with_antex,
            const std::string& label) {
  const Eigen::Vector3d base = geodetic_to_ecef(kBase);
  const auto config = dir / (label + ".conf");
  std::ofstream conf(config);
  conf << "pos1-posmode=static\npos1-frequency=l1+l2\npos1-soltype=forward\npos1-elmask=10\n"
          "pos1-ionoopt=brdc\npos1-tropopt=saas\npos1-sateph=brdc\npos1-navsys=1\npos2-armode=continuous\n"
          "ant2-postype=xyz\n"
       << "ant2-pos1=" << std::to_string(base.x()) << "\nant2-pos2=" << std::to_string(base.y())
       << "\nant2-pos3=" << std::to_string(base.z()) << "\nout-solformat=xyz\n";
  if (with_antex) conf << "file-rcvantfile=" << (dir / "test.atx").string() << "\nant1-anttype=*\npos1-posopt2=on\n";
  conf.close();
  const auto solution = dir / (label + ".pos");
  const auto r = test::run_command("rnx2rtkp -k " + test::shell_quote(config.string()) + " -o " +
                                   test::shell_quote(solution.string()) + " " +
                                   test::shell_quote((out_dir / "obs_ROVR.rnx").string()) + " " +
                                   test::shell_quote((out_dir / "obs_BASE.rnx").string()) + " " +
                                   test::shell_quote((out_dir / "nav.rnx").string()));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  Outcome out;
  const auto solutions = test::read_rtklib_xyz(solution);
  out.epochs = solutions.size();
  for (const auto& s : solutions) out.fixed += s.quality == 1 ? 1 : 0;
  if (!solutions.empty()) {
    const LocalFrame frame{kRover, 0.0};
    out.last_error_enu_m = frame.ecef_to_local_rotation() * (solutions.back().ecef_m - geodetic_to_ecef(kRover));
  }
  return out;
}

TEST(RtklibAntex, RoverWithAntexLandsOnItsReferencePointOnlyWhenRtklibAppliesTheSameFile) {
  if (!test::program_available("rnx2rtkp")) GTEST_SKIP() << "rnx2rtkp (Debian package rtklib) is not installed";
  const auto dir = test::make_temp_dir("rtklib_antex");
  std::ofstream(dir / "test.atx") << antex_text();
  for (const bool antex : {false, true}) {
    const std::string name = antex ? "pair" : "pair_plain";
    std::ofstream(dir / (name + ".yaml")) << pair_scenario(antex);
    const auto r = test::run_command(test::shell_quote(test::skytrace_executable().string()) + " run " +
                                     test::shell_quote((dir / (name + ".yaml")).string()) + " --out " +
                                     test::shell_quote((dir / name).string()) + " --quiet");
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  // The same pair without any antenna model: what RTKLIB's RTK gives on this baseline.
  const Outcome plain = rtk(dir, dir / "pair_plain", false, "plain");
  const Outcome applied = rtk(dir, dir / "pair", true, "applied");
  const Outcome ignored = rtk(dir, dir / "pair", false, "ignored");
  std::printf("[ figures ] rnx2rtkp static RTK GPS L1+L2, rover with ANTEX PCO 90/120 mm up: error ENU of the last "
              "epoch, no model anywhere (%.4f, %.4f, %.4f) m; ANTEX given to RTKLIB (%.4f, %.4f, %.4f) m; not given "
              "(%.4f, %.4f, %.4f) m\n",
              plain.last_error_enu_m.x(), plain.last_error_enu_m.y(), plain.last_error_enu_m.z(),
              applied.last_error_enu_m.x(), applied.last_error_enu_m.y(), applied.last_error_enu_m.z(),
              ignored.last_error_enu_m.x(), ignored.last_error_enu_m.y(), ignored.last_error_enu_m.z());
  for (const Outcome* o : {&plain, &applied, &ignored}) {
    EXPECT_GE(o->epochs, 60u);
    EXPECT_GE(o->fixed, o->epochs * 9 / 10);
  }
  // Given the file, RTKLIB lands where it lands without any antenna: the model is RTKLIB's.
  EXPECT_LT((applied.last_error_enu_m - plain.last_error_enu_m).norm(), 0.0005);
  EXPECT_LT(applied.last_error_enu_m.norm(), 0.005);
  // Not given: off upwards by about the offsets (90 mm on L1, 120 mm on L2).
  EXPECT_GT(ignored.last_error_enu_m.z() - plain.last_error_enu_m.z(), 0.07);
  EXPECT_LT(ignored.last_error_enu_m.z() - plain.last_error_enu_m.z(), 0.13);
  EXPECT_LT(ignored.last_error_enu_m.head<2>().norm(), 0.01);
}

}  // namespace
}  // namespace skytrace
