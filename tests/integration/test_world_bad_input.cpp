// Bad worlds through `skytrace run`: every case ends with a clear message naming the file (and
// line, key or object), the documented exit code (3: bad input), and no outputs left behind; or,
// for what Gazebo itself skips (a missing model:// include), a run that says what it skipped.
#include <gtest/gtest.h>

#include <fstream>

#include "process.hpp"
#include "test_support.hpp"

namespace skytrace {
namespace {

constexpr int kExitInput = 3;  // apps/skytrace/commands.hpp

std::filesystem::path write_file(const std::filesystem::path& path, const std::string& text) {
  std::filesystem::create_directories(path.parent_path());
  std::ofstream out(path, std::ios::binary);
  out << text;
  return path;
}

std::string sdf_world(const std::string& models) {
  return R"(<?xml version="1.0"?>
<sdf version="1.9">
  <world name="w">
    <spherical_coordinates>
      <latitude_deg>47.0</latitude_deg>
      <longitude_deg>8.0</longitude_deg>
      <elevation>400</elevation>
    </spherical_coordinates>
)" + models + R"(
  </world>
</sdf>
)";
}

const char* kBlock = R"(
    <model name="block">
      <static>true</static>
      <pose>0 20 5 0 0 0</pose>
      <link name="link"><collision name="collision">
        <geometry><box><size>10 10 10</size></box></geometry>
      </collision></link>
    </model>)";

class WorldBadInput : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = test::make_temp_dir(std::string("world_bad_input_") +
                               ::testing::UnitTest::GetInstance()->current_test_info()->name());
  }

  // A 2-minute scenario at `position` with the given world keys.
  std::filesystem::path scenario(const std::string& world, const std::string& position = "[0, 0, 1.5]") const {
    return write_file(dir_ / "s.yaml", "name: bad\ntime:\n  start: 2020-06-25T00:00:00\n  duration_s: 120\n"
                                       "  interval_s: 30\nreceiver:\n  position:\n    world_enu_m: " +
                                           position + "\n  signals: [G1C]\nephemeris:\n  nominal: true\nworld:\n" + world);
  }

  test::ProcessResult run(const std::filesystem::path& scenario_file) const {
    return test::run_command(test::shell_quote(test::skytrace_executable().string()) + " run " +
                             test::shell_quote(scenario_file.string()) + " --out " + test::shell_quote(out().string()) +
                             " --quiet");
  }
  std::filesystem::path out() const { return dir_ / "out"; }

  // Stopped with exit code 3, the message holding every `expected` text, nothing written.
  void expect_refused(const test::ProcessResult& r, std::initializer_list<std::string> expected) const {
    EXPECT_EQ(r.exit_code, kExitInput) << r.output;
    for (const auto& text : expected) EXPECT_NE(r.output.find(text), std::string::npos) << "missing '" << text << "' in: " << r.output;
    EXPECT_EQ(r.output.find("terminate"), std::string::npos) << r.output;
    std::error_code ec;
    const bool empty = !std::filesystem::exists(out()) || std::filesystem::is_empty(out(), ec);
    EXPECT_TRUE(empty) << "outputs left behind in " << out();
  }

  std::filesystem::path dir_;
};

TEST_F(WorldBadInput, SdfThatIsNotXml) {
  write_file(dir_ / "w.sdf", "<sdf version=\"1.9\">\n  <world name=\"w\">\n    <model name=\"m\">\n  </world>\n</sdf>\n");
  expect_refused(run(scenario("  sdf: w.sdf\n")), {"w.sdf:4", "malformed XML"});
}

