#include "params.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <set>

namespace skytrace::ros2_node {
namespace {

Error usage(std::string message) { return Error{ErrorCode::kInvalidArgument, std::move(message)}; }

// "a:=b" split at ":="; nullopt without it.
std::optional<std::pair<std::string, std::string>> split_assignment(const std::string& text) {
  const size_t at = text.find(":=");
  if (at == std::string::npos || at == 0) return std::nullopt;
  return std::make_pair(text.substr(0, at), text.substr(at + 2));
}

bool valid_name_characters(const std::string& name) {
  return std::all_of(name.begin(), name.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_' || c == '/' || c == '~';
  });
}

std::string fully_qualified_node_name(const CommandLine& c) {
  return c.node_namespace == "/" ? "/" + c.node_name : c.node_namespace + "/" + c.node_name;
}

// Parameters under ros__parameters: nested maps become dotted names, as rcl flattens them.
void flatten(const YAML::Node& node, const std::string& prefix, std::map<std::string, YAML::Node>& out) {
  for (const auto& entry : node) {
    const std::string name = prefix.empty() ? entry.first.as<std::string>() : prefix + "." + entry.first.as<std::string>();
    if (entry.second.IsMap()) {
      flatten(entry.second, name, out);
    } else {
      out[name] = entry.second;
    }
  }
}

bool key_matches_node(const std::string& key, const CommandLine& c) {
  const std::string fqn = fully_qualified_node_name(c);
  return key == "/**" || key == "**" || key == c.node_name || key == fqn || "/" + key == fqn ||
         key == "/**/" + c.node_name;
}

// Names inside a parameters file that could be meant for this node in the nested form
// (namespace: {node: {ros__parameters: ...}}): collected with their parameters.
void collect(const YAML::Node& map, const std::string& path, const CommandLine& c, const std::string& file,
             std::map<std::string, YAML::Node>& out, int& matched) {
  for (const auto& entry : map) {
    const std::string key = entry.first.as<std::string>();
    const std::string full = path.empty() ? key : path + "/" + key;
    if (!entry.second.IsMap()) continue;
    if (key_matches_node(full, c)) {
      const YAML::Node parameters = entry.second["ros__parameters"];
      if (!parameters) continue;
      if (!parameters.IsMap()) throw YAML::Exception(parameters.Mark(), full + ": ros__parameters must be a map");
      flatten(parameters, "", out);
      ++matched;
    } else if (!entry.second["ros__parameters"]) {
      collect(entry.second, full, c, file, out, matched);
    }
  }
}

}  // namespace

Result<std::string> normalize_namespace(const std::string& ns) {
  std::string out = ns.empty() || ns.front() != '/' ? "/" + ns : ns;
  while (out.size() > 1 && out.back() == '/') out.pop_back();
  if (!valid_name_characters(out) || out.find('~') != std::string::npos || out.find("//") != std::string::npos) {
    return usage(fmt::format("namespace '{}': only letters, digits, '_' and '/' are allowed", ns));
  }
  return out;
}

Result<CommandLine> parse_command_line(int argc, const char* const* argv) {
  CommandLine c;
  std::vector<std::pair<std::string, std::string>> remaps;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const auto value = [&](const std::string& option) -> Result<std::string> {
      if (i + 1 >= argc) return usage(option + " needs a value");
      return std::string(argv[++i]);
    };
    if (arg == "--ros-args" || arg == "--") continue;
    if (arg == "-h" || arg == "--help") {
      c.help = true;
    } else if (arg == "--params-file") {
      auto file = value(arg);
      if (!file) return file.error();
      c.params_files.push_back(*file);
    } else if (arg == "-p" || arg == "--param") {
      auto text = value(arg);
      if (!text) return text.error();
      auto assignment = split_assignment(*text);
      if (!assignment) return usage(fmt::format("{} '{}': expected NAME:=VALUE", arg, *text));
      c.param_overrides.push_back(*assignment);
    } else if (arg == "-r" || arg == "--remap") {
      auto text = value(arg);
      if (!text) return text.error();
      auto assignment = split_assignment(*text);
      if (!assignment) return usage(fmt::format("{} '{}': expected FROM:=TO", arg, *text));
      remaps.push_back(*assignment);
    } else if (auto assignment = split_assignment(arg); assignment && assignment->first.rfind("__", 0) == 0) {
      remaps.push_back(*assignment);  // the ROS 1 style "__ns:=/x" without -r
    } else {
      return usage(fmt::format("unknown argument '{}' (see --help)", arg));
    }
  }
  for (const auto& [from, to] : remaps) {
    if (from == "__ns") {
      auto ns = normalize_namespace(to);
      if (!ns) return ns.error();
      c.node_namespace = *ns;
    } else if (from == "__node" || from == "__name") {
      if (to.empty() || !valid_name_characters(to) || to.find('/') != std::string::npos || to.find('~') != std::string::npos) {
        return usage(fmt::format("node name '{}': only letters, digits and '_' are allowed", to));
      }
      c.node_name = to;
    }
  }
  // Topic remappings are resolved once the namespace and the name are known.
  for (const auto& [from, to] : remaps) {
    if (from.rfind("__", 0) == 0) continue;
    CommandLine plain = c;
    plain.remappings.clear();
    auto resolved_from = resolve_topic_name(from, plain);
    if (!resolved_from) return resolved_from.error();
    auto resolved_to = resolve_topic_name(to, plain);
    if (!resolved_to) return resolved_to.error();
    c.remappings[*resolved_from] = *resolved_to;
  }
  return c;
}

