// CityGML city models (CityGML 1.0, 2.0 and 3.0): every city object's surfaces of its highest LoD
// as triangles in the world frame (docs/worlds.md). Read as a stream with expat: files of whole
// districts run to gigabytes.
#include <expat.h>
#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "city_model.hpp"
#include "skytrace/core/input_limits.hpp"
#include "skytrace/world/loaders.hpp"

namespace skytrace::world {
namespace {

constexpr std::size_t kMaxDepth = 2000;  // elements nested deeper: not a city model, refused

struct Surface {
  int lod = -1;  // -1: outside every lodN element (a TIN relief's triangles)
  std::vector<std::vector<Eigen::Vector3d>> rings;  // outer first, in the model's CRS
};

struct CityObject {
  std::string id;
  std::string type;
  std::vector<Surface> surfaces;
};

// The local name of an element ("bldg:lod2Solid" or "http://...|lod2Solid" -> "lod2Solid").
std::string_view local_name(std::string_view name) {
  const auto cut = name.find_last_of(":|");
  return cut == std::string_view::npos ? name : name.substr(cut + 1);
}

// The N of lodN... element names (lod2Solid, lod1MultiSurface, lod3Geometry); -1 otherwise.
int lod_of_element(std::string_view name) {
  if (name.size() < 5 || name.substr(0, 3) != "lod" || name[3] < '0' || name[3] > '4') return -1;
  return name[3] - '0';
}

bool is_ring_owner(std::string_view name) {
  return name == "Polygon" || name == "Triangle" || name == "PolygonPatch" || name == "Rectangle";
}

struct Parser {
  std::string where;
  XML_Parser xml = nullptr;
  std::string error;  // the first problem; parsing stops
  std::vector<std::string> stack;  // local names
  std::vector<int> lods;           // the lod of each open element (inherited)
  std::vector<bool> implicit;      // inside an ImplicitGeometry (relative coordinates: skipped)
  int member_depth = -1;           // depth of the open cityObjectMember / featureMember
  std::optional<CityObject> object;
  int object_depth = -1;
  std::vector<CityObject> objects;
  std::string srs_name;
  std::optional<int> dimension;  // srsDimension of the coordinates being read
  // The surface being read.
  bool in_surface = false;
  int surface_depth = -1;
  Surface surface;
  int ring_kind = 0;  // 1 exterior, 2 interior, 0 none
  std::vector<Eigen::Vector3d> ring;
  std::string text;
  bool reading_text = false;
  std::size_t points = 0;

  void fail(const std::string& message) {
    if (error.empty()) {
      error = fmt::format("{}:{}: {}", where, XML_GetCurrentLineNumber(xml), message);
      XML_StopParser(xml, XML_FALSE);
    }
  }

  // Numbers of a posList / pos / coordinates text into the ring, `dim` per point.
  void add_coordinates(std::string_view s, int dim, bool commas) {
    std::vector<double> values;
    const char* p = s.data();
    const char* end = s.data() + s.size();
    while (p < end) {
      while (p < end && (std::isspace(static_cast<unsigned char>(*p)) != 0 || (commas && *p == ','))) ++p;
      if (p >= end) break;
      double v = 0.0;
      const auto [next, ec] = std::from_chars(p, end, v);
      if (ec != std::errc() || !std::isfinite(v)) {
        fail("expected numbers in <" + stack.back() + ">, found '" + std::string(p, std::min<std::size_t>(end - p, 20)) + "'");
        return;
      }
      values.push_back(v);
      p = next;
    }
    if (dim != 2 && dim != 3) {
      fail(fmt::format("srsDimension {}: expected 2 or 3", dim));
      return;
    }
    if (values.size() % static_cast<std::size_t>(dim) != 0) {
      fail(fmt::format("<{}>: {} numbers are not points of {} coordinates", stack.back(), values.size(), dim));
      return;
    }
    for (std::size_t i = 0; i < values.size(); i += static_cast<std::size_t>(dim)) {
      ring.emplace_back(values[i], values[i + 1], dim == 3 ? values[i + 2] : 0.0);
    }
    points += values.size() / static_cast<std::size_t>(dim);
    if (points > input_limits().max_grid_points) {
      fail(fmt::format("more than {} points", input_limits().max_grid_points));
    }
  }