TEST_F(WorldBadInput, XmlThatIsNotValidSdf) {
  // A box size with two numbers: XML is fine, sdformat refuses the value.
  write_file(dir_ / "w.sdf", sdf_world(R"(<model name="m"><static>true</static><link name="l"><collision name="c">
      <geometry><box><size>1 2</size></box></geometry></collision></link></model>)"));
  expect_refused(run(scenario("  sdf: w.sdf\n")), {"w.sdf: malformed SDF", "w.sdf:10: Error reading element <size>"});
  // Not SDF at all (a URDF robot).
  write_file(dir_ / "robot.sdf", "<?xml version=\"1.0\"?>\n<robot name=\"r\"><link name=\"base\"/></robot>\n");
  expect_refused(run(scenario("  sdf: robot.sdf\n")), {"robot.sdf"});
}

TEST_F(WorldBadInput, MeshThatFailsToLoadStopsNamingTheFile) {
  write_file(dir_ / "models" / "kiosk" / "meshes" / "kiosk.dae", "<COLLADA>truncated");
  write_file(dir_ / "w.sdf", sdf_world(R"(<model name="kiosk"><static>true</static><link name="l"><collision name="c">
      <geometry><mesh><uri>model://kiosk/meshes/kiosk.dae</uri></mesh></geometry></collision></link></model>)"));
  expect_refused(run(scenario("  sdf: w.sdf\n  model_paths: [models]\n")), {"kiosk.dae", "kiosk/l/c", "w.sdf:"});
  // The same through world.meshes.
  write_file(dir_ / "broken.obj", "v 0 0\nf 1 2 3 4\n");
  expect_refused(run(scenario("  latitude_deg: 47\n  longitude_deg: 8\n  meshes:\n    - {file: broken.obj}\n")),
                 {"broken.obj"});
}

TEST_F(WorldBadInput, MissingModelIsSkippedWithAWarningNamingIt) {
  write_file(dir_ / "w.sdf", sdf_world(std::string(kBlock) + R"(
    <include><uri>model://fountain</uri><pose>30 0 0 0 0 0</pose></include>)"));
  const auto r = run(scenario("  sdf: w.sdf\n"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("warning: "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("model://fountain not found"), std::string::npos) << r.output;
  std::ifstream summary(out() / "summary.json");
  const std::string text((std::istreambuf_iterator<char>(summary)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("model://fountain not found"), std::string::npos);
}

TEST_F(WorldBadInput, OsmWithoutBuildings) {
  // Nothing usable: an error naming the file.
  write_file(dir_ / "empty.osm", "<?xml version='1.0'?>\n<osm version=\"0.6\">\n"
                                 "<node id=\"1\" version=\"1\" lat=\"47.0\" lon=\"8.0\"/>\n</osm>\n");
  expect_refused(run(scenario("  osm: empty.osm\n")), {"empty.osm: no buildings, trees or woods"});
  // Only trees: the run goes on and says so.
  write_file(dir_ / "park.osm", "<?xml version='1.0'?>\n<osm version=\"0.6\">\n"
                                "<node id=\"1\" version=\"1\" lat=\"47.0\" lon=\"8.0003\">"
                                "<tag k=\"natural\" v=\"tree\"/></node>\n</osm>\n");
  const auto r = run(scenario("  osm: park.osm\n  latitude_deg: 47\n  longitude_deg: 8\n"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("park.osm: no buildings in the OSM data, only vegetation"), std::string::npos) << r.output;
  // Not OSM at all.
  std::filesystem::remove_all(out());
  write_file(dir_ / "garbage.osm", "<osm><node id=\"1\" lat=\"x\"</osm>");
  expect_refused(run(scenario("  osm: garbage.osm\n")), {"garbage.osm"});
}

TEST_F(WorldBadInput, ReceiverInsideAWallNamesTheObject) {
  write_file(dir_ / "w.sdf", sdf_world(kBlock));
  expect_refused(run(scenario("  sdf: w.sdf\n", "[0, 20, 1.5]")), {"receiver 'bad'", "inside the object 'block/link/collision'"});
}

TEST_F(WorldBadInput, MovingModelErrorsNameKeyAndFile) {
  write_file(dir_ / "w.sdf", sdf_world(kBlock));
  write_file(dir_ / "bus.csv", "t,x,y,z,yaw\n0,0,0,0,0\n10,1,2,3\n");
  expect_refused(run(scenario("  sdf: w.sdf\n  moving:\n    - {model: bus, trajectory: bus.csv}\n")),
                 {"world.moving: no model named 'bus'", "block"});
  expect_refused(run(scenario("  sdf: w.sdf\n  moving:\n    - {model: block, trajectory: bus.csv}\n")),
                 {"bus.csv:3", "expected 5 columns"});
  expect_refused(run(scenario("  sdf: w.sdf\n  moving:\n    - {model: block, trajectory: nowhere.csv}\n")),
                 {"s.yaml:15: world.moving[0].trajectory: file not found"});
}

}  // namespace
}  // namespace skytrace
