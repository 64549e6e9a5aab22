// Guards the observation model against unintended change: short runs of the quick-start scenario
// (nominal constellation, no downloaded data; courtyard world, loop noise, cycle slips, the PolarX5
// clock; once with multipath) must give the recorded FNV-1a 64 digests of the observation records
// of obs.rnx (after END OF HEADER, so that a version or header change does not count) and of
// truth.csv. The generator was split into stages (issue #13) with these outputs byte-identical.
// truth.csv's digests were re-recorded when it gained its last column antenna_pc_m (ANTEX phase
// centres, issue #13): obs.rnx unchanged, truth.csv the old rows plus that column (0.0000 or empty).
// The run writes truth.csv.zst (output.truth_format csv.zst, issue #21): the digest is of its
// decompressed content, the same bytes as the plain truth.csv (tests/integration/test_truth_format).
//
// Re-recorded (obs.rnx and truth.csv) when GPS L2 P(Y) got its power per block and semi-codeless
// channels their own threshold (issue #13, docs/validation.md "GPS L2C and L2 P(Y) power per
// satellite block"): only G2W records changed. Again when semi-codeless channels report their L1
// C/A channel's Doppler (D2W): only that column changed.
//
// Again (obs.rnx and truth.csv) for foliage fading (models.foliage_fading, on by default with noise;
// issue #19): the courtyard's tree crowns fade the signals through them. With
// --set models.foliage_fading=false obs.rnx gives the previous digests (57e98cfed6d4ca33,
// 732abd079afaceba); truth.csv also gained the columns foliage_code_m, foliage_phase_m,
// foliage_power_db.
//
// Again (QuickstartMultipath) when a receiver at a fixed position got its paths by sky cell
// (models.static_sky_cell_deg, issue #15, docs/adr/0006-static-paths-by-sky-cell.md); with the cells
// off the run gives the previous digests (QuickstartMultipathSearchedEveryEpoch).
//
// When a model change is intended: check the new outputs (skytrace compare, the report), then
// record the digests this test prints on failure, and say so in the commit message.
//
// Floating point: the digests hold for the same compiler and flags (the CI's GCC 12, -O3, x86-64
// without -march, so no FMA contraction); another compiler, -ffast-math, -march=native (FMA) or
// another libm may change the last bits of some numbers and so the digests without any model
// change. Then compare the outputs numerically and re-record.
#include <gtest/gtest.h>

#include <cstdint>
#include <fstream>
#include <sstream>

#include "process.hpp"
#include "test_support.hpp"
#include "zst_text.hpp"

namespace skytrace {
namespace {

std::uint64_t fnv1a64(const std::string& bytes) {
  std::uint64_t h = 0xcbf29ce484222325ULL;
  for (const unsigned char c : bytes) {
    h ^= c;
    h *= 0x100000001b3ULL;
  }
  return h;
}

std::string read_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string hex(std::uint64_t v) {
  std::ostringstream s;
  s << std::hex << v;
  return s.str();
}

struct Digests {
  std::string obs_records;
  std::string truth;
};

Digests run_quickstart(const std::string& name, const std::string& sets) {
  const auto out = test::make_temp_dir("observation_digest_" + name);
  const auto scenario = test::source_dir() / "examples" / "quickstart.yaml";
  // SOURCE_DATE_EPOCH would change the header only; unset anyway so the run is the reference one.
  const auto r = test::run_command("env -u SOURCE_DATE_EPOCH " + test::shell_quote(test::skytrace_executable().string()) +
                                   " run " + test::shell_quote(scenario.string()) + " --out " +
                                   test::shell_quote(out.string()) + " --quiet " + sets);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  const std::string obs = read_bytes(out / "obs.rnx");
  const auto header_end = obs.find("END OF HEADER");
  EXPECT_NE(header_end, std::string::npos);
  const std::string records = header_end == std::string::npos ? obs : obs.substr(obs.find('\n', header_end) + 1);
  EXPECT_GT(records.size(), 10000u);
  return Digests{hex(fnv1a64(records)), hex(fnv1a64(test::read_zst_text(out / "truth.csv.zst")))};
}

TEST(ObservationDigest, QuickstartMinute) {
  const Digests d = run_quickstart("quick", "--set time.duration_s=60");
  EXPECT_EQ(d.obs_records, "2c739f8104cccda5") << "obs.rnx records changed (see the comment at the top to re-record)";
  EXPECT_EQ(d.truth, "4cfa797d1db99be5") << "truth.csv changed (see the comment at the top to re-record)";
}

TEST(ObservationDigest, QuickstartMultipath) {
  const Digests d = run_quickstart("multipath", "--set time.duration_s=30 --set models.multipath=true");
  EXPECT_EQ(d.obs_records, "4da22daa7c8543fb") << "obs.rnx records changed (see the comment at the top to re-record)";
  EXPECT_EQ(d.truth, "64e6d290183bb41d") << "truth.csv changed (see the comment at the top to re-record)";
}

TEST(ObservationDigest, QuickstartMultipathSearchedEveryEpoch) {
  const Digests d = run_quickstart("multipath-every-epoch",
                                   "--set time.duration_s=30 --set models.multipath=true --set models.static_sky_cell_deg=0");
  EXPECT_EQ(d.obs_records, "18acfedd7cbdaecd") << "obs.rnx records changed (see the comment at the top to re-record)";
  EXPECT_EQ(d.truth, "3b45fcedf813510b") << "truth.csv changed (see the comment at the top to re-record)";
}

}  // namespace
}  // namespace skytrace
