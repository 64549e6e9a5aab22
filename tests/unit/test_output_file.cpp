// Outputs never replace what the output path is: regular files atomically, links followed, devices
// and FIFOs written in place, folders refused; YAML mappings with a key twice are found.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <fstream>
#include <sstream>

#include "skytrace/core/output_file.hpp"
#include "skytrace/core/yaml_field.hpp"
#include "test_support.hpp"

namespace skytrace {
namespace {

namespace fs = std::filesystem;

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

class OutputFile : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = test::make_temp_dir(std::string("output_file_") +
                               ::testing::UnitTest::GetInstance()->current_test_info()->name());
  }
  // Nothing but `expected` in the folder: no temporary file left behind.
  void expect_only(const std::vector<std::string>& expected) {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(dir_)) names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    EXPECT_EQ(names, expected);
  }
  fs::path dir_;
};

TEST_F(OutputFile, RegularFileIsReplacedWhole) {
  std::ofstream(dir_ / "a.csv") << "old\n";
  ASSERT_TRUE(write_file_atomically(dir_ / "a.csv", "new\n").ok());
  EXPECT_EQ(read_text(dir_ / "a.csv"), "new\n");
  expect_only({"a.csv"});
}

TEST_F(OutputFile, SymlinkIsFollowedAndKept) {
  fs::create_directories(dir_ / "real");
  fs::create_symlink("real/target.csv", dir_ / "link.csv");  // relative, dangling until written
  ASSERT_TRUE(write_file_atomically(dir_ / "link.csv", "through\n").ok());
  EXPECT_TRUE(fs::is_symlink(dir_ / "link.csv"));
  EXPECT_EQ(read_text(dir_ / "real" / "target.csv"), "through\n");
  const auto resolved = resolve_output_target(dir_ / "link.csv");
  ASSERT_TRUE(resolved.ok());
  EXPECT_EQ(resolved->kind, OutputKind::kFile);
  EXPECT_EQ(resolved->path, dir_ / "real/target.csv");
}

TEST_F(OutputFile, SymlinkLoopIsAnError) {
  fs::create_symlink("b", dir_ / "a");
  fs::create_symlink("a", dir_ / "b");
  const auto st = write_file_atomically(dir_ / "a", "x");
  ASSERT_FALSE(st.ok());
  EXPECT_EQ(st.error().code, ErrorCode::kOutput);
  EXPECT_NE(st.error().message.find("too many levels of symbolic links"), std::string::npos);
}

TEST_F(OutputFile, DevicesAreWrittenInPlace) {
  const auto resolved = resolve_output_target("/dev/null");
  ASSERT_TRUE(resolved.ok());
  EXPECT_EQ(resolved->kind, OutputKind::kStream);
  ASSERT_TRUE(write_file_atomically("/dev/null", "discarded\n").ok());
  struct stat info {};
  ASSERT_EQ(stat("/dev/null", &info), 0);
  EXPECT_TRUE(S_ISCHR(info.st_mode));
  const auto full = write_file_atomically("/dev/full", "no room\n");
  ASSERT_FALSE(full.ok());
  EXPECT_EQ(full.error().code, ErrorCode::kOutput);
  EXPECT_NE(full.error().message.find("no space left"), std::string::npos) << full.error().message;
}

TEST_F(OutputFile, InstalledFileIntoADeviceIsCopiedAndRemoved) {
  std::ofstream(dir_ / "finished.tmp") << "payload\n";
  ASSERT_TRUE(install_output_file(dir_ / "finished.tmp", "/dev/null").ok());
  expect_only({});
}

TEST_F(OutputFile, FolderIsRefused) {
  const auto st = write_file_atomically(dir_, "x");
  ASSERT_FALSE(st.ok());
  EXPECT_EQ(st.error().code, ErrorCode::kOutput);
  EXPECT_NE(st.error().message.find("is a folder"), std::string::npos);
}

TEST_F(OutputFile, MissingFolderIsAnOutputError) {
  const auto st = write_file_atomically(dir_ / "no" / "such" / "file.csv", "x");
  ASSERT_FALSE(st.ok());
  EXPECT_EQ(st.error().code, ErrorCode::kOutput);
}

TEST(YamlDuplicateKeys, FoundAtAnyDepthWithBothLines) {
  EXPECT_FALSE(find_duplicate_key(YAML::Load("a: 1\nb:\n  c: 2\n  d: 3\n"), "f.yaml"));
  const auto nested = find_duplicate_key(YAML::Load("a: 1\nb:\n  - c: 2\n    c: 3\n"), "f.yaml");
  ASSERT_TRUE(nested);
  EXPECT_EQ(*nested, "f.yaml:4: b[0].c: duplicate key (first at line 3; YAML allows a key once per mapping)");
  const auto top = find_duplicate_key(YAML::Load("name: x\nseed: 1\nname: y\n"), "s.yaml");
  ASSERT_TRUE(top);
  EXPECT_NE(top->find("s.yaml:3: name: duplicate key (first at line 1"), std::string::npos);
}

}  // namespace
}  // namespace skytrace
