#include "skytrace/sim/sweep.hpp"

#include <fmt/format.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <charconv>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>

#include "skytrace/core/input_limits.hpp"
#include "skytrace/core/output_file.hpp"
#include "skytrace/core/text_file.hpp"
#include "skytrace/core/yaml_field.hpp"
#include "skytrace/sim/scenario.hpp"

namespace skytrace::sim {
namespace {

// A YAML node as the flow text --set takes: [1, 2, 3], {a: 1}, "07". Quoted scalars stay quoted
// (yaml-cpp's emitter would drop the quotes of "07", which --set would then read as a number).
std::string flow_yaml(const YAML::Node& node) {
  if (node.IsSequence()) {
    std::string out = "[";
    for (size_t i = 0; i < node.size(); ++i) out += (i > 0 ? ", " : "") + flow_yaml(node[i]);
    return out + "]";
  }
  if (node.IsMap()) {
    std::string out = "{";
    for (const auto& entry : node) out += (out.size() > 1 ? ", " : "") + flow_yaml(entry.first) + ": " + flow_yaml(entry.second);
    return out + "}";
  }
  if (!node.IsScalar()) return "null";
  YAML::Emitter out;
  if (node.Tag() == "!") out << YAML::DoubleQuoted;
  out << node.Scalar();
  return out.c_str();
}

// A plain YAML scalar as JSON: true/false, a number, else text (quoted YAML stays text).
nlohmann::json scalar_json(const YAML::Node& node) {
  const std::string& text = node.Scalar();
  if (node.Tag() == "!") return text;  // quoted
  if (text == "true" || text == "false") return text == "true";
  if (text == "null" || text == "~" || text.empty()) return nullptr;
  long long whole = 0;
  auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), whole);
  if (ec == std::errc() && end == text.data() + text.size()) return whole;
  double value = 0.0;
  auto [end2, ec2] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec2 == std::errc() && end2 == text.data() + text.size() && std::isfinite(value)) return value;
  return text;
}

nlohmann::json yaml_json(const YAML::Node& node) {
  if (node.IsSequence()) {
    nlohmann::json out = nlohmann::json::array();
    for (const auto& element : node) out.push_back(yaml_json(element));
    return out;
  }
  if (node.IsMap()) {
    nlohmann::json out = nlohmann::json::object();
    for (const auto& entry : node) out[entry.first.Scalar()] = yaml_json(entry.second);
    return out;
  }
  if (node.IsScalar()) return scalar_json(node);
  return nullptr;
}

// A number as both texts: integers without a decimal point, others in the shortest form that reads
// back the same.
void add_number(SweepAxis& axis, double value) {
  if (value == std::floor(value) && std::abs(value) < 9e15) {
    const auto whole = static_cast<long long>(value);
    axis.yaml_values.push_back(std::to_string(whole));
    axis.json_values.emplace_back(whole);
  } else {
    axis.yaml_values.push_back(fmt::format("{}", value));
    axis.json_values.emplace_back(value);
  }
}

// SplitMix64: the draws of an axis depend only on the sweep's random_seed and the axis key, not on
// the platform's <random> distributions.
class Draws {
 public:
  Draws(std::uint64_t seed, const std::string& key) : state_(seed) {
    std::uint64_t hash = 1469598103934665603ULL;  // FNV-1a of the key
    for (const unsigned char c : key) hash = (hash ^ c) * 1099511628211ULL;
    state_ ^= hash;
  }
  std::uint64_t next() {
    std::uint64_t z = (state_ += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
  }
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }  // [0, 1)
  double normal() {  // Box-Muller
    const double u1 = 1.0 - uniform();
    const double u2 = uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
  }

 private:
  std::uint64_t state_;
};

constexpr int kMaxCount = 10'000'000;