  void start(const XML_Char* raw_name, const XML_Char** attributes) {
    const std::string name(local_name(raw_name));
    if (stack.size() >= kMaxDepth) {
      fail(fmt::format("elements nested more than {} deep", kMaxDepth));
      return;
    }
    std::string id, srs;
    std::optional<int> srs_dimension;
    for (const XML_Char** a = attributes; *a != nullptr; a += 2) {
      const std::string_view key = local_name(a[0]);
      if (key == "id") id = a[1];
      if (key == "srsName") srs = a[1];
      if (key == "srsDimension") {
        int d = 0;
        const std::string_view v(a[1]);
        if (std::from_chars(v.data(), v.data() + v.size(), d).ec != std::errc()) {
          fail("srsDimension '" + std::string(v) + "': expected 2 or 3");
          return;
        }
        srs_dimension = d;
      }
    }
    if (!srs.empty() && srs_name.empty()) srs_name = srs;
    if (stack.empty() && name != "CityModel") {
      fail("not a CityGML file (root element <" + name + ">, expected <CityModel>)");
      return;
    }
    const int depth = static_cast<int>(stack.size());
    const int parent_lod = lods.empty() ? -1 : lods.back();
    const int own_lod = lod_of_element(name);
    lods.push_back(own_lod >= 0 ? own_lod : parent_lod);
    implicit.push_back((!implicit.empty() && implicit.back()) || name == "ImplicitGeometry");
    stack.push_back(name);

    if ((name == "cityObjectMember" || name == "featureMember") && member_depth < 0) {
      member_depth = depth;
    } else if (member_depth >= 0 && depth == member_depth + 1 && !object) {
      object = CityObject{id, name, {}};
      object_depth = depth;
    }
    if (!object || implicit.back()) return;
    if (is_ring_owner(name) && !in_surface) {
      in_surface = true;
      surface_depth = depth;
      surface = Surface{lods.back(), {}};
    } else if (in_surface && (name == "exterior" || name == "outerBoundaryIs")) {
      ring_kind = 1;
    } else if (in_surface && (name == "interior" || name == "innerBoundaryIs")) {
      ring_kind = 2;
    } else if (in_surface && ring_kind != 0 && (name == "posList" || name == "pos" || name == "coordinates")) {
      reading_text = true;
      text.clear();
      dimension = srs_dimension;
    }
  }

