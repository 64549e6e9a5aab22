// The optional modules of the skytrace command (docs/adr/0005-optional-modules.md): the command
// itself loads neither sdformat, GDAL nor Gazebo transport; the modules that do resolve every
// reference to skytrace in the command; a missing module is a clear error that leaves no outputs.
#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <sstream>

#include "process.hpp"
#include "test_support.hpp"

namespace skytrace {
namespace {

constexpr int kExitInput = 3;  // apps/skytrace/commands.hpp

std::filesystem::path module_dir() { return test::binary_dir() / "lib" / "skytrace"; }

// Lines of a command's output.
std::vector<std::string> lines_of(const std::string& command_line) {
  const test::ProcessResult r = test::run_command(command_line);
  EXPECT_EQ(r.exit_code, 0) << command_line << "\n" << r.output;
  std::vector<std::string> lines;
  std::istringstream in(r.output);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

TEST(Modules, TheCommandLinksNoSdformatGdalOrGazeboTransport) {
  if (!test::program_available("readelf")) GTEST_SKIP() << "readelf (binutils) absent";
  const auto dynamic = lines_of("readelf -d " + test::shell_quote(test::skytrace_executable().string()));
  std::vector<std::string> needed;
  for (const auto& line : dynamic) {
    if (line.find("(NEEDED)") != std::string::npos) needed.push_back(line);
  }
  ASSERT_FALSE(needed.empty());
  for (const auto& line : needed) {
    for (const char* heavy : {"sdformat", "gdal", "ignition", "protobuf", "proj"}) {
      EXPECT_EQ(line.find(heavy), std::string::npos) << "the command loads " << heavy << " at start: " << line;
    }
  }
}

TEST(Modules, EveryReferenceOfAModuleToSkytraceResolvesInTheCommand) {
  if (!test::program_available("nm")) GTEST_SKIP() << "nm (binutils) absent";
  std::set<std::string> defined;
  for (const auto& line : lines_of("nm -D --defined-only " + test::shell_quote(test::skytrace_executable().string()))) {
    const auto space = line.rfind(' ');
    if (space != std::string::npos) defined.insert(line.substr(space + 1));
  }
  int modules = 0;
  for (const auto& entry : std::filesystem::directory_iterator(module_dir())) {
    if (entry.path().extension() != ".so") continue;
    ++modules;
    int references = 0;
    for (const auto& line : lines_of("nm -D --undefined-only " + test::shell_quote(entry.path().string()))) {
      const auto space = line.rfind(' ');
      const std::string symbol = space == std::string::npos ? line : line.substr(space + 1);
      if (symbol.find("skytrace") == std::string::npos) continue;  // the libraries' own, resolved by their sonames
      ++references;
      EXPECT_TRUE(defined.count(symbol) != 0) << entry.path().filename() << " needs " << symbol
                                              << ", which the command does not export";
    }
    EXPECT_GT(references, 0) << entry.path();
  }
  EXPECT_GE(modules, 1) << module_dir();
}

TEST(Modules, AMissingModuleIsAClearErrorWithoutOutputs) {
  const auto contract = test::shared_data_dir().parent_path() / "contract" / "wall.yaml";
  if (!std::filesystem::exists(contract)) GTEST_SKIP() << contract << " absent";
  const auto dir = test::make_temp_dir("modules_missing");
  const auto out = dir / "out";
  const auto r = test::run_command("SKYTRACE_MODULE_DIR=" + test::shell_quote((dir / "none").string()) + " " +
                                   test::shell_quote(test::skytrace_executable().string()) + " run " +
                                   test::shell_quote(contract.string()) + " --out " + test::shell_quote(out.string()) +
                                   " --quiet");
  EXPECT_EQ(r.exit_code, kExitInput) << r.output;
  EXPECT_NE(r.output.find("SDF worlds"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("skytrace-world.so"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("SKYTRACE_MODULE_DIR"), std::string::npos) << r.output;
  const bool left = std::filesystem::exists(out) && !std::filesystem::is_empty(out);
  EXPECT_FALSE(left) << "outputs left in " << out;
  // The same scenario with the module where it belongs runs.
  const auto ok = test::run_command(test::shell_quote(test::skytrace_executable().string()) + " run " +
                                    test::shell_quote(contract.string()) + " --out " +
                                    test::shell_quote((dir / "ok").string()) + " --quiet");
  EXPECT_EQ(ok.exit_code, 0) << ok.output;
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace skytrace
