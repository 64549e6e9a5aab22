#include "skytrace/core/yaml_field.hpp"

#include <map>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace skytrace {
namespace {

std::string one_of(std::initializer_list<const char*> items) {
  std::string list;
  for (const char* item : items) list += (list.empty() ? "" : ", ") + std::string(item);
  return list;
}

}  // namespace

void YamlField::fail(const std::string& what) const {
  std::string where = *file_;
  const auto set_here = [&](const YamlOverride& set) {
    const std::string& p = set.path;
    return path_ == p || (path_.size() > p.size() && path_.compare(0, p.size(), p) == 0 &&
                          (path_[p.size()] == '.' || path_[p.size()] == '['));
  };
  // The last option that set the value wins, as it did when the options were applied.
  const auto set = overridden_ != nullptr ? std::find_if(overridden_->rbegin(), overridden_->rend(), set_here)
                                          : std::vector<YamlOverride>::const_reverse_iterator{};
  if (overridden_ != nullptr && set != overridden_->rend()) {
    where += " (" + set->option + ")";  // the value is not in the file: its line would mislead
  } else if (node_.Mark().line >= 0) {
    where += ":" + std::to_string(node_.Mark().line + 1);
  }
  throw YamlFieldError{where + ": " + (path_.empty() ? document_ : path_) + ": " + what};
}

namespace {

std::optional<std::string> duplicate_in(const YAML::Node& node, const std::string& file, const std::string& path,
                                        int depth) {
  constexpr int kMaxDepth = 256;  // far deeper than any configuration; bounds the recursion
  if (depth > kMaxDepth) return file + ":" + std::to_string(node.Mark().line + 1) + ": nesting deeper than 256 levels";
  if (node.IsMap()) {
    std::map<std::string, int> first_line;
    for (const auto& item : node) {
      if (!item.first.IsScalar()) continue;
      const std::string key = item.first.Scalar();
      const int line = item.first.Mark().line + 1;
      const auto [it, inserted] = first_line.emplace(key, line);
      const std::string key_path = path.empty() ? key : path + "." + key;
      if (!inserted) {
        return file + ":" + std::to_string(line) + ": " + key_path + ": duplicate key (first at line " +
               std::to_string(it->second) + "; YAML allows a key once per mapping)";
      }
      if (auto found = duplicate_in(item.second, file, key_path, depth + 1)) return found;
    }
  } else if (node.IsSequence()) {
    for (size_t i = 0; i < node.size(); ++i) {
      if (auto found = duplicate_in(node[i], file, path + "[" + std::to_string(i) + "]", depth + 1)) return found;
    }
  }
  return std::nullopt;
}

}  // namespace

std::optional<std::string> find_duplicate_key(const YAML::Node& root, const std::string& file) {
  return duplicate_in(root, file, "", 0);
}

void YamlField::expect_keys(std::initializer_list<const char*> allowed) const {
  if (!node_.IsMap()) fail("expected a mapping of keys");
  for (const auto& item : node_) {
    const std::string key = item.first.as<std::string>();
    if (std::none_of(allowed.begin(), allowed.end(), [&](const char* a) { return key == a; })) {
      at(item.first, join(key)).fail("unknown key (expected one of: " + one_of(allowed) + ")");
    }
  }
}

std::optional<YamlField> YamlField::child(const std::string& key) const {
  const YAML::Node c = node_[key];
  if (!c || c.IsNull()) return std::nullopt;
  return at(c, join(key));
}

YamlField YamlField::required(const std::string& key) const {
  auto c = child(key);
  if (!c) fail("missing required key '" + key + "'");
  return *c;
}

std::vector<YamlField> YamlField::elements() const {
  if (!node_.IsSequence()) fail("expected a list");
  std::vector<YamlField> out;
  for (size_t i = 0; i < node_.size(); ++i) out.push_back(at(node_[i], path_ + "[" + std::to_string(i) + "]"));
  return out;
}

std::vector<std::pair<std::string, YamlField>> YamlField::entries() const {
  if (!node_.IsMap()) fail("expected a mapping of keys");
  std::vector<std::pair<std::string, YamlField>> out;
  for (const auto& item : node_) {
    const std::string key = item.first.as<std::string>();
    out.emplace_back(key, at(item.second, join(key)));
  }
  return out;
}

std::vector<YamlField> YamlField::as_list_or_single() const {
  if (node_.IsSequence()) return elements();
  return {*this};
}

std::string YamlField::as_string() const {
  if (!node_.IsScalar()) fail("expected a single value");
  return node_.Scalar();
}

double YamlField::as_double() const {
  const std::string text = as_string();
  try {
    size_t used = 0;
    const double v = std::stod(text, &used);
    if (used != text.size() || !std::isfinite(v)) throw std::invalid_argument(text);
    return v;
  } catch (const std::exception&) {
    fail("expected a number, got '" + text + "'");
  }
}

double YamlField::as_double_in(double low, double high) const {
  const double v = as_double();
  if (v < low || v > high) {
    std::ostringstream s;
    s << "value " << v << " out of range [" << low << ", " << high << "]";
    fail(s.str());
  }
  return v;
}

int YamlField::as_int_in(int low, int high) const {
  const double v = as_double_in(low, high);
  if (v != std::floor(v)) fail("expected a whole number, got '" + as_string() + "'");
  return static_cast<int>(v);
}

bool YamlField::as_bool() const {
  const std::string text = as_string();
  if (text == "true" || text == "yes" || text == "on") return true;
  if (text == "false" || text == "no" || text == "off") return false;
  fail("expected true or false, got '" + text + "'");
}

std::string YamlField::as_choice(std::initializer_list<const char*> choices) const {
  const std::string text = as_string();
  if (std::any_of(choices.begin(), choices.end(), [&](const char* c) { return text == c; })) return text;
  fail("unknown value '" + text + "' (expected one of: " + one_of(choices) + ")");
}

Eigen::Vector3d YamlField::as_vector3() const {
  const auto items = elements();
  if (items.size() != 3) fail("expected a list of 3 numbers");
  return {items[0].as_double(), items[1].as_double(), items[2].as_double()};
}

std::vector<double> YamlField::as_doubles_in(double low, double high) const {
  std::vector<double> out;
  for (const YamlField& e : elements()) out.push_back(e.as_double_in(low, high));
  return out;
}

Result<YAML::Node> load_yaml_document(const std::string& text, const std::string& file) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    return make_error(ErrorCode::kParse, file + ":" + std::to_string(e.mark.line + 1) + ": YAML syntax error: " + e.msg);
  }
  if (auto duplicate = find_duplicate_key(root, file)) return make_error(ErrorCode::kParse, *duplicate);
  return root;
}

}  // namespace skytrace
