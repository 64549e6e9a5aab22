// Material classes, name rules and default classification shared by the SDF, mesh and OSM loaders.
#include <algorithm>
#include <array>
#include <cctype>
#include <map>
#include <string>
#include <vector>

#include "skytrace/world/loaders.hpp"

namespace skytrace::world {

namespace {

char lower(char c) { return static_cast<char>(std::tolower(static_cast<unsigned char>(c))); }

std::string to_lower(std::string_view text) {
  std::string out(text);
  std::transform(out.begin(), out.end(), out.begin(), lower);
  return out;
}

// Names are split into words at non-letters and at lower-to-upper case changes ("PineTree_2" ->
// pine, tree). A keyword matches a word equal to it, ending with it (compounds such as "warehouse",
// "pinetree") or the same with a plural s/es; so "street" is not a tree and "small" not a mall.
std::vector<std::string> split_words(std::string_view name) {
  std::vector<std::string> words;
  std::string current;
  char previous = '\0';
  for (const char c : name) {
    const bool is_letter = std::isalpha(static_cast<unsigned char>(c)) != 0;
    const bool camel_break = is_letter && std::isupper(static_cast<unsigned char>(c)) != 0 &&
                             std::islower(static_cast<unsigned char>(previous)) != 0;
    if ((!is_letter || camel_break) && !current.empty()) {
      words.push_back(current);
      current.clear();
    }
    if (is_letter) current.push_back(lower(c));
    previous = c;
  }
  if (!current.empty()) words.push_back(current);
  return words;
}

bool word_matches(const std::string& word, std::string_view keyword) {
  for (std::string_view suffix : {"", "s", "es"}) {
    const std::string full = std::string(keyword) + std::string(suffix);
    if (word.size() >= full.size() &&
        word.compare(word.size() - full.size(), full.size(), full) == 0)
      return true;
  }
  return false;
}

bool contains_any(std::string_view name, const auto& keywords) {
  const auto words = split_words(name);
  return std::any_of(words.begin(), words.end(), [&](const std::string& word) {
    return std::any_of(std::begin(keywords), std::end(keywords),
                       [&](std::string_view keyword) { return word_matches(word, keyword); });
  });
}

// Keywords of model names and URIs. Callers test vegetation first, so "tree_house" is vegetation:
// a wrong guess costs a few dB, not a missing satellite behind a wall.
constexpr std::array<std::string_view, 11> kVegetationWords = {
    "tree", "pine",  "oak",     "bush",  "hedge",   "forest",
    "palm", "shrub", "foliage", "birch", "conifer",
};
constexpr std::array<std::string_view, 26> kBuildingWords = {
    "house",    "building", "office",    "apartment", "school",     "station",    "store",
    "shop",     "garage",   "salon",     "food",      "restaurant", "industrial", "hotel",
    "hospital", "church",   "warehouse", "factory",   "tower",      "skyscraper", "library",
    "hall",     "stadium",  "barn",      "villa",     "dormitory",
};

}  // namespace

std::string_view material_class_name(MaterialClass material_class) {
  switch (material_class) {
    case MaterialClass::kConcrete:
      return "concrete";
    case MaterialClass::kBrick:
      return "brick";
    case MaterialClass::kGlass:
      return "glass";
    case MaterialClass::kMetal:
      return "metal";
    case MaterialClass::kWood:
      return "wood";
    case MaterialClass::kGround:
      return "ground";
    case MaterialClass::kVegetation:
      return "vegetation";
    case MaterialClass::kUnknown:
      return "unknown";
  }
  return "unknown";
}

Result<MaterialClass> parse_material_class(std::string_view name) {
  static const std::map<std::string, MaterialClass, std::less<>> names_by_text = {
      {"concrete", MaterialClass::kConcrete},  {"stone", MaterialClass::kConcrete},
      {"brick", MaterialClass::kBrick},        {"glass", MaterialClass::kGlass},
      {"metal", MaterialClass::kMetal},        {"steel", MaterialClass::kMetal},
      {"wood", MaterialClass::kWood},          {"timber", MaterialClass::kWood},
      {"ground", MaterialClass::kGround},      {"vegetation", MaterialClass::kVegetation},
      {"foliage", MaterialClass::kVegetation}, {"unknown", MaterialClass::kUnknown},
  };
  const auto found = names_by_text.find(to_lower(name));
  if (found == names_by_text.end()) {
    return make_error(
        ErrorCode::kInvalidArgument,
        "unknown material class '" + std::string(name) +
            "' (expected concrete, brick, glass, metal, wood, ground, vegetation, unknown)");
  }
  return found->second;
}

std::string_view object_kind_name(ObjectKind kind) {
  switch (kind) {
    case ObjectKind::kBuilding:
      return "building";
    case ObjectKind::kTree:
      return "tree";
    case ObjectKind::kGround:
      return "ground";
    case ObjectKind::kOther:
      return "other";
    case ObjectKind::kSurroundings:
      return "surroundings";
  }
  return "other";
}

bool glob_match(std::string_view pattern, std::string_view text) {
  // Iterative matcher with one backtrack point per '*': linear in practice, no recursion.
  std::size_t p = 0;
  std::size_t t = 0;
  std::size_t star = std::string_view::npos;
  std::size_t star_text = 0;
  while (t < text.size()) {
    if (p < pattern.size() && (pattern[p] == '?' || lower(pattern[p]) == lower(text[t]))) {
      ++p;
      ++t;
    } else if (p < pattern.size() && pattern[p] == '*') {
      star = p++;
      star_text = t;
    } else if (star != std::string_view::npos) {
      p = star + 1;
      t = ++star_text;
    } else {
      return false;
    }
  }
  while (p < pattern.size() && pattern[p] == '*') ++p;
  return p == pattern.size();
}

const MaterialRule* match_material_rule(const std::vector<MaterialRule>& rules,
                                        const std::vector<std::string>& names) {
  for (const auto& rule : rules) {
    for (const auto& name : names) {
      if (!name.empty() && glob_match(rule.pattern, name)) return &rule;
    }
  }
  return nullptr;
}

bool name_suggests_vegetation(std::string_view name) {
  return contains_any(name, kVegetationWords);
}

bool name_suggests_building(std::string_view name) { return contains_any(name, kBuildingWords); }

std::string entity_name(const std::string& object_name) {
  // SDF objects are "model[/nested...]/link/collision": the entity is the model path. Other loaders
  // use two-part names ("way/123", "file/node") that are entities themselves.
  std::size_t parts =
      1 + static_cast<std::size_t>(std::count(object_name.begin(), object_name.end(), '/'));
  if (parts < 3) return object_name;
  std::size_t cut = object_name.size();
  for (int i = 0; i < 2; ++i) cut = object_name.rfind('/', cut - 1);
  return object_name.substr(0, cut);
}

WorldSummary summarize_world(const WorldModel& world) {
  WorldSummary summary;
  std::map<std::string, ObjectKind> entities;
  for (const auto& object : world.objects) {
    ++summary.objects;
    summary.triangles += object.mesh.triangles.size();
    summary.vertices += object.mesh.vertices_m.size();
    // A model's ground parts (a terrain inside a building model) do not decide its kind.
    auto [it, inserted] = entities.emplace(entity_name(object.name), object.kind);
    if (!inserted && it->second == ObjectKind::kGround && object.kind != ObjectKind::kGround)
      it->second = object.kind;
  }
  for (const auto& [name, kind] : entities) {
    switch (kind) {
      case ObjectKind::kBuilding:
        ++summary.buildings;
        break;
      case ObjectKind::kTree:
        ++summary.trees;
        break;
      case ObjectKind::kGround:
        ++summary.ground;
        break;
      case ObjectKind::kOther:
        ++summary.other;
        break;
      case ObjectKind::kSurroundings:
        break;  // not part of the model
    }
  }
  return summary;
}

}  // namespace skytrace::world