void parse_axis(const YamlField& spec, SweepAxis& axis, std::uint64_t random_seed) {
  if (spec.is_sequence()) {
    for (const auto& element : spec.elements()) {
      axis.yaml_values.push_back(flow_yaml(element.node()));
      axis.json_values.push_back(yaml_json(element.node()));
    }
    if (axis.yaml_values.empty()) spec.fail("an empty list: expected at least one value");
    return;
  }
  if (!spec.is_map()) {  // one value
    axis.yaml_values.push_back(flow_yaml(spec.node()));
    axis.json_values.push_back(yaml_json(spec.node()));
    return;
  }
  spec.expect_keys({"values", "range", "step", "uniform", "normal", "integers", "choice", "count"});
  int kinds = 0;
  for (const char* kind : {"values", "range", "uniform", "normal", "integers", "choice"}) kinds += spec.child(kind) ? 1 : 0;
  if (kinds != 1) spec.fail("expected exactly one of values, range, uniform, normal, integers, choice");
  if (auto values = spec.child("values")) {
    parse_axis(*values, axis, random_seed);
    return;
  }
  if (auto range = spec.child("range")) {
    const auto bounds = range->as_doubles_in(-1e15, 1e15);
    if (bounds.size() != 2) range->fail("expected [FIRST, LAST]");
    const double step = spec.child("step") ? spec.child("step")->as_double_in(-1e15, 1e15) : 1.0;
    if (step == 0.0) spec.child("step")->fail("a step of 0: expected a step that moves from FIRST to LAST");
    const double span = (bounds[1] - bounds[0]) / step;
    if (span < -1e-9) {
      range->fail(fmt::format("an empty range: from {} to {} with step {} has no value", bounds[0], bounds[1], step));
    }
    const double count = std::floor(span + 1e-9) + 1.0;
    if (count > kMaxCount) range->fail(fmt::format("{} values: more than {} in one axis", count, kMaxCount));
    for (int i = 0; i < static_cast<int>(count); ++i) {
      // Rounded to 12 significant digits: 0.1 steps give 0.3, not 0.30000000000000004.
      const double value = std::stod(fmt::format("{:.12g}", bounds[0] + i * step));
      add_number(axis, value);
    }
    return;
  }
  if (spec.child("step")) spec.child("step")->fail("step belongs to a range");
  auto count_field = spec.child("count");
  if (!count_field) spec.fail("a random axis needs count: how many values to draw");
  const int count = count_field->as_int_in(1, kMaxCount);
  Draws draws(random_seed, axis.key);
  if (auto uniform = spec.child("uniform")) {
    const auto bounds = uniform->as_doubles_in(-1e15, 1e15);
    if (bounds.size() != 2 || !(bounds[1] > bounds[0])) uniform->fail("expected [LOW, HIGH] with LOW < HIGH");
    for (int i = 0; i < count; ++i) add_number(axis, bounds[0] + (bounds[1] - bounds[0]) * draws.uniform());
  } else if (auto normal = spec.child("normal")) {
    const auto parameters = normal->as_doubles_in(-1e15, 1e15);
    if (parameters.size() != 2 || parameters[1] < 0.0) normal->fail("expected [MEAN, SIGMA] with SIGMA >= 0");
    for (int i = 0; i < count; ++i) add_number(axis, parameters[0] + parameters[1] * draws.normal());
  } else if (auto integers = spec.child("integers")) {
    const auto bounds = integers->as_doubles_in(-1e15, 1e15);
    if (bounds.size() != 2 || bounds[0] != std::floor(bounds[0]) || bounds[1] != std::floor(bounds[1]) || bounds[1] < bounds[0]) {
      integers->fail("expected [LOW, HIGH], whole numbers with LOW <= HIGH");
    }
    const double values = bounds[1] - bounds[0] + 1.0;
    for (int i = 0; i < count; ++i) add_number(axis, bounds[0] + std::floor(values * draws.uniform()));
  } else if (auto choice = spec.child("choice")) {
    SweepAxis options;
    parse_axis(*choice, options, random_seed);
    for (int i = 0; i < count; ++i) {
      const auto pick = static_cast<size_t>(static_cast<double>(options.yaml_values.size()) * draws.uniform());
      axis.yaml_values.push_back(options.yaml_values[pick]);
      axis.json_values.push_back(options.json_values[pick]);
    }
  }
}

int line_of(const YAML::Node& node) { return node.Mark().line + 1; }

}  // namespace

std::string SweepPlan::point_id(std::uint64_t index) const {
  const std::string digits = std::to_string(point_count > 0 ? point_count - 1 : 0);
  return fmt::format("p{:0>{}}", index, std::max<size_t>(6, digits.size()));
}

