// Mesh files through assimp, the convex hull that turns open vegetation meshes into volumes, and
// worlds made of one mesh file.
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <assimp/Importer.hpp>
#include <cmath>
#include <limits>
#include <unordered_map>
#include <unordered_set>

#include "skytrace/world/loaders.hpp"

namespace skytrace::world {

namespace {

std::string lower_extension(const std::filesystem::path& path) {
  std::string extension = path.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return extension;
}

Eigen::Matrix4d to_eigen(const aiMatrix4x4& m) {
  Eigen::Matrix4d out;
  out << m.a1, m.a2, m.a3, m.a4, m.b1, m.b2, m.b3, m.b4, m.c1, m.c2, m.c3, m.c4, m.d1, m.d2, m.d3,
      m.d4;
  return out;
}

struct Collector {
  const aiScene* scene = nullptr;
  std::vector<MeshPart> parts;

  void walk(const aiNode* node, const Eigen::Matrix4d& parent_transform) {
    const Eigen::Matrix4d transform = parent_transform * to_eigen(node->mTransformation);
    // A mirroring transform flips the winding; undo it so triangles stay counter-clockwise outward.
    const bool mirrored = transform.topLeftCorner<3, 3>().determinant() < 0.0;
    for (unsigned int i = 0; i < node->mNumMeshes; ++i) {
      const aiMesh* mesh = scene->mMeshes[node->mMeshes[i]];
      MeshPart part;
      part.node_name = node->mName.C_Str();
      part.mesh_name = mesh->mName.C_Str();
      part.mesh.vertices_m.reserve(mesh->mNumVertices);
      for (unsigned int v = 0; v < mesh->mNumVertices; ++v) {
        const aiVector3D& p = mesh->mVertices[v];
        const Eigen::Vector4d q = transform * Eigen::Vector4d(p.x, p.y, p.z, 1.0);
        part.mesh.vertices_m.emplace_back(static_cast<float>(q.x()), static_cast<float>(q.y()),
                                          static_cast<float>(q.z()));
      }
      for (unsigned int f = 0; f < mesh->mNumFaces; ++f) {
        const aiFace& face = mesh->mFaces[f];
        if (face.mNumIndices != 3) continue;  // points and lines left by SortByPType
        const auto a = static_cast<int>(face.mIndices[0]);
        const auto b = static_cast<int>(face.mIndices[1]);
        const auto c = static_cast<int>(face.mIndices[2]);
        part.mesh.triangles.emplace_back(a, mirrored ? c : b, mirrored ? b : c);
      }
      if (!part.mesh.triangles.empty()) parts.push_back(std::move(part));
    }
    for (unsigned int c = 0; c < node->mNumChildren; ++c) walk(node->mChildren[c], transform);
  }
};

// Convex hull -------------------------------------------------------------------------------------

struct HullFace {
  std::array<int, 3> v;
  Eigen::Vector3d normal;  // unit, outward
  double offset = 0.0;     // normal . x = offset on the plane
  bool alive = true;
};

HullFace make_face(const std::vector<Eigen::Vector3d>& p, int a, int b, int c) {
  HullFace face{{a, b, c}, Eigen::Vector3d::Zero(), 0.0, true};
  const Eigen::Vector3d n =
      (p[static_cast<std::size_t>(b)] - p[static_cast<std::size_t>(a)])
          .cross(p[static_cast<std::size_t>(c)] - p[static_cast<std::size_t>(a)]);
  const double norm = n.norm();
  face.normal = norm > 0.0 ? Eigen::Vector3d(n / norm) : Eigen::Vector3d::Zero();
  face.offset = face.normal.dot(p[static_cast<std::size_t>(a)]);
  return face;
}

std::uint64_t edge_key(int a, int b) {
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(a)) << 32U) |
         static_cast<std::uint32_t>(b);
}

}  // namespace