  void end() {
    if (stack.empty()) return;
    const std::string name = stack.back();
    const int depth = static_cast<int>(stack.size()) - 1;
    if (reading_text && (name == "posList" || name == "pos" || name == "coordinates")) {
      reading_text = false;
      if (name == "coordinates") {
        // GML 2: "x,y,z x,y,z": the numbers of a tuple are its commas plus one.
        const auto first = text.find_first_not_of(" \t\r\n");
        const auto tuple_end = first == std::string::npos ? first : text.find_first_of(" \t\r\n", first);
        const std::string tuple = first == std::string::npos ? std::string() : text.substr(first, tuple_end - first);
        add_coordinates(text, static_cast<int>(std::count(tuple.begin(), tuple.end(), ',')) + 1, true);
      } else {
        add_coordinates(text, dimension.value_or(3), false);
      }
    } else if (in_surface && (name == "LinearRing" || name == "Ring")) {
      // A closed ring repeats its first point last: dropped.
      if (ring.size() >= 2 && ring.front() == ring.back()) ring.pop_back();
      if (ring_kind == 1 && surface.rings.empty()) {
        surface.rings.push_back(std::move(ring));
      } else if (ring_kind == 2 && !surface.rings.empty()) {
        surface.rings.push_back(std::move(ring));
      }
      ring.clear();
    } else if (name == "exterior" || name == "interior" || name == "outerBoundaryIs" || name == "innerBoundaryIs") {
      ring_kind = 0;
    }
    if (in_surface && depth == surface_depth) {
      in_surface = false;
      if (!surface.rings.empty()) object->surfaces.push_back(std::move(surface));
      surface = Surface{};
    }
    if (object && depth == object_depth) {
      objects.push_back(std::move(*object));
      object.reset();
      object_depth = -1;
    }
    if (depth == member_depth) member_depth = -1;
    stack.pop_back();
    lods.pop_back();
    implicit.pop_back();
  }
};

Result<WorldModel> read_citygml(const std::filesystem::path& path, const CityModelLoadOptions& options) {
  const std::string where = path.string();
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return make_error(ErrorCode::kIo, where + ": CityGML file not found");
  std::ifstream in(path, std::ios::binary);
  if (!in) return make_error(ErrorCode::kIo, where + ": cannot open the CityGML file");
  Parser parser;
  parser.where = where;
  // Namespace processing off: element names keep their prefix, local_name() strips it.
  std::unique_ptr<std::remove_pointer_t<XML_Parser>, decltype(&XML_ParserFree)> xml(XML_ParserCreate(nullptr),
                                                                                   &XML_ParserFree);
  parser.xml = xml.get();
  XML_SetUserData(xml.get(), &parser);
  XML_SetElementHandler(
      xml.get(),
      [](void* data, const XML_Char* name, const XML_Char** attributes) { static_cast<Parser*>(data)->start(name, attributes); },
      [](void* data, const XML_Char*) { static_cast<Parser*>(data)->end(); });
  XML_SetCharacterDataHandler(xml.get(), [](void* data, const XML_Char* s, int length) {
    auto* p = static_cast<Parser*>(data);
    if (p->reading_text) p->text.append(s, static_cast<std::size_t>(length));
  });
  // Read straight into expat's own buffer (XML_Parse would copy a buffer of ours into it).
  constexpr int kChunkBytes = 1 << 16;
  bool last = false;
  while (!last) {
    void* chunk = XML_GetBuffer(xml.get(), kChunkBytes);
    if (chunk == nullptr) return make_error(ErrorCode::kParse, where + ": out of memory for the XML parser");
    in.read(static_cast<char*>(chunk), kChunkBytes);
    const auto got = static_cast<int>(in.gcount());
    last = got < kChunkBytes;
    if (XML_ParseBuffer(xml.get(), got, last ? XML_TRUE : XML_FALSE) == XML_STATUS_ERROR) {
      if (!parser.error.empty()) return make_error(ErrorCode::kParse, parser.error);
      return make_error(ErrorCode::kParse, fmt::format("{}:{}:{}: malformed XML: {}", where, XML_GetCurrentLineNumber(xml.get()),
                                                       XML_GetCurrentColumnNumber(xml.get()),
                                                       XML_ErrorString(XML_GetErrorCode(xml.get()))));
    }
  }
  if (!parser.error.empty()) return make_error(ErrorCode::kParse, parser.error);

  // The surfaces of each object's highest LoD, their points in one list for the CRS transformation.
  std::vector<Eigen::Vector3d> points;
  for (CityObject& o : parser.objects) {
    int best = -1;
    for (const Surface& s : o.surfaces) best = std::max(best, s.lod);
    std::erase_if(o.surfaces, [&](const Surface& s) { return s.lod != best; });
    for (const Surface& s : o.surfaces) {
      for (const auto& r : s.rings) points.insert(points.end(), r.begin(), r.end());
    }
  }
  if (points.empty()) {
    return make_error(ErrorCode::kNotFound, where + ": no city object with surfaces (gml:Polygon, gml:Triangle) in the file");
  }
  if (parser.srs_name.empty()) {
    return make_error(ErrorCode::kParse, where + ": no srsName: the coordinate reference system is not given");
  }
  const auto epsg = city_model::epsg_code(parser.srs_name);
  if (!epsg) return make_error(ErrorCode::kParse, where + ": srsName '" + parser.srs_name + "': no EPSG code in it");
  if (auto st = city_model::to_wgs84(epsg, true, points, where, "srsName"); !st) return st.error();
  WorldModel world;
  world.name = path.filename().string();
  auto placed = city_model::place(points, options.origin, options.height_offset_m, world, where, "point",
                                  "srsName '" + parser.srs_name + "'");
  if (!placed) return placed.error();

  std::size_t next = 0, skipped_surfaces = 0, unnamed = 0;
  for (const CityObject& c : parser.objects) {
    const std::string name = world.name + "/" + (c.id.empty() ? fmt::format("{}#{}", c.type, ++unnamed) : c.id);
    WorldObject o = city_model::new_object(name, c.id, c.type, options);
    for (const Surface& s : c.surfaces) {
      std::vector<std::vector<Eigen::Vector3d>> rings;
      for (const auto& r : s.rings) {
        rings.emplace_back((*placed).begin() + static_cast<std::ptrdiff_t>(next),
                           (*placed).begin() + static_cast<std::ptrdiff_t>(next + r.size()));
        next += r.size();
      }
      if (!city_model::add_surface(rings, o)) ++skipped_surfaces;
    }
    city_model::keep(std::move(o), world);
  }
  if (auto st = city_model::finish(world, skipped_surfaces, where, "polygons with an area"); !st) return st.error();
  return world;
}

}  // namespace

Result<WorldModel> load_citygml_world(const std::filesystem::path& path, const CityModelLoadOptions& options) {
  return read_citygml(path, options);
}

}  // namespace skytrace::world
