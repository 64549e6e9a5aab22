// A YAML node with its key path and file, so that every message about a configuration file (scenario,
// receiver profile) reads "file:12: receiver.signals[2]: what was expected". Parsers throw
// YamlFieldError from deep inside and turn it into an Error at their boundary.
#pragma once

#include <yaml-cpp/yaml.h>

#include <Eigen/Core>

#include <initializer_list>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "skytrace/core/error.hpp"

namespace skytrace {

struct YamlFieldError {
  std::string message;
};

// "file:LINE: duplicate key 'k' (first at line N)" for the first mapping anywhere in `root` that
// holds a key twice (YAML forbids it; yaml-cpp would keep the first value silently), else nullopt.
[[nodiscard]] std::optional<std::string> find_duplicate_key(const YAML::Node& root, const std::string& file);

// A YAML document parsed, or the error "file:LINE: YAML syntax error: ..." / a duplicate key (kParse).
[[nodiscard]] Result<YAML::Node> load_yaml_document(const std::string& text, const std::string& file);

// A value set on the command line: its key path as YamlField::path() writes it (list indices in
// brackets), and the option as the user gave it ("--set receivers.0.name=A").
struct YamlOverride {
  std::string path, option;
};

class YamlField {
 public:
  // `file` names the document in messages and must outlive the field; `document` stands for the
  // empty path ("scenario", "profile"). `overridden`, when given, lists the values set on the
  // command line and must outlive the field: a message about one of them, or about anything below
  // it, names the option instead of a line of the file.
  YamlField(YAML::Node node, std::string path, const std::string* file, std::string document = "document",
            const std::vector<YamlOverride>* overridden = nullptr)
      : node_(std::move(node)),
        path_(std::move(path)),
        file_(file),
        document_(std::move(document)),
        overridden_(overridden) {}

  [[nodiscard]] const std::string& path() const { return path_; }
  [[nodiscard]] const YAML::Node& node() const { return node_; }
  [[nodiscard]] bool is_map() const { return node_.IsMap(); }
  [[nodiscard]] bool is_sequence() const { return node_.IsSequence(); }
  [[nodiscard]] bool is_scalar() const { return node_.IsScalar(); }

  // Throws YamlFieldError "file:line: path: what".
  [[noreturn]] void fail(const std::string& what) const;
  // A mapping holding only the allowed keys.
  void expect_keys(std::initializer_list<const char*> allowed) const;

  [[nodiscard]] std::optional<YamlField> child(const std::string& key) const;  // absent or null: nullopt
  [[nodiscard]] YamlField required(const std::string& key) const;
  [[nodiscard]] std::vector<YamlField> elements() const;                            // a list
  [[nodiscard]] std::vector<std::pair<std::string, YamlField>> entries() const;     // a mapping, in order
  [[nodiscard]] std::vector<YamlField> as_list_or_single() const;

  [[nodiscard]] std::string as_string() const;
  [[nodiscard]] double as_double() const;
  [[nodiscard]] double as_double_in(double low, double high) const;
  [[nodiscard]] int as_int_in(int low, int high) const;
  [[nodiscard]] bool as_bool() const;
  [[nodiscard]] std::string as_choice(std::initializer_list<const char*> choices) const;
  [[nodiscard]] Eigen::Vector3d as_vector3() const;
  [[nodiscard]] std::vector<double> as_doubles_in(double low, double high) const;

 private:
  [[nodiscard]] std::string join(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }
  [[nodiscard]] YamlField at(YAML::Node node, std::string path) const {
    return YamlField(std::move(node), std::move(path), file_, document_, overridden_);
  }

  YAML::Node node_;
  std::string path_;
  const std::string* file_;
  std::string document_;
  const std::vector<YamlOverride>* overridden_ = nullptr;
};

}  // namespace skytrace