namespace {

// The incremental hull. tolerance_m = 0: every point, in order. tolerance_m > 0: the point farthest
// outside the current hull goes in next, until none is farther out than the tolerance.
Result<TriangleMesh> hull_of(const std::vector<Eigen::Vector3f>& points_m, double tolerance_m) {
  // Distinct points in double precision.
  std::vector<Eigen::Vector3d> p;
  {
    std::vector<Eigen::Vector3f> sorted = points_m;
    std::sort(sorted.begin(), sorted.end(), [](const Eigen::Vector3f& a, const Eigen::Vector3f& b) {
      return std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3);
    });
    sorted.erase(std::unique(sorted.begin(), sorted.end()), sorted.end());
    for (const auto& v : sorted) {
      if (!v.allFinite())
        return make_error(ErrorCode::kInvalidArgument, "convex hull: non-finite point");
      p.push_back(v.cast<double>());
    }
  }
  if (p.size() < 4)
    return make_error(ErrorCode::kInvalidArgument, "convex hull: fewer than 4 distinct points");

  Eigen::Vector3d low = p[0];
  Eigen::Vector3d high = p[0];
  for (const auto& q : p) {
    low = low.cwiseMin(q);
    high = high.cwiseMax(q);
  }
  const double scale_m = (high - low).norm();
  const double eps_m = 1e-9 * scale_m;

  // Initial tetrahedron from extreme points, so that the first volume is as large as possible.
  int i0 = 0;
  int i1 = 0;
  for (int i = 0; i < static_cast<int>(p.size()); ++i) {
    if (p[static_cast<std::size_t>(i)].x() < p[static_cast<std::size_t>(i0)].x()) i0 = i;
    if (p[static_cast<std::size_t>(i)].x() > p[static_cast<std::size_t>(i1)].x()) i1 = i;
  }
  if (i0 == i1) i1 = (i0 + 1) % static_cast<int>(p.size());
  const auto at = [&](int i) -> const Eigen::Vector3d& { return p[static_cast<std::size_t>(i)]; };
  int i2 = -1;
  double best = eps_m;
  const Eigen::Vector3d axis = (at(i1) - at(i0)).normalized();
  for (int i = 0; i < static_cast<int>(p.size()); ++i) {
    const Eigen::Vector3d d = at(i) - at(i0);
    const double distance = (d - axis * d.dot(axis)).norm();
    if (distance > best) {
      best = distance;
      i2 = i;
    }
  }
  if (i2 < 0) return make_error(ErrorCode::kInvalidArgument, "convex hull: all points on one line");
  const Eigen::Vector3d plane_normal = (at(i1) - at(i0)).cross(at(i2) - at(i0)).normalized();
  int i3 = -1;
  best = eps_m;
  for (int i = 0; i < static_cast<int>(p.size()); ++i) {
    const double distance = std::abs(plane_normal.dot(at(i) - at(i0)));
    if (distance > best) {
      best = distance;
      i3 = i;
    }
  }
  if (i3 < 0)
    return make_error(ErrorCode::kInvalidArgument, "convex hull: all points in one plane");

  std::vector<HullFace> faces;
  const Eigen::Vector3d inside = (at(i0) + at(i1) + at(i2) + at(i3)) / 4.0;
  const auto add_face = [&](int a, int b, int c) {
    HullFace face = make_face(p, a, b, c);
    if (face.normal.dot(inside) > face.offset) {  // inward: flip
      face = make_face(p, a, c, b);
    }
    faces.push_back(face);
  };
  add_face(i0, i1, i2);
  add_face(i0, i1, i3);
  add_face(i0, i2, i3);
  add_face(i1, i2, i3);