std::optional<std::uint64_t> SweepPlan::point_index(const std::string& id) const {
  if (id.size() < 2 || id[0] != 'p') return std::nullopt;
  std::uint64_t index = 0;
  auto [end, ec] = std::from_chars(id.data() + 1, id.data() + id.size(), index);
  if (ec != std::errc() || end != id.data() + id.size() || index >= point_count || point_id(index) != id) return std::nullopt;
  return index;
}

std::vector<size_t> SweepPlan::value_indices(std::uint64_t index) const {
  std::vector<size_t> indices(axes.size(), 0);
  if (zip) {
    for (auto& i : indices) i = static_cast<size_t>(index);
    return indices;
  }
  // The last axis varies fastest, as nested loops in the order the file lists the axes.
  for (size_t k = axes.size(); k-- > 0;) {
    const std::uint64_t n = axes[k].yaml_values.size();
    indices[k] = static_cast<size_t>(index % n);
    index /= n;
  }
  return indices;
}

std::vector<std::string> SweepPlan::overrides(std::uint64_t index) const {
  std::vector<std::string> out = fixed_overrides;
  const auto indices = value_indices(index);
  for (size_t k = 0; k < axes.size(); ++k) out.push_back(axes[k].key + "=" + axes[k].yaml_values[indices[k]]);
  return out;
}

nlohmann::json SweepPlan::parameters(std::uint64_t index) const {
  nlohmann::json out = nlohmann::json::object();
  const auto indices = value_indices(index);
  for (size_t k = 0; k < axes.size(); ++k) out[axes[k].key] = axes[k].json_values[indices[k]];
  return out;
}

