// output.truth_format (issue #21): truth.csv.zst and paths.csv.zst by default, whose content is the
// plain-CSV run's truth.csv and paths.csv byte for byte; `csv` writes the plain files; another value
// is refused naming the key and the values it takes, as every scenario error (exit 3); a file size
// limit reached while the truth is written leaves no file behind.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "process.hpp"
#include "test_support.hpp"
#include "zst_text.hpp"

namespace skytrace {
namespace {

namespace fs = std::filesystem;

std::string read_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

class TruthFormat : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = test::make_temp_dir(std::string("truth_format_") + ::testing::UnitTest::GetInstance()->current_test_info()->name());
  }
  test::ProcessResult run(const std::string& name, const std::string& arguments) {
    const auto scenario = test::source_dir() / "examples" / "quickstart.yaml";
    return test::run_command(test::shell_quote(test::skytrace_executable().string()) + " run " +
                             test::shell_quote(scenario.string()) + " --out " + test::shell_quote((dir_ / name).string()) +
                             " --quiet --set time.duration_s=30 --set models.multipath=true " + arguments);
  }
  fs::path dir_;
};

TEST_F(TruthFormat, CompressedByDefaultWithThePlainContent) {
  auto r = run("zst", "");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = run("csv", "--set output.truth_format=csv");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = run("flag", "--truth-format csv");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* table : {"truth.csv", "paths.csv"}) {
    const std::string name(table);
    EXPECT_TRUE(fs::exists(dir_ / "zst" / (name + ".zst"))) << name;
    EXPECT_FALSE(fs::exists(dir_ / "zst" / name)) << name;
    EXPECT_TRUE(fs::exists(dir_ / "csv" / name)) << name;
    EXPECT_FALSE(fs::exists(dir_ / "csv" / (name + ".zst"))) << name;
    const std::string plain = read_bytes(dir_ / "csv" / name);
    ASSERT_GT(plain.size(), 10000u) << name;
    const std::string unpacked = test::read_zst_text(dir_ / "zst" / (name + ".zst"));
    EXPECT_TRUE(unpacked == plain) << name << ": the decompressed content differs from the plain CSV";
    EXPECT_TRUE(read_bytes(dir_ / "flag" / name) == plain) << name << ": --truth-format csv differs from the key";
    EXPECT_LT(read_bytes(dir_ / "zst" / (name + ".zst")).size(), plain.size() * 15 / 100) << name;
  }
  // summary.json records the choice.
  EXPECT_NE(read_bytes(dir_ / "zst" / "summary.json").find("\"truth_format\": \"csv.zst\""), std::string::npos);
  EXPECT_NE(read_bytes(dir_ / "csv" / "summary.json").find("\"truth_format\": \"csv\""), std::string::npos);
}

// Real readers of the file: the zstd tool (scripts/setup installs it) checks the frame and its
// checksum and gives the plain bytes; pandas (when Debian's python3-pandas and python3-zstandard are
// installed) opens it in the documented one line.
TEST_F(TruthFormat, RealReadersOpenTheCompressedTruth) {
  if (test::run_command("command -v zstd").exit_code != 0) GTEST_SKIP() << "zstd (the command) not installed: scripts/setup";
  auto r = run("zst", "");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = run("csv", "--truth-format csv");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto zst = dir_ / "zst" / "truth.csv.zst";
  r = test::run_command("zstd -q -t " + test::shell_quote(zst.string()));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  r = test::run_command("zstd -q -dc " + test::shell_quote(zst.string()) + " > " + test::shell_quote((dir_ / "unpacked.csv").string()));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(read_bytes(dir_ / "unpacked.csv") == read_bytes(dir_ / "csv" / "truth.csv"));
  if (test::run_command("/usr/bin/python3 -c 'import pandas, zstandard'").exit_code != 0) {
    GTEST_SKIP() << "pandas or zstandard (python3-pandas, python3-zstandard) not installed: the zstd tool was checked";
  }
  r = test::run_command("/usr/bin/python3 -c " +
                        test::shell_quote("import pandas as pd, sys; a = pd.read_csv(sys.argv[1]); b = pd.read_csv(sys.argv[2]); "
                                          "print(len(a), len(a.columns), a.equals(b))") +
                        " " + test::shell_quote(zst.string()) + " " + test::shell_quote((dir_ / "csv" / "truth.csv").string()));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find(" 40 True"), std::string::npos) << r.output;
}

TEST_F(TruthFormat, UnknownFormatIsRefusedNamingTheKey) {
  for (const char* arguments : {"--set output.truth_format=parquet", "--truth-format parquet"}) {
    const auto r = run("bad", arguments);
    EXPECT_EQ(r.exit_code, 3) << arguments << "\n" << r.output;
    EXPECT_NE(r.output.find("output.truth_format: unknown value 'parquet' (expected one of: csv.zst, csv)"),
              std::string::npos)
        << r.output;
    EXPECT_FALSE(fs::exists(dir_ / "bad") && !fs::is_empty(dir_ / "bad"));
  }
}

TEST_F(TruthFormat, FileSizeLimitLeavesNothingBehind) {
  // A file size limit (as a full disk would) reached by the compressed truth: a clear error, and
  // neither the truth nor any other output is left in --out.
  const auto scenario = test::source_dir() / "examples" / "quickstart.yaml";
  const std::string command = test::shell_quote(test::skytrace_executable().string()) + " run " +
                              test::shell_quote(scenario.string()) + " --out " + test::shell_quote((dir_ / "out").string()) +
                              " --quiet --set time.duration_s=1200 --set 'receiver.signals=[G1C]'";
  const auto r = test::run_command("bash -c " + test::shell_quote("trap '' XFSZ; ulimit -f 256; exec " + command));
  EXPECT_EQ(r.exit_code, 5) << r.output;
  EXPECT_NE(r.output.find("truth.csv.zst: write failed (file size limit exceeded)"), std::string::npos) << r.output;
  EXPECT_TRUE(!fs::exists(dir_ / "out") || fs::is_empty(dir_ / "out")) << "a failed run left files in " << dir_ / "out";
}

}  // namespace
}  // namespace skytrace