  std::vector<int> visible;
  std::unordered_set<std::uint64_t> visible_edges;
  std::vector<bool> used(p.size(), false);
  for (int i : {i0, i1, i2, i3}) used[static_cast<std::size_t>(i)] = true;
  // The next point to insert: the next one in order, or the farthest outside (none: -1).
  int next_in_order = 0;
  const auto next_point = [&]() -> int {
    if (tolerance_m <= 0.0) {
      while (next_in_order < static_cast<int>(p.size()) && used[static_cast<std::size_t>(next_in_order)]) ++next_in_order;
      return next_in_order < static_cast<int>(p.size()) ? next_in_order : -1;
    }
    int farthest = -1;
    double farthest_m = tolerance_m;
    for (int i = 0; i < static_cast<int>(p.size()); ++i) {
      if (used[static_cast<std::size_t>(i)]) continue;
      for (const HullFace& face : faces) {
        if (!face.alive) continue;
        const double outside_m = face.normal.dot(at(i)) - face.offset;
        if (outside_m > farthest_m) {
          farthest_m = outside_m;
          farthest = i;
        }
      }
    }
    return farthest;
  };
  for (int i = next_point(); i >= 0; i = next_point()) {
    used[static_cast<std::size_t>(i)] = true;
    visible.clear();
    for (int f = 0; f < static_cast<int>(faces.size()); ++f) {
      const HullFace& face = faces[static_cast<std::size_t>(f)];
      if (face.alive && face.normal.dot(at(i)) - face.offset > eps_m) visible.push_back(f);
    }
    if (visible.empty()) continue;  // inside the current hull
    visible_edges.clear();
    for (int f : visible) {
      const auto& v = faces[static_cast<std::size_t>(f)].v;
      for (int k = 0; k < 3; ++k)
        visible_edges.insert(
            edge_key(v[static_cast<std::size_t>(k)], v[(static_cast<std::size_t>(k) + 1) % 3]));
    }
    // Horizon: edges of visible faces whose twin belongs to a face that stays. New faces keep the
    // edge's direction, so they are oriented like the face they replace.
    for (int f : visible) {
      faces[static_cast<std::size_t>(f)].alive = false;
      const auto v = faces[static_cast<std::size_t>(f)].v;
      for (int k = 0; k < 3; ++k) {
        const int a = v[static_cast<std::size_t>(k)];
        const int b = v[(static_cast<std::size_t>(k) + 1) % 3];
        if (visible_edges.count(edge_key(b, a)) == 0) faces.push_back(make_face(p, a, b, i));
      }
    }
  }

  TriangleMesh mesh;
  std::unordered_map<int, int> remap;
  for (const auto& face : faces) {
    if (!face.alive) continue;
    Eigen::Vector3i triangle;
    for (int k = 0; k < 3; ++k) {
      const int source = face.v[static_cast<std::size_t>(k)];
      auto [it, inserted] = remap.emplace(source, static_cast<int>(mesh.vertices_m.size()));
      if (inserted) mesh.vertices_m.push_back(at(source).cast<float>());
      triangle[k] = it->second;
    }
    mesh.triangles.push_back(triangle);
  }
  return mesh;
}

}  // namespace

Result<TriangleMesh> convex_hull(const std::vector<Eigen::Vector3f>& points_m) { return hull_of(points_m, 0.0); }

TriangleMesh simplify_convex_hull(const TriangleMesh& hull, double tolerance_m) {
  if (!(tolerance_m > 0.0)) return hull;
  auto simpler = hull_of(hull.vertices_m, tolerance_m);
  return simpler.ok() ? std::move(*simpler) : hull;
}

Result<std::vector<MeshPart>> read_mesh_file(const std::filesystem::path& path, UpAxis up_axis) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    return make_error(ErrorCode::kIo, path.string() + ": mesh file not found");
  }
  const std::string extension = lower_extension(path);
  const bool is_collada = extension == ".dae";
  // Where assimp leaves the file's axes: COLLADA and FBX are turned Y-up by assimp itself (from
  // their own up-axis declaration), glTF is Y-up by specification, the rest is raw (Z-up for us).
  const bool assimp_output_y_up =
      is_collada || extension == ".gltf" || extension == ".glb" || extension == ".fbx";

  Assimp::Importer importer;
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE,
                              aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  bool rotate_y_up = assimp_output_y_up;
  if (up_axis != UpAxis::kAuto) {
    // An explicit axis overrides the file: make assimp keep the raw coordinates.
    importer.SetPropertyBool(AI_CONFIG_IMPORT_COLLADA_IGNORE_UP_DIRECTION, true);
    rotate_y_up = up_axis == UpAxis::kY;
  }
  const aiScene* scene =
      importer.ReadFile(path.string(), aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                                           aiProcess_SortByPType);
  if (scene == nullptr || scene->mRootNode == nullptr) {
    return make_error(ErrorCode::kParse, path.string() + ": assimp cannot read the mesh: " +
                                             importer.GetErrorString());
  }
  Eigen::Matrix4d root = Eigen::Matrix4d::Identity();
  if (rotate_y_up) {
    // +90 degrees about x: (x, y, z) -> (x, -z, y), so that the file's y becomes our z.
    root << 1, 0, 0, 0, 0, 0, -1, 0, 0, 1, 0, 0, 0, 0, 0, 1;
  }
  Collector collector;
  collector.scene = scene;
  collector.walk(scene->mRootNode, root);
  if (collector.parts.empty()) {
    return make_error(ErrorCode::kParse, path.string() + ": the mesh file holds no triangles");
  }
  return std::move(collector.parts);
}