Result<SweepPlan> parse_sweep(const std::string& text, const std::filesystem::path& file) {
  const std::string name = file.string();
  auto document = load_yaml_document(text, name);
  if (!document) return document.error();
  YAML::Node root = std::move(*document);
  SweepPlan plan;
  plan.file = file;
  plan.name = file.stem().string();
  try {
    const YamlField top(root, "", &name, "sweep");
    if (!top.is_map()) top.fail("expected a mapping with scenario and axes");
    top.expect_keys({"name", "scenario", "set", "combine", "random_seed", "axes"});
    if (auto c = top.child("name")) plan.name = c->as_string();
    const YamlField scenario = top.required("scenario");
    std::filesystem::path base = scenario.as_string();
    if (base.is_relative()) base = file.parent_path() / base;
    std::error_code ec;
    plan.scenario = std::filesystem::absolute(base, ec).lexically_normal();
    if (!std::filesystem::is_regular_file(plan.scenario, ec)) {
      scenario.fail("no scenario file " + plan.scenario.string());
    }
    if (auto c = top.child("random_seed")) {
      const double seed = c->as_double_in(0.0, 1.8e19);
      if (seed != std::floor(seed)) c->fail("expected a whole number");
      plan.random_seed = static_cast<std::uint64_t>(seed);
    }
    if (auto c = top.child("combine")) plan.zip = c->as_choice({"grid", "zip"}) == "zip";
    if (auto set = top.child("set")) {
      if (!set->is_map()) set->fail("expected a mapping of KEY.PATH: VALUE");
      for (const auto& [key, value] : set->entries()) plan.fixed_overrides.push_back(key + "=" + flow_yaml(value.node()));
    }
    if (auto axes = top.child("axes")) {
      if (!axes->is_map()) axes->fail("expected a mapping of KEY.PATH: values");
      for (const auto& [key, spec] : axes->entries()) {
        SweepAxis axis;
        axis.key = key;
        axis.line = line_of(spec.node());
        parse_axis(spec, axis, plan.random_seed);
        plan.axes.push_back(std::move(axis));
      }
    }
    const std::uint64_t limit = input_limits().max_sweep_points;
    std::uint64_t count = 1;
    for (const SweepAxis& axis : plan.axes) {
      const std::uint64_t n = axis.yaml_values.size();
      if (plan.zip) {
        if (&axis != &plan.axes.front() && n != count) {
          return make_error(ErrorCode::kParse,
                            fmt::format("{}:{}: axes.{}: {} values, but the axes before it have {}: combine: zip pairs the "
                                        "i-th values of every axis, so all need as many",
                                        name, axis.line, axis.key, n, count));
        }
        count = n;
      } else {
        if (count > limit / n) {
          return make_error(ErrorCode::kParse, fmt::format("{}: the grid of its axes has more than {} points {}", name, limit,
                                                           limit_hint(limit, "SKYTRACE_MAX_SWEEP_POINTS")));
        }
        count *= n;
      }
    }
    if (count > limit) {
      return make_error(ErrorCode::kParse,
                        fmt::format("{}: {} points {}", name, count, limit_hint(limit, "SKYTRACE_MAX_SWEEP_POINTS")));
    }
    plan.point_count = count;
  } catch (const YamlFieldError& e) {
    return make_error(ErrorCode::kParse, e.message);
  } catch (const YAML::Exception& e) {
    return make_error(ErrorCode::kParse, name + ":" + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
  return plan;
}

Result<SweepPlan> load_sweep(const std::filesystem::path& file) {
  auto text = read_text_file(file);
  if (!text) return text.error();
  return parse_sweep(*text, file);
}

Status check_sweep_against_scenario(const SweepPlan& plan) {
  auto text = read_text_file(plan.scenario);
  if (!text) return text.error();
  const std::string scenario_name = plan.scenario.string();
  auto first = parse_scenario(*text, scenario_name, plan.scenario.parent_path(), plan.overrides(0));
  if (!first) {
    return make_error(first.error().code, fmt::format("{}: the first point of the sweep: {}", plan.file.string(), first.error().message));
  }
  constexpr size_t kCheckedValues = 1000;
  for (size_t k = 0; k < plan.axes.size(); ++k) {
    const SweepAxis& axis = plan.axes[k];
    std::vector<std::string> overrides = plan.overrides(0);
    const size_t axis_slot = plan.fixed_overrides.size() + k;
    for (size_t v = 1; v < std::min(axis.yaml_values.size(), kCheckedValues); ++v) {
      if (axis.yaml_values[v] == axis.yaml_values[v - 1]) continue;
      overrides[axis_slot] = axis.key + "=" + axis.yaml_values[v];
      auto scenario = parse_scenario(*text, scenario_name, plan.scenario.parent_path(), overrides);
      if (!scenario) {
        return make_error(scenario.error().code, fmt::format("{}:{}: axes.{}: the value {}: {}", plan.file.string(), axis.line,
                                                             axis.key, axis.yaml_values[v], scenario.error().message));
      }
    }
  }
  return Ok{};
}

Status write_point_record(const SweepLayout& layout, const PointRecord& r) {
  nlohmann::json j = {{"id", r.id},       {"status", r.status},           {"exit_code", r.exit_code},
                      {"error", r.error}, {"wall_time_s", r.wall_time_s}, {"host", r.host},
                      {"overrides", r.overrides}, {"scenario", r.scenario}};
  std::error_code ec;
  std::filesystem::create_directories(layout.point_dir(r.id), ec);
  return write_file_atomically(layout.point_record(r.id), j.dump(1) + "\n");
}

std::optional<PointRecord> read_point_record(const SweepLayout& layout, const std::string& id) {
  std::ifstream in(layout.point_record(id));
  if (!in) return std::nullopt;
  try {
    const nlohmann::json j = nlohmann::json::parse(in);
    PointRecord r;
    r.id = j.at("id").get<std::string>();
    r.status = j.at("status").get<std::string>();
    r.exit_code = j.at("exit_code").get<int>();
    r.error = j.at("error").get<std::string>();
    r.wall_time_s = j.at("wall_time_s").get<double>();
    r.host = j.at("host").get<std::string>();
    r.overrides = j.at("overrides").get<std::vector<std::string>>();
    r.scenario = j.at("scenario").get<std::string>();
    return r;
  } catch (const nlohmann::json::exception&) {
    return std::nullopt;  // half-written by hand or damaged: the point runs again
  }
}

std::map<std::uint64_t, PointRecord> read_point_records(const SweepPlan& plan, const SweepLayout& layout) {
  std::map<std::uint64_t, PointRecord> records;
  std::error_code ec;
  for (std::filesystem::directory_iterator it(layout.runs(), ec), end; !ec && it != end; it.increment(ec)) {
    const std::string id = it->path().filename().string();
    const auto index = plan.point_index(id);
    if (!index) continue;
    if (auto record = read_point_record(layout, id)) records.emplace(*index, std::move(*record));
  }
  return records;
}

bool record_of_this_sweep(const SweepPlan& plan, const PointRecord& record, std::uint64_t index) {
  return record.overrides == plan.overrides(index) && record.scenario == plan.scenario.string();
}

bool point_done(const SweepPlan& plan, const std::optional<PointRecord>& record, std::uint64_t index) {
  return record && record->status == "done" && record_of_this_sweep(plan, *record, index);
}

namespace {

std::string csv_field(std::string text) {
  if (text.find_first_of(",\"\n") == std::string::npos) return text;
  std::string out = "\"";
  for (const char c : text) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + "\"";
}

std::string csv_value(const nlohmann::json& value) {
  if (value.is_null()) return "";
  if (value.is_string()) return csv_field(value.get<std::string>());
  if (value.is_number_float()) return fmt::format("{}", value.get<double>());
  return csv_field(value.dump());
}

const nlohmann::json& at_path(const nlohmann::json& j, std::initializer_list<const char*> path) {
  static const nlohmann::json null;
  const nlohmann::json* node = &j;
  for (const char* key : path) {
    if (!node->is_object() || !node->contains(key)) return null;
    node = &(*node)[key];
  }
  return *node;
}

}  // namespace

Result<SweepCounts> write_sweep_manifest(const SweepPlan& plan, const SweepLayout& layout,
                                         const std::vector<std::pair<std::uint64_t, std::string>>& reasons) {
  SweepCounts counts;
  // The points' part of manifest.json, one object per line: written as it is built, so that the
  // manifest of 10^6 points does not hold a JSON tree of them all.
  std::string points_text;
  std::string manifest_csv = "id,status";
  std::string summaries_csv = "id,status";
  for (const SweepAxis& axis : plan.axes) {
    manifest_csv += "," + csv_field(axis.key);
    summaries_csv += "," + csv_field(axis.key);
  }
  manifest_csv += ",exit_code,wall_time_s,host,error\n";
  summaries_csv +=
      ",receiver,epochs,availability,rtk_fixed_share,time_to_first_fix_s,time_to_first_rtk_fixed_s,"
      "horizontal_error_p50_m,horizontal_error_p95_m,horizontal_error_max_m,vertical_error_p50_m,vertical_error_p95_m,"
      "vertical_error_max_m,mean_satellites_used,mean_tracked_satellites,nlos_share,multipath_share,signal_observations,"
      "wall_time_s\n";
  size_t next_reason = 0;
  std::vector<std::pair<std::uint64_t, std::string>> sorted_reasons = reasons;
  std::sort(sorted_reasons.begin(), sorted_reasons.end());
  auto records = read_point_records(plan, layout);
  static const std::optional<PointRecord> kNoRecord;
  for (std::uint64_t i = 0; i < plan.point_count; ++i) {
    const std::string id = plan.point_id(i);
    const nlohmann::json parameters = plan.parameters(i);
    const auto found = records.find(i);
    std::optional<PointRecord> record = found == records.end() ? kNoRecord : std::optional<PointRecord>(found->second);
    if (record && !record_of_this_sweep(plan, *record, i)) record.reset();
    std::string status = record ? record->status : "pending";
    std::string error = record ? record->error : "";
    while (next_reason < sorted_reasons.size() && sorted_reasons[next_reason].first < i) ++next_reason;
    if (!record && next_reason < sorted_reasons.size() && sorted_reasons[next_reason].first == i) {
      status = "failed";
      error = sorted_reasons[next_reason].second;
    }
    nlohmann::json point = {{"id", id}, {"status", status}, {"parameters", parameters}};
    std::string parameter_fields;
    for (const SweepAxis& axis : plan.axes) parameter_fields.append(1, ',').append(csv_value(parameters[axis.key]));
    if (record) {
      point["exit_code"] = record->exit_code;
      point["wall_time_s"] = record->wall_time_s;
      point["host"] = record->host;
    }
    if (!error.empty()) point["error"] = error;
    if (status == "done") {
      ++counts.done;
      // The run's own figures per receiver (summary.json "receivers").
      std::ifstream in(layout.point_dir(id) / "summary.json");
      nlohmann::json summary;
      try {
        if (in) summary = nlohmann::json::parse(in);
      } catch (const nlohmann::json::exception&) {
        summary = nullptr;
      }
      const nlohmann::json& receivers = at_path(summary, {"receivers"});
      point["receivers"] = receivers.is_array() ? receivers : nlohmann::json::array();
      for (const auto& rx : point["receivers"]) {
        summaries_csv += csv_field(id) + ",done" + parameter_fields;
        for (const nlohmann::json* value :
             {&at_path(rx, {"name"}), &at_path(rx, {"epochs"}), &at_path(rx, {"fix", "availability"}),
              &at_path(rx, {"fix", "rtk_fixed_share"}), &at_path(rx, {"fix", "time_to_first_fix_s"}),
              &at_path(rx, {"fix", "time_to_first_rtk_fixed_s"}), &at_path(rx, {"fix", "horizontal_error_m", "p50"}),
              &at_path(rx, {"fix", "horizontal_error_m", "p95"}), &at_path(rx, {"fix", "horizontal_error_m", "max"}),
              &at_path(rx, {"fix", "vertical_error_m", "p50"}), &at_path(rx, {"fix", "vertical_error_m", "p95"}),
              &at_path(rx, {"fix", "vertical_error_m", "max"}), &at_path(rx, {"fix", "mean_satellites_used"}),
              &at_path(rx, {"mean_tracked_satellites"}), &at_path(rx, {"nlos_share"}), &at_path(rx, {"multipath_share"}),
              &at_path(rx, {"signal_observations"})}) {
          summaries_csv.append(1, ',').append(csv_value(*value));
        }
        summaries_csv += fmt::format(",{}\n", record->wall_time_s);
      }
    } else if (status == "failed") {
      ++counts.failed;
      counts.failed_ids.push_back(id);
    } else {
      ++counts.pending;
    }
    manifest_csv += csv_field(id) + "," + status + parameter_fields;
    manifest_csv += record ? fmt::format(",{},{},{}", record->exit_code, record->wall_time_s, csv_field(record->host)) : ",,,";
    manifest_csv += "," + csv_field(error) + "\n";
    points_text += (i == 0 ? "\n  " : ",\n  ") + point.dump();
  }
  // One line per key, one line per point: readable, and written without a JSON tree of every point.
  nlohmann::json axes = nlohmann::json::array();
  for (const SweepAxis& axis : plan.axes) axes.push_back({{"key", axis.key}, {"values", axis.json_values}});
  const std::vector<std::pair<const char*, nlohmann::json>> header = {
      {"sweep", plan.name},
      {"sweep_file", std::filesystem::absolute(plan.file).lexically_normal().string()},
      {"scenario", plan.scenario.string()},
      {"combine", plan.zip ? "zip" : "grid"},
      {"random_seed", plan.random_seed},
      {"set", plan.fixed_overrides},
      {"axes", axes},
      {"points_total", plan.point_count},
      {"done", counts.done},
      {"failed", counts.failed},
      {"pending", counts.pending}};
  std::string manifest_text = "{\n";
  for (const auto& [key, value] : header) manifest_text += fmt::format(" \"{}\": {},\n", key, value.dump());
  manifest_text.reserve(manifest_text.size() + points_text.size() + 32);
  manifest_text.append(" \"points\": [").append(points_text).append(points_text.empty() ? "]\n}\n" : "\n ]\n}\n");
  points_text = std::string();
  if (auto st = write_file_atomically(layout.out / "manifest.json", manifest_text); !st) return st.error();
  if (auto st = write_file_atomically(layout.out / "manifest.csv", manifest_csv); !st) return st.error();
  if (auto st = write_file_atomically(layout.out / "summaries.csv", summaries_csv); !st) return st.error();
  return counts;
}

}  // namespace skytrace::sim
