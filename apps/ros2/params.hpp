// The ROS 2 command line of the node, without rcl: `--ros-args`, `--params-file FILE`,
// `-p name:=value`, `-r __ns:=/ns`, `-r __node:=name`, `-r from:=to`; and parameters files as
// `ros2 run ... --params-file` reads them:
//   skytrace:                 # the node's name, its full name (/ns/skytrace), or /** for every node
//     ros__parameters:
//       scenario: /path/to/scenario.yaml
//       rate_hz: 10.0
// Later sources win: files in order, then -p. Values stay YAML nodes until the node reads them.
#pragma once

#include <yaml-cpp/yaml.h>

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "skytrace/core/error.hpp"

namespace skytrace::ros2_node {

struct CommandLine {
  std::string node_name = "skytrace";
  // Topics are relative to it: /skytrace/fix by default, as the ROS 1 node publishes.
  std::string node_namespace = "/skytrace";
  std::vector<std::string> params_files;
  std::vector<std::pair<std::string, std::string>> param_overrides;  // -p name:=value (value as YAML)
  std::map<std::string, std::string> remappings;                     // -r from:=to, topic names
  bool help = false;
};

// Errors name the argument (exit code 2).
[[nodiscard]] Result<CommandLine> parse_command_line(int argc, const char* const* argv);

// "/" for "", a leading '/' added, no trailing '/'; an error for characters ROS 2 refuses.
[[nodiscard]] Result<std::string> normalize_namespace(const std::string& ns);

// The node's parameters from the files and overrides, as YAML nodes by name. Errors name the file
// and what is wrong with it (exit code 3).
[[nodiscard]] Result<std::map<std::string, YAML::Node>> load_parameters(const CommandLine& command_line);

// A topic name resolved as rcl does: absolute names unchanged, `~/x` in the node's private
// namespace (/ns/node/x), others relative to the namespace; remappings applied to the result.
[[nodiscard]] Result<std::string> resolve_topic_name(const std::string& name, const CommandLine& command_line);

// Reading typed parameters: errors name the parameter and the type expected.
class Parameters {
 public:
  explicit Parameters(std::map<std::string, YAML::Node> values) : values_(std::move(values)) {}
  [[nodiscard]] bool has(const std::string& name) const { return values_.count(name) > 0; }
  [[nodiscard]] Result<std::string> get_string(const std::string& name, const std::string& fallback) const;
  [[nodiscard]] Result<double> get_double(const std::string& name, double fallback) const;
  [[nodiscard]] Result<bool> get_bool(const std::string& name, bool fallback) const;
  [[nodiscard]] Result<std::vector<double>> get_doubles(const std::string& name) const;  // empty when absent
  [[nodiscard]] Result<std::vector<std::string>> get_strings(const std::string& name) const;
  // Names given but never read (a typo the user should hear about).
  [[nodiscard]] std::vector<std::string> unread() const;

 private:
  std::map<std::string, YAML::Node> values_;
  mutable std::map<std::string, bool> read_;
};

}  // namespace skytrace::ros2_node