Result<WorldModel> load_mesh_world(const std::filesystem::path& path, const GeoOrigin& origin,
                                   const MeshLoadOptions& options) {
  if (!(options.scale > 0.0) || !std::isfinite(options.scale)) {
    return make_error(ErrorCode::kInvalidArgument, path.string() + ": mesh scale must be positive");
  }
  auto parts = read_mesh_file(path, options.up_axis);
  if (!parts.ok()) return parts.error();

  WorldModel world;
  world.name = path.stem().string();
  world.geo_origin = origin;
  const std::string file_name = options.name.empty() ? path.filename().string() : options.name;
  world.model_poses[file_name] = options.pose;

  // Group parts into objects: one per node, or one for the whole file.
  std::vector<std::pair<std::string, std::vector<const MeshPart*>>> groups;
  for (const auto& part : *parts) {
    const std::string name =
        options.split_by_node
            ? file_name + "/" + (part.node_name.empty() ? part.mesh_name : part.node_name)
            : file_name;
    auto it =
        std::find_if(groups.begin(), groups.end(), [&](const auto& g) { return g.first == name; });
    if (it == groups.end()) {
      groups.push_back({name, {}});
      it = std::prev(groups.end());
    }
    it->second.push_back(&part);
  }

  for (const auto& [name, members] : groups) {
    WorldObject object;
    object.name = name;
    object.pose = options.pose;
    std::vector<std::string> names = {name};
    for (const MeshPart* part : members) {
      names.push_back(part->mesh_name);
      const int base = static_cast<int>(object.mesh.vertices_m.size());
      for (const auto& v : part->mesh.vertices_m) {
        object.mesh.vertices_m.push_back(v * static_cast<float>(options.scale));
      }
      for (const auto& t : part->mesh.triangles)
        object.mesh.triangles.push_back(t + Eigen::Vector3i::Constant(base));
    }
    const MaterialRule* rule = match_material_rule(options.material_rules, names);
    const bool vegetation_name = std::any_of(names.begin(), names.end(), [](const std::string& n) {
      return name_suggests_vegetation(n);
    });
    if (rule != nullptr) {
      object.material = rule->material;
    } else if (vegetation_name) {
      object.material =
          Material{MaterialClass::kVegetation, options.vegetation_attenuation_db_per_m};
    } else {
      object.material = options.default_material;
    }
    if (rule != nullptr && rule->kind) {
      object.kind = *rule->kind;
    } else if (object.material.is_vegetation()) {
      object.kind = ObjectKind::kTree;
    } else if (object.material.material_class == MaterialClass::kGround) {
      object.kind = ObjectKind::kGround;
    } else {
      object.kind = options.default_kind;
    }
    if (object.material.is_vegetation()) {
      auto hull = convex_hull(object.mesh.vertices_m);
      if (!hull.ok()) {
        world.warnings.push_back(name + ": vegetation skipped, no volume (" + hull.error().message +
                                 ")");
        continue;
      }
      object.mesh = simplify_convex_hull(*hull, options.vegetation_hull_tolerance_m);
    }
    world.objects.push_back(std::move(object));
  }
  return world;
}

}  // namespace skytrace::world