Result<std::string> resolve_topic_name(const std::string& name, const CommandLine& c) {
  if (name.empty() || !valid_name_characters(name) || name.find("//") != std::string::npos || name.back() == '/' ||
      (name.find('~') != std::string::npos && name.rfind("~", 0) != 0)) {
    return usage(fmt::format("topic name '{}': not a valid ROS 2 name", name));
  }
  std::string resolved;
  if (name.front() == '/') {
    resolved = name;
  } else if (name == "~") {
    resolved = fully_qualified_node_name(c);
  } else if (name.rfind("~/", 0) == 0) {
    resolved = fully_qualified_node_name(c) + name.substr(1);
  } else {
    resolved = (c.node_namespace == "/" ? "" : c.node_namespace) + "/" + name;
  }
  if (const auto it = c.remappings.find(resolved); it != c.remappings.end()) return it->second;
  return resolved;
}

Result<std::map<std::string, YAML::Node>> load_parameters(const CommandLine& c) {
  std::map<std::string, YAML::Node> values;
  for (const auto& file : c.params_files) {
    try {
      const YAML::Node root = YAML::LoadFile(file);
      if (!root.IsMap()) {
        return Error{ErrorCode::kParse, fmt::format("{}: expected a map of node names, each with ros__parameters", file)};
      }
      int matched = 0;
      collect(root, "", c, file, values, matched);
      if (matched == 0) {
        return Error{ErrorCode::kParse,
                     fmt::format("{}: no entry for node {} (expected '{}:', '{}:' or '/**:' with ros__parameters)", file,
                                 fully_qualified_node_name(c), c.node_name, fully_qualified_node_name(c))};
      }
    } catch (const YAML::BadFile&) {
      return Error{ErrorCode::kIo, fmt::format("{}: cannot read the parameters file", file)};
    } catch (const YAML::Exception& e) {
      return Error{ErrorCode::kParse, fmt::format("{}:{}: {}", file, e.mark.line + 1, e.msg)};
    }
  }
  for (const auto& [name, text] : c.param_overrides) {
    try {
      values[name] = YAML::Load(text);
    } catch (const YAML::Exception& e) {
      return Error{ErrorCode::kInvalidArgument, fmt::format("-p {}:={}: {}", name, text, e.msg)};
    }
  }
  return values;
}

Result<std::string> Parameters::get_string(const std::string& name, const std::string& fallback) const {
  const auto it = values_.find(name);
  if (it == values_.end() || it->second.IsNull()) return fallback;
  read_[name] = true;
  if (!it->second.IsScalar()) return usage(fmt::format("parameter {}: expected a string", name));
  return it->second.as<std::string>();
}

Result<double> Parameters::get_double(const std::string& name, double fallback) const {
  const auto it = values_.find(name);
  if (it == values_.end() || it->second.IsNull()) return fallback;
  read_[name] = true;
  try {
    if (it->second.IsScalar()) return it->second.as<double>();
  } catch (const YAML::Exception&) {
  }
  return usage(fmt::format("parameter {}: expected a number, got '{}'", name, YAML::Dump(it->second)));
}

Result<bool> Parameters::get_bool(const std::string& name, bool fallback) const {
  const auto it = values_.find(name);
  if (it == values_.end() || it->second.IsNull()) return fallback;
  read_[name] = true;
  try {
    if (it->second.IsScalar()) return it->second.as<bool>();
  } catch (const YAML::Exception&) {
  }
  return usage(fmt::format("parameter {}: expected true or false, got '{}'", name, YAML::Dump(it->second)));
}

Result<std::vector<double>> Parameters::get_doubles(const std::string& name) const {
  const auto it = values_.find(name);
  if (it == values_.end() || it->second.IsNull()) return std::vector<double>{};
  read_[name] = true;
  try {
    if (it->second.IsSequence()) return it->second.as<std::vector<double>>();
  } catch (const YAML::Exception&) {
  }
  return usage(fmt::format("parameter {}: expected a list of numbers, got '{}'", name, YAML::Dump(it->second)));
}

Result<std::vector<std::string>> Parameters::get_strings(const std::string& name) const {
  const auto it = values_.find(name);
  if (it == values_.end() || it->second.IsNull()) return std::vector<std::string>{};
  read_[name] = true;
  try {
    if (it->second.IsSequence()) return it->second.as<std::vector<std::string>>();
  } catch (const YAML::Exception&) {
  }
  return usage(fmt::format("parameter {}: expected a list of strings, got '{}'", name, YAML::Dump(it->second)));
}

std::vector<std::string> Parameters::unread() const {
  std::vector<std::string> out;
  for (const auto& [name, value] : values_) {
    if (!read_.count(name)) out.push_back(name);
  }
  return out;
}

}  // namespace skytrace::ros2_node
