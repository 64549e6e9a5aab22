// Reflections (image method on merged planar facets) and knife-edge diffraction over convex
// edges, every leg checked with the scene. Geometry in double precision in the world frame.
#include "skytrace/world/propagation.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstddef>
#include <map>
#include <mutex>
#include <numbers>
#include <optional>
#include <tuple>
#include <unordered_map>

#include "skytrace/world/scene.hpp"

namespace skytrace::world {

namespace {

constexpr double kSpeedOfLight_mps = 299792458.0;
// Leg origins are lifted off the surface they leave so that the ray does not hit it again.
constexpr double kSurfaceOffset_m = 0.005;
constexpr double kEdgeOffset_m = 0.02;
// Diffraction candidates kept per blocked satellite (least loss first).
constexpr std::size_t kMaxDiffractedPaths = 3;
// Scattering patches per facet at most (larger patches on larger facets).
constexpr std::size_t kMaxPatchesPerFacet = 256;
// The facet candidates found for one point serve antenna positions this close to it.
constexpr double kCandidateMargin_m = 10.0;
// How much wider the single-precision screens take a cosine than the exact tests after them: far
// above the rounding of a float dot product of unit vectors (below 1e-6).
constexpr float kSinglePrecisionSlack = 1e-5F;

double leg_tolerance_m(double length_m) { return std::max(0.02, 1e-4 * length_m); }

bool is_reflecting(const WorldObject& object) {
  return object.is_static && !object.material.is_vegetation() && !object.mesh.triangles.empty() &&
         object.kind != ObjectKind::kSurroundings;
}
bool is_diffracting(const WorldObject& object) {
  return is_reflecting(object) && object.kind != ObjectKind::kGround &&
         object.material.material_class != MaterialClass::kGround;
}

Eigen::Vector3d any_perpendicular(const Eigen::Vector3d& n) {
  const Eigen::Vector3d helper = std::abs(n.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  return n.cross(helper).normalized();
}

struct KeyHash {
  std::size_t operator()(const std::array<std::int64_t, 4>& k) const {
    std::size_t h = 1469598103934665603ULL;
    for (const auto v : k) h = (h ^ static_cast<std::size_t>(v)) * 1099511628211ULL;
    return h;
  }
};

// x^n by repeated multiplication (n >= 0): the directive lobe's power, the same in its
// normalisation table and in the sums; within a few ulp of std::pow and far cheaper.
double lobe_power(double x, int n) {
  double y = 1.0;
  for (int e = 0; e < n; ++e) y *= x;
  return y;
}

// For the directive scattering lobe ((1 + cos psi) / 2)^n around the specular direction: its
// integral over the hemisphere in front of the surface, per incidence angle 0..90 deg (psi is the
// angle from the specular direction, which leans away from the normal as the incidence does).
// Computed once per exponent, on a 1 deg grid.
const std::array<double, 91>& directive_lobe_integrals(int exponent) {
  static std::mutex mutex;
  static std::map<int, std::array<double, 91>> tables;
  const std::lock_guard lock(mutex);
  auto [it, inserted] = tables.try_emplace(exponent);
  if (!inserted) return it->second;
  constexpr int kSteps = 90;  // polar angle steps over 90 deg
  const double d_theta = 0.5 * std::numbers::pi / kSteps, d_phi = 2.0 * std::numbers::pi / (4 * kSteps);
  // The grid's sines and cosines once (they were taken at every point of every incidence: half the
  // table's cost; the same values, so the same table).
  std::array<double, kSteps> sin_theta{}, cos_theta{};
  std::array<double, 4 * kSteps> sin_phi{}, cos_phi{};
  for (int a = 0; a < kSteps; ++a) {
    const double theta = (a + 0.5) * d_theta;
    sin_theta[static_cast<std::size_t>(a)] = std::sin(theta);
    cos_theta[static_cast<std::size_t>(a)] = std::cos(theta);
  }
  for (int b = 0; b < 4 * kSteps; ++b) {
    const double phi = (b + 0.5) * d_phi;
    sin_phi[static_cast<std::size_t>(b)] = std::sin(phi);
    cos_phi[static_cast<std::size_t>(b)] = std::cos(phi);
  }
  for (int incidence = 0; incidence <= 90; ++incidence) {
    const double ti = incidence * std::numbers::pi / 180.0;
    // Normal along z; the specular direction in the x-z plane.
    const Eigen::Vector3d specular(std::sin(ti), 0.0, std::cos(ti));
    double sum = 0.0;
    for (std::size_t a = 0; a < sin_theta.size(); ++a) {
      for (std::size_t b = 0; b < sin_phi.size(); ++b) {
        const Eigen::Vector3d w(sin_theta[a] * cos_phi[b], sin_theta[a] * sin_phi[b], cos_theta[a]);
        sum += lobe_power(0.5 * (1.0 + specular.dot(w)), exponent) * sin_theta[a] * d_theta * d_phi;
      }
    }
    it->second[static_cast<std::size_t>(incidence)] = sum;
  }
  return it->second;
}

// Marks the unit directions (x, y, z) within both cones (axis, cosine of the half angle; a cosine
// of -2: no cone) with 1, the others 0, and returns how many are marked. In single precision, the
// cones a little wider than given: a pass before the exact test. One loop the compiler vectorises.
__attribute__((target_clones("arch=x86-64-v3", "default"))) int mark_within_cones(
    const float* __restrict x, const float* __restrict y, const float* __restrict z, std::size_t n, float ax, float ay, float az,
    float cos1, float bx, float by, float bz, float cos2, std::int32_t* __restrict within) {
  const float min1 = cos1 - kSinglePrecisionSlack, min2 = cos2 - kSinglePrecisionSlack;
  int count = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const bool in1 = ax * x[i] + ay * y[i] + az * z[i] >= min1;
    const bool in2 = bx * x[i] + by * y[i] + bz * z[i] >= min2;
    const std::int32_t in = in1 && in2 ? 1 : 0;
    within[i] = in;
    count += in;
  }
  return count;
}

// Marks the entries whose band [low, high] of s . axis may hold direction s with 1, the others 0.
// In single precision, the bands given a little wide: a pass before the exact test. One loop the
// compiler vectorises.
__attribute__((target_clones("arch=x86-64-v3", "default"))) void screen_bands(
    const float* __restrict ax, const float* __restrict ay, const float* __restrict az, const float* __restrict low,
    const float* __restrict high, std::size_t n, float sx, float sy, float sz, std::int32_t* __restrict within) {
  for (std::size_t k = 0; k < n; ++k) {
    const float c = ax[k] * sx + ay[k] * sy + az[k] * sz;
    within[k] = static_cast<std::int32_t>(c >= low[k]) & static_cast<std::int32_t>(c <= high[k]);
  }
}

// The second-order facets as arrays (normal, plane offset, bounding sphere), for screen_facet_pairs.
struct FacetArrays {
  std::vector<double> nx, ny, nz, offset, cx, cy, cz, radius;
};

// Facet A's pairs with every facet B, screened before make_facet_pair forms them (docs/performance.md):
// per B, whether the pair may exist (make_facet_pair's conditions, a hair loose: it decides) and its
// two cones, the first when it certainly has one (a cosine of -2 otherwise: every direction), for
// a test against the satellites in single precision. image_a: the antenna's image in A; (na, ca):
// A's plane towards the antenna; centre_a, radius_a: A's sphere; (axis_a, cos_a): the cone from
// image_a through that sphere (cos_a -2: none), sin_a its sine. Also necessary: the reflection
// points lie on one ray from image_a (the one on A between image_a and the one on B), so the
// cones from image_a through both spheres must meet; and both must reach up to lowest_z, the
// lowest satellite's z (up). The planes in double precision; the cones, from differences taken in
// double, in single precision and wider by far more than its rounding (1e-4 in cosine, 1e-4 m).
// One loop the compiler vectorises.
__attribute__((target_clones("arch=x86-64-v3", "default"))) void screen_facet_pairs(
    const FacetArrays& f, std::size_t n, std::size_t a, const Eigen::Vector3d& image_a, const Eigen::Vector3d& na, double ca,
    const Eigen::Vector3d& centre_a, double radius_a, const Eigen::Vector3d& axis_a, double cos_a, double sin_a,
    double lowest_z, std::int32_t* __restrict keep, float* __restrict axis1_x, float* __restrict axis1_y, float* __restrict axis1_z,
    float* __restrict cos1, float* __restrict axis2_x, float* __restrict axis2_y, float* __restrict axis2_z) {
  constexpr double kLoose_m = 1e-9;
  constexpr float kWiderCos = 1e-4F;
  const double iax = image_a.x(), iay = image_a.y(), iaz = image_a.z();
  const double nax = na.x(), nay = na.y(), naz = na.z();
  const double cax = centre_a.x(), cay = centre_a.y(), caz = centre_a.z();
  const double uax = axis_a.x(), uay = axis_a.y(), uaz = axis_a.z();
  const bool cone_a = cos_a > -2.0;
  const auto cos_af = static_cast<float>(cos_a), sin_af = static_cast<float>(sin_a);
  const auto uaxf = static_cast<float>(uax), uayf = static_cast<float>(uay), uazf = static_cast<float>(uaz);
  const auto lowest_zf = static_cast<float>(lowest_z) - kWiderCos;
  const double* __restrict nx = f.nx.data();
  const double* __restrict ny = f.ny.data();
  const double* __restrict nz = f.nz.data();
  const double* __restrict off = f.offset.data();
  const double* __restrict cx = f.cx.data();
  const double* __restrict cy = f.cy.data();
  const double* __restrict cz = f.cz.data();
  const double* __restrict rb = f.radius.data();
  for (std::size_t b = 0; b < n; ++b) {
    // The planes (bitwise: no branch in the loop).
    const double hb = nx[b] * iax + ny[b] * iay + nz[b] * iaz - off[b];
    const double side = hb >= 0.0 ? 1.0 : -1.0;
    const int planes = static_cast<int>(b != a) & static_cast<int>(std::abs(hb) >= 1e-6 - kLoose_m) &
                       static_cast<int>(nax * cx[b] + nay * cy[b] + naz * cz[b] + rb[b] > ca - kLoose_m) &
                       static_cast<int>(side * (nx[b] * cax + ny[b] * cay + nz[b] * caz - off[b]) + radius_a > -kLoose_m);
    const auto r_b = static_cast<float>(rb[b]);
    // The cones from image_a through A's sphere and B's meet: the angle between v and A's axis is
    // within both half angles, v . axis_a >= cos_a sqrt(|v|^2 - r_b^2) - sin_a r_b.
    const auto vx = static_cast<float>(cx[b] - iax), vy = static_cast<float>(cy[b] - iay), vz = static_cast<float>(cz[b] - iaz);
    const float v2 = vx * vx + vy * vy + vz * vz;
    const float bound = cos_af * std::sqrt(std::max(v2 - r_b * r_b, 0.0F)) - sin_af * r_b;
    const int meet = static_cast<int>(!cone_a) | static_cast<int>(v2 <= r_b * r_b) |
                     static_cast<int>(vx * uaxf + vy * uayf + vz * uazf >= bound - 1e-4F * (std::abs(vx) + std::abs(vy) + std::abs(vz) + 1.0F));
    // The first cone, from image_ab = image_a - 2 |hb| nb = image_a - 2 hb n, only where it is
    // certainly one (the apex well outside the sphere).
    const auto tx = static_cast<float>(cx[b] - (iax - 2.0 * hb * nx[b]));
    const auto ty = static_cast<float>(cy[b] - (iay - 2.0 * hb * ny[b]));
    const auto tz = static_cast<float>(cz[b] - (iaz - 2.0 * hb * nz[b]));
    const float d2 = tx * tx + ty * ty + tz * tz;
    const float cone_limit = r_b * 1.001F + 1e-3F;
    const bool cone = d2 > cone_limit * cone_limit;
    const float inverse = cone ? 1.0F / std::sqrt(std::max(d2, 1e-30F)) : 0.0F;
    const float sin_half = r_b * inverse;
    const float cos_half = std::sqrt(std::max(1.0F - sin_half * sin_half, 0.0F));
    axis1_x[b] = tx * inverse;
    axis1_y[b] = ty * inverse;
    axis1_z[b] = tz * inverse;
    cos1[b] = cone ? cos_half - kWiderCos : -2.0F;
    // The second cone, A's mirrored in B.
    const double along = nx[b] * uax + ny[b] * uay + nz[b] * uaz;
    const auto z2 = static_cast<float>(uaz - 2.0 * along * nz[b]);
    axis2_x[b] = cone_a ? static_cast<float>(uax - 2.0 * along * nx[b]) : 0.0F;
    axis2_y[b] = cone_a ? static_cast<float>(uay - 2.0 * along * ny[b]) : 0.0F;
    axis2_z[b] = cone_a ? z2 : 0.0F;
    // Both cones reach up to the lowest satellite: a cone's highest point lies at
    // cos(zenith angle of its axis - half angle) = z cos h + sqrt(1 - z^2) sin h, or the zenith.
    const float z1 = tz * inverse;
    const float top1 = z1 >= cos_half ? 1.0F : z1 * cos_half + std::sqrt(std::max(1.0F - z1 * z1, 0.0F)) * sin_half;
    const float top2 = z2 >= cos_af ? 1.0F : z2 * cos_af + std::sqrt(std::max(1.0F - z2 * z2, 0.0F)) * sin_af;
    const int reach_sky = (static_cast<int>(!cone) | static_cast<int>(top1 >= lowest_zf)) &
                          (static_cast<int>(!cone_a) | static_cast<int>(top2 >= lowest_zf));
    keep[b] = planes & meet & reach_sky;
  }
}

// The facets seen from the antenna as arrays: normal towards it, its height above the plane, its
// image in the plane, the bounding sphere (radius squared), for screen_reflections.
struct ReflectorArrays {
  std::vector<double> nx, ny, nz, height, ix, iy, iz, cx, cy, cz, radius2;
};

// First-order reflections of direction s: 1 for each facet whose reflection point may exist (the
// point where the line from the image towards s meets the plane, within the radius and the
// facet's sphere; a hair loose: the exact test decides), 0 otherwise. One loop the compiler vectorises.
__attribute__((target_clones("arch=x86-64-v3", "default"))) void screen_reflections(const ReflectorArrays& f, std::size_t n,
                                                                                      const Eigen::Vector3d& s, double radius_m,
                                                                                      double* __restrict may_reflect) {
  const double sx = s.x(), sy = s.y(), sz = s.z();
  const double* __restrict nx = f.nx.data();
  const double* __restrict ny = f.ny.data();
  const double* __restrict nz = f.nz.data();
  const double* __restrict h = f.height.data();
  const double* __restrict ix = f.ix.data();
  const double* __restrict iy = f.iy.data();
  const double* __restrict iz = f.iz.data();
  const double* __restrict cx = f.cx.data();
  const double* __restrict cy = f.cy.data();
  const double* __restrict cz = f.cz.data();
  const double* __restrict r2 = f.radius2.data();
  const double max_t = radius_m * (1.0 + 1e-9);
  for (std::size_t k = 0; k < n; ++k) {
    const double ns = nx[k] * sx + ny[k] * sy + nz[k] * sz;
    const double t = h[k] / std::max(ns, 1e-12);
    const double dx = ix[k] + t * sx - cx[k], dy = iy[k] + t * sy - cy[k], dz = iz[k] + t * sz - cz[k];
    const double d2 = dx * dx + dy * dy + dz * dz;
    may_reflect[k] = static_cast<int>(ns > 1e-6 - 1e-12) & static_cast<int>(t <= max_t) &
                             static_cast<int>(d2 <= r2[k] * (1.0 + 1e-9) + 1e-6)
                         ? 1.0
                         : 0.0;
  }
}

// Keller's points (keller_point) of edges [begin, end) of one object seen from `origin` towards s:
// 1 where the point may lie inside the edge (a hair loose: keller_point decides), 0 where it
// cannot; inside[k - begin]. One loop the compiler vectorises.
__attribute__((target_clones("arch=x86-64-v3", "default"))) void screen_keller_points(
    const double* __restrict sx, const double* __restrict sy, const double* __restrict sz, const double* __restrict ax,
    const double* __restrict ay, const double* __restrict az, const double* __restrict length, std::size_t begin,
    std::size_t end, const Eigen::Vector3d& origin, const Eigen::Vector3d& s, double* __restrict inside) {
  const double ox = origin.x(), oy = origin.y(), oz = origin.z();
  const double dx = s.x(), dy = s.y(), dz = s.z();
  for (std::size_t k = begin; k < end; ++k) {
    const double c = dx * ax[k] + dy * ay[k] + dz * az[k];
    const double wx = sx[k] - ox, wy = sy[k] - oy, wz = sz[k] - oz;
    const double along = wx * ax[k] + wy * ay[k] + wz * az[k];
    const double px = wx - along * ax[k], py = wy - along * ay[k], pz = wz - along * az[k];
    const double rho = std::sqrt(px * px + py * py + pz * pz);
    const double sin2 = 1.0 - c * c;
    const double u = c * rho / std::sqrt(std::max(sin2, 1e-300)) - along;
    // u's rounding grows as sin2 shrinks (to 1e-7 relative at sin2 = 1e-9).
    const double margin = 1e-6 * (std::abs(u) + 1.0);
    inside[k - begin] = static_cast<int>(sin2 >= 1e-9 - 1e-15) & static_cast<int>(u > 1e-3 - margin) &
                                static_cast<int>(u < length[k] - 1e-3 + margin)
                            ? 1.0
                            : 0.0;
  }
}

// Spheres [begin, end) that may hold an edge point of a path over the edge, then off a facet: on
// the facet's side towards the receiver (normal . x > plane), within the cone from the receiver's
// image through the facet's sphere (when `cone`: axis, sine and cosine of its half angle), and near
// the image's line towards s (may_reach_line). 1 where a sphere may (the tests of the search's
// may_hold, a hair loose), 0 where none of its points can; may_hold[k - begin]. One loop the
// compiler vectorises.
__attribute__((target_clones("arch=x86-64-v3", "default"))) void screen_spheres(
    const double* __restrict cx, const double* __restrict cy, const double* __restrict cz, const double* __restrict radius,
    std::size_t begin, std::size_t end, const Eigen::Vector3d& normal, double plane, const Eigen::Vector3d& image, bool cone,
    const Eigen::Vector3d& axis, double cone_sin, double cone_cos, const Eigen::Vector3d& s, double excess_max_m,
    double* __restrict may_hold) {
  const double nx = normal.x(), ny = normal.y(), nz = normal.z();
  const double ix = image.x(), iy = image.y(), iz = image.z();
  const double ux = axis.x(), uy = axis.y(), uz = axis.z();
  const double sx = s.x(), sy = s.y(), sz = s.z();
  for (std::size_t k = begin; k < end; ++k) {
    const double r = radius[k];
    const int above = static_cast<int>(nx * cx[k] + ny * cy[k] + nz * cz[k] - plane + r > -1e-9);
    const double mx = cx[k] - ix, my = cy[k] - iy, mz = cz[k] - iz;
    const double d2 = mx * mx + my * my + mz * mz;
    const double d = std::sqrt(d2);
    const double sin_b = std::min(r / std::max(d, 1e-300), 1.0);
    const double cos_b = std::sqrt(std::max(1.0 - sin_b * sin_b, 0.0));
    const int in_cone = static_cast<int>(!cone) | static_cast<int>(d <= r) |
                        static_cast<int>(mx * ux + my * uy + mz * uz >= d * (cone_cos * cos_b - cone_sin * sin_b - 1e-9) - 1e-9 * (d + 1.0));
    const double along = mx * sx + my * sy + mz * sz;
    const double h = std::max(std::sqrt(std::max(d2 - along * along, 0.0)) - r, 0.0);
    const int near_line = static_cast<int>(along >= -r - 1e-9) &
                          static_cast<int>(h * h <= 2.0 * excess_max_m * (d + r) * (1.0 + 1e-9) + 1e-9);
    may_hold[k - begin] = (above & in_cone & near_line) != 0 ? 1.0 : 0.0;
  }
}

// visit(k) for each edge k in [begin, end) of an object's edge arrays whose Keller point from
// `origin` towards s may lie inside it (screen_keller_points, in chunks), in order.
template <class EdgeArrays, class Visit>
void for_each_edge_keller_may_hit(const EdgeArrays& arrays, std::size_t begin, std::size_t end, const Eigen::Vector3d& origin,
                                  const Eigen::Vector3d& s, Visit&& visit) {
  std::array<double, 64> inside;
  for (std::size_t first = begin; first < end; first += inside.size()) {
    const std::size_t last = std::min(end, first + inside.size());
    screen_keller_points(arrays.sx.data(), arrays.sy.data(), arrays.sz.data(), arrays.ax.data(), arrays.ay.data(), arrays.az.data(),
                         arrays.length.data(), first, last, origin, s, inside.data());
    for (std::size_t k = first; k < last; ++k) {
      if (inside[k - first] != 0.0) visit(k);
    }
  }
}

// A double bounce's second cone is reflected in B's plane: a little wider than the first.
constexpr double kMirroredConeWider = 1e-7;

// The cone from `apex` through a facet's bounding sphere: unit axis, the cosine of its half angle
// less `wider`, and the sine; a cosine of -2 when the apex lies within the sphere (no cone).
struct SphereCone {
  Eigen::Vector3d axis = Eigen::Vector3d::Zero();
  double cos = -2.0, sin = 1.0;
};
SphereCone sphere_cone(const Facet& f, const Eigen::Vector3d& apex, double wider) {
  SphereCone cone;
  const Eigen::Vector3d to_centre = f.centre_m - apex;
  const double distance_m = to_centre.norm();
  if (distance_m > f.radius_m * (1.0 + 1e-9) + 1e-9) {
    cone.axis = to_centre / distance_m;
    cone.sin = f.radius_m / distance_m;
    cone.cos = std::sqrt(1.0 - cone.sin * cone.sin) - wider;
  }
  return cone;
}

// Whether any point within radius_m of centre_m can lie on a path from `origin` over it towards
// direction s with at most excess_max_m more length than the straight line: the excess over a
// point at distance h from the line and D from the origin is at least h^2 / (2 D).
bool may_reach_line(const Eigen::Vector3d& origin, const Eigen::Vector3d& s, double excess_max_m,
                    const Eigen::Vector3d& centre_m, double radius_m) {
  const Eigen::Vector3d m = centre_m - origin;
  const double along = m.dot(s);
  if (along < -radius_m) return false;
  const double h_min = std::max(std::sqrt(std::max(m.squaredNorm() - along * along, 0.0)) - radius_m, 0.0);
  return h_min * h_min <= 2.0 * excess_max_m * (m.norm() + radius_m);
}

// may_reach_line for some direction s within `reach` of `axis`: the line's reach at the sphere's
// distance widened by that angle (or the sphere near the origin, where a line could also pass it
// backwards within the excess).
bool may_reach_cone(const Eigen::Vector3d& origin, const Eigen::Vector3d& axis, const ConeReach& reach,
                    double excess_max_m, const Eigen::Vector3d& centre_m, double radius_m) {
  const Eigen::Vector3d m = centre_m - origin;
  const double distance_m = m.norm();
  const double rho_m = radius_m + std::sqrt(2.0 * excess_max_m * (distance_m + radius_m));
  if (distance_m <= std::sqrt(rho_m * rho_m + radius_m * radius_m) * (1.0 + 1e-9) + 1e-9 || rho_m >= distance_m) return true;
  if (reach.rad >= 0.5 * std::numbers::pi) return true;
  // The angle from the axis within asin(x) + reach, x = rho / distance, both below pi / 2: as
  // cosines, cos(asin(x) + reach) = sqrt(1 - x^2) cos(reach) - x sin(reach), a hair wide (a screen).
  const double x = rho_m / distance_m;
  const double cos_limit = std::sqrt(1.0 - x * x) * reach.cos - x * reach.sin;
  return m.dot(axis) >= distance_m * (cos_limit - 1e-12);
}

// The point of the edge where the ray from `origin` and the direction s towards the satellite make
// equal angles with it (Keller's cone: the stationary path over the edge), if it lies inside the edge.
std::optional<Eigen::Vector3d> keller_point(const DiffractionEdge& edge, const Eigen::Vector3d& origin, const Eigen::Vector3d& s) {
  const Eigen::Vector3d& axis = edge.axis;
  const double length = edge.length_m;
  const double c = s.dot(axis);
  if (1.0 - c * c < 1e-9) return std::nullopt;
  const Eigen::Vector3d w = edge.start_m - origin;
  const double along = w.dot(axis);
  const double rho = (w - along * axis).norm();
  const double u = c * rho / std::sqrt(1.0 - c * c) - along;
  if (u <= 1e-3 || u >= length - 1e-3) return std::nullopt;
  return Eigen::Vector3d(edge.start_m + u * axis);
}

// The direct path first, then the others strongest first.
void sort_indirect_paths_by_power(std::vector<PathSet>& sets) {
  for (PathSet& set : sets) {
    const auto begin = set.paths.begin() + ((!set.paths.empty() && set.paths.front().type == PathType::kDirect) ? 1 : 0);
    std::stable_sort(begin, set.paths.end(),
                     [](const SignalPath& a, const SignalPath& b) { return a.power_linear() > b.power_linear(); });
  }
}

// RHCP/LHCP field components after a reflection with the given circular coefficients.
void reflect_state(std::complex<double>& rhcp, std::complex<double>& lhcp, const FresnelCoefficients& f) {
  const std::complex<double> r = f.co * rhcp + f.cross * lhcp;
  const std::complex<double> l = f.cross * rhcp + f.co * lhcp;
  rhcp = r;
  lhcp = l;
}

// A cell of the sky for PathSearchSettings::static_sky_cell_deg: bands of elevation, each cut into
// whole cells of about the size on the sky in azimuth. Its key and its centre direction (ENU).
struct SkyCell {
  std::uint64_t key = 0;
  Eigen::Vector3d centre = Eigen::Vector3d::UnitZ();
};
SkyCell sky_cell_of(const Eigen::Vector3d& s, double requested_cell_deg) {
  constexpr double kDeg = std::numbers::pi / 180.0;
  const double cell_deg = std::max(requested_cell_deg, 1e-3);  // so that a cell's number fits its 32 bits
  const double elevation_deg = std::asin(std::clamp(s.z(), -1.0, 1.0)) / kDeg;
  double azimuth_deg = std::atan2(s.x(), s.y()) / kDeg;
  if (azimuth_deg < 0.0) azimuth_deg += 360.0;
  const auto bands = std::max<std::int64_t>(1, std::llround(180.0 / cell_deg));
  const double band_deg = 180.0 / static_cast<double>(bands);
  const std::int64_t band = std::clamp<std::int64_t>(static_cast<std::int64_t>(std::floor((elevation_deg + 90.0) / band_deg)), 0, bands - 1);
  const double centre_elevation_deg = -90.0 + (static_cast<double>(band) + 0.5) * band_deg;
  const auto cells = std::max<std::int64_t>(1, static_cast<std::int64_t>(std::floor(360.0 * std::cos(centre_elevation_deg * kDeg) / cell_deg)));
  const double cell_azimuth_deg = 360.0 / static_cast<double>(cells);
  const std::int64_t cell = std::clamp<std::int64_t>(static_cast<std::int64_t>(std::floor(azimuth_deg / cell_azimuth_deg)), 0, cells - 1);
  const double centre_azimuth_deg = (static_cast<double>(cell) + 0.5) * cell_azimuth_deg;
  SkyCell out;
  out.key = (static_cast<std::uint64_t>(band) << 32U) | static_cast<std::uint64_t>(cell);
  out.centre = enu_direction(centre_azimuth_deg, centre_elevation_deg);
  return out;
}

}  // namespace

Eigen::Vector3d sky_cell_centre(const Eigen::Vector3d& direction, double cell_deg) {
  return sky_cell_of(direction, cell_deg).centre;
}

ElectricalProperties electrical_properties(MaterialClass material, double frequency_hz) {
  const double f_ghz = frequency_hz * 1e-9;
  // a, b, c, d of ITU-R P.2040-1 Table 3 (frequency in GHz).
  struct Coefficients {
    double a, b, c, d;
  };
  Coefficients k{5.31, 0.0, 0.0326, 0.8095};  // concrete
  switch (material) {
    case MaterialClass::kConcrete:
    case MaterialClass::kUnknown: break;
    case MaterialClass::kBrick: k = {3.75, 0.0, 0.038, 0.0}; break;
    case MaterialClass::kGlass: k = {6.27, 0.0, 0.0043, 1.1925}; break;
    case MaterialClass::kMetal: k = {1.0, 0.0, 1e7, 0.0}; break;
    case MaterialClass::kWood: k = {1.99, 0.0, 0.0047, 1.0718}; break;
    case MaterialClass::kGround: k = {15.0, -0.1, 0.035, 1.63}; break;  // medium dry ground, 1-10 GHz
    case MaterialClass::kVegetation: k = {1.0, 0.0, 0.0, 0.0}; break;   // not a reflector
  }
  return {k.a * std::pow(f_ghz, k.b), k.c * std::pow(f_ghz, k.d)};
}

std::complex<double> complex_permittivity(MaterialClass material, double frequency_hz) {
  const ElectricalProperties e = electrical_properties(material, frequency_hz);
  return {e.relative_permittivity, -17.98 * e.conductivity_s_per_m / (frequency_hz * 1e-9)};
}

FresnelCoefficients fresnel_coefficients(std::complex<double> eta, double cos_incidence) {
  const double c = std::clamp(cos_incidence, 0.0, 1.0);
  const double sin2 = 1.0 - c * c;
  const std::complex<double> root = std::sqrt(eta - sin2);
  FresnelCoefficients f;
  f.te = (c - root) / (c + root);
  f.tm = (eta * c - root) / (eta * c + root);
  f.co = 0.5 * (f.te + f.tm);
  f.cross = 0.5 * (f.te - f.tm);
  return f;
}

double knife_edge_loss_db(double v) {
  if (v <= -0.78) return 0.0;
  const double x = v - 0.1;
  return 6.9 + 20.0 * std::log10(std::sqrt(x * x + 1.0) + x);
}

namespace {

// 10^(-loss/10), a power's factor, and 10^(-loss/20), an amplitude's: exactly 1 without a loss,
// as std::pow gives it, without the call (most rays cross no vegetation).
double power_factor(double loss_db) { return loss_db == 0.0 ? 1.0 : std::pow(10.0, -loss_db / 10.0); }
double amplitude_factor(double loss_db) { return loss_db == 0.0 ? 1.0 : std::pow(10.0, -loss_db / 20.0); }

// Facet::contains in parts, so that a caller testing many points of one facet can try only the
// triangles near each: the point in the facet's plane coordinates, whether it lies in the facet's
// box, and whether it lies in the triangle whose first vertex is triangles_uv[i] (boundary included).
constexpr double kContainsSlack = 1e-9;

Eigen::Vector2d plane_coordinates(const Facet& f, const Eigen::Vector3d& point_m) {
  const Eigen::Vector3d d = point_m - f.origin_m;
  return {d.dot(f.axis_u), d.dot(f.axis_v)};
}

bool within_box(const Facet& f, const Eigen::Vector2d& p) {
  return !((p.array() < f.min_uv.array() - kContainsSlack).any() || (p.array() > f.max_uv.array() + kContainsSlack).any());
}

bool within_triangle(const Facet& f, const Eigen::Vector2d& p, std::size_t i) {
  const Eigen::Vector2d& a = f.triangles_uv[i];
  const Eigen::Vector2d e1 = f.triangles_uv[i + 1] - a, e2 = f.triangles_uv[i + 2] - a, q = p - a;
  const double det = e1.x() * e2.y() - e1.y() * e2.x();
  if (det == 0.0) return false;
  const double s = (q.x() * e2.y() - q.y() * e2.x()) / det;
  const double t = (e1.x() * q.y() - e1.y() * q.x()) / det;
  return s >= -kContainsSlack && t >= -kContainsSlack && s + t <= 1.0 + kContainsSlack;
}

}  // namespace

bool Facet::contains(const Eigen::Vector3d& point_m) const {
  const Eigen::Vector2d p = plane_coordinates(*this, point_m);
  if (!within_box(*this, p)) return false;
  const bool bounded = 3 * triangle_bounds_uv.size() == triangles_uv.size();
  for (std::size_t i = 0; i + 2 < triangles_uv.size(); i += 3) {
    if (bounded) {
      const std::array<double, 4>& b = triangle_bounds_uv[i / 3];
      if (p.x() < b[0] || p.y() < b[1] || p.x() > b[2] || p.y() > b[3]) continue;
    }
    if (within_triangle(*this, p, i)) return true;
  }
  return false;
}

void Facet::set_triangle_bounds() {
  triangle_bounds_uv.clear();
  for (std::size_t i = 0; i + 2 < triangles_uv.size(); i += 3) {
    const Eigen::Vector2d low = triangles_uv[i].cwiseMin(triangles_uv[i + 1]).cwiseMin(triangles_uv[i + 2]);
    const Eigen::Vector2d high = triangles_uv[i].cwiseMax(triangles_uv[i + 1]).cwiseMax(triangles_uv[i + 2]);
    // within_triangle's barycentric slack reaches at most about 6 kContainsSlack times the
    // triangle's extent beyond its corners: the box is a thousand times wider than that.
    const double margin = 1e-6 * (high - low).maxCoeff() + 1e-9;
    triangle_bounds_uv.push_back({low.x() - margin, low.y() - margin, high.x() + margin, high.y() + margin});
  }
}

Result<std::unique_ptr<PropagationScene>> PropagationScene::build(const WorldModel& world,
                                                                  std::shared_ptr<const PathQuery> scene) {
  if (!scene) return make_error(ErrorCode::kInvalidArgument, "propagation scene: no ray-casting scene given");
  if (auto valid = validate_world_for_scene(world); !valid) return valid.error();
  std::unique_ptr<PropagationScene> out(new PropagationScene());
  out->scene_ = std::move(scene);

  for (const WorldObject& object : world.objects) {
    if (!is_reflecting(object)) continue;
    const std::size_t object_index = out->object_names_.size();
    out->object_names_.push_back(object.name);
    out->object_index_.emplace(object.name, object_index);
    out->object_edges_.emplace_back();
    std::vector<Eigen::Vector3d> vertices;
    vertices.reserve(object.mesh.vertices_m.size());
    for (const auto& v : object.mesh.vertices_m) vertices.push_back(object.pose * v.cast<double>());
    // Weld vertices (meshes often repeat them per face) so that edges are shared.
    std::map<std::array<std::int64_t, 3>, int> welded;
    std::vector<int> weld_id(vertices.size());
    for (std::size_t i = 0; i < vertices.size(); ++i) {
      const std::array<std::int64_t, 3> key{std::llround(vertices[i].x() * 1000.0), std::llround(vertices[i].y() * 1000.0),
                                            std::llround(vertices[i].z() * 1000.0)};
      weld_id[i] = welded.try_emplace(key, static_cast<int>(welded.size())).first->second;
    }

    // Coplanar triangles: keyed by the plane (normal to 0.005, offset to 2 cm), the normal turned
    // so that its largest component is positive (meshes are not always wound consistently).
    struct Group {
      Eigen::Vector3d normal_sum = Eigen::Vector3d::Zero();
      double offset_sum = 0.0, area = 0.0;
      std::vector<Eigen::Vector3d> corners;
    };
    std::unordered_map<std::array<std::int64_t, 4>, std::size_t, KeyHash> group_of;
    std::vector<Group> groups;
    struct EdgeUse {
      int count = 0;
      std::array<std::size_t, 2> triangle{};
      std::array<int, 2> opposite{};
    };
    std::map<std::pair<int, int>, EdgeUse> edge_uses;
    std::vector<Eigen::Vector3d> triangle_normals;
    std::vector<std::array<int, 3>> triangle_ids;
    for (const auto& tri : object.mesh.triangles) {
      const Eigen::Vector3d& a = vertices[static_cast<std::size_t>(tri[0])];
      const Eigen::Vector3d& b = vertices[static_cast<std::size_t>(tri[1])];
      const Eigen::Vector3d& c = vertices[static_cast<std::size_t>(tri[2])];
      if (triangle_is_degenerate(a, b, c)) continue;
      const Eigen::Vector3d cross = (b - a).cross(c - a);
      const double area = 0.5 * cross.norm();
      const Eigen::Vector3d n = cross.normalized();
      Eigen::Index largest = 0;
      n.cwiseAbs().maxCoeff(&largest);
      const Eigen::Vector3d canonical = n[largest] < 0.0 ? Eigen::Vector3d(-n) : n;
      const double offset = canonical.dot((a + b + c) / 3.0);
      const std::array<std::int64_t, 4> key{std::llround(canonical.x() / 0.005), std::llround(canonical.y() / 0.005),
                                            std::llround(canonical.z() / 0.005), std::llround(offset / 0.02)};
      auto [it, inserted] = group_of.try_emplace(key, groups.size());
      if (inserted) groups.emplace_back();
      Group& g = groups[it->second];
      g.normal_sum += area * canonical;
      g.offset_sum += area * offset;
      g.area += area;
      g.corners.insert(g.corners.end(), {a, b, c});

      const std::size_t t = triangle_normals.size();
      triangle_normals.push_back(n);
      const std::array<int, 3> ids{weld_id[static_cast<std::size_t>(tri[0])], weld_id[static_cast<std::size_t>(tri[1])],
                                   weld_id[static_cast<std::size_t>(tri[2])]};
      triangle_ids.push_back(ids);
      for (int e = 0; e < 3; ++e) {
        const int i0 = ids[static_cast<std::size_t>(e)], i1 = ids[static_cast<std::size_t>((e + 1) % 3)];
        EdgeUse& use = edge_uses[{std::min(i0, i1), std::max(i0, i1)}];
        if (use.count < 2) {
          use.triangle[static_cast<std::size_t>(use.count)] = t;
          use.opposite[static_cast<std::size_t>(use.count)] = ids[static_cast<std::size_t>((e + 2) % 3)];
        }
        ++use.count;
      }
    }
    for (Group& g : groups) {
      Facet f;
      f.normal = g.normal_sum.normalized();
      f.offset_m = g.offset_sum / g.area;
      f.area_m2 = g.area;
      f.material = object.material.material_class;
      f.object = object_index;
      f.origin_m = g.corners.front() - (f.normal.dot(g.corners.front()) - f.offset_m) * f.normal;
      f.axis_u = any_perpendicular(f.normal);
      f.axis_v = f.normal.cross(f.axis_u);
      f.min_uv = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
      f.max_uv = -f.min_uv;
      f.min_m = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
      f.max_m = -f.min_m;
      for (const Eigen::Vector3d& corner : g.corners) {
        const Eigen::Vector3d d = corner - f.origin_m;
        const Eigen::Vector2d uv(d.dot(f.axis_u), d.dot(f.axis_v));
        f.triangles_uv.push_back(uv);
        f.min_uv = f.min_uv.cwiseMin(uv);
        f.max_uv = f.max_uv.cwiseMax(uv);
        f.min_m = f.min_m.cwiseMin(corner);
        f.max_m = f.max_m.cwiseMax(corner);
      }
      f.centre_m = 0.5 * (f.min_m + f.max_m);
      f.radius_m = 0.5 * (f.max_m - f.min_m).norm();
      f.set_triangle_bounds();
      out->facets_.push_back(std::move(f));
    }

    if (!is_diffracting(object)) continue;
    std::vector<Eigen::Vector3d> welded_position(welded.size());
    for (std::size_t i = 0; i < vertices.size(); ++i) welded_position[static_cast<std::size_t>(weld_id[i])] = vertices[i];
    for (const auto& [ends, use] : edge_uses) {
      const Eigen::Vector3d& p0 = welded_position[static_cast<std::size_t>(ends.first)];
      const Eigen::Vector3d& p1 = welded_position[static_cast<std::size_t>(ends.second)];
      DiffractionEdge edge;
      edge.start_m = p0;
      edge.end_m = p1;
      edge.object = object_index;
      edge.material = object.material.material_class;
      edge.midpoint_m = 0.5 * (p0 + p1);
      edge.half_length_m = 0.5 * (p1 - p0).norm();
      edge.axis = p1 - p0;
      edge.length_m = edge.axis.norm();
      edge.axis /= edge.length_m;
      if (use.count == 1) {
        // Boundary of an open surface: outward in the triangle's plane, away from its third vertex.
        const Eigen::Vector3d n = triangle_normals[use.triangle[0]];
        Eigen::Vector3d out_dir = (p1 - p0).cross(n).normalized();
        if (out_dir.dot(welded_position[static_cast<std::size_t>(use.opposite[0])] - p0) > 0.0) out_dir = -out_dir;
        edge.outward = out_dir;
        edge.face_normal_a = n;
        edge.face_normal_b = -n;
      } else if (use.count == 2) {
        const Eigen::Vector3d& n0 = triangle_normals[use.triangle[0]];
        const Eigen::Vector3d& n1 = triangle_normals[use.triangle[1]];
        if (n0.dot(n1) > std::cos(20.0 * std::numbers::pi / 180.0)) continue;  // (nearly) flat: no edge
        // Convex (outward winding): the other face's far vertex lies behind this face's plane.
        const Eigen::Vector3d& far = welded_position[static_cast<std::size_t>(use.opposite[1])];
        if (n0.dot(far - p0) > 1e-6) continue;
        const Eigen::Vector3d bisector = n0 + n1;
        if (bisector.norm() < 1e-9) continue;  // a zero-thickness fin
        edge.outward = bisector.normalized();
        edge.face_normal_a = n0;
        edge.face_normal_b = n1;
      } else {
        continue;  // non-manifold
      }
      out->object_edges_[object_index].push_back(out->edges_.size());
      out->edges_.push_back(edge);
    }
  }

  // Each object's edges in Morton order of their midpoints, in clusters of 16.
  out->object_clusters_.resize(out->object_edges_.size());
  for (std::size_t o = 0; o < out->object_edges_.size(); ++o) {
    auto& list = out->object_edges_[o];
    if (list.empty()) continue;
    Eigen::Vector3d lo3 = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi3 = -lo3;
    for (const std::size_t e : list) {
      lo3 = lo3.cwiseMin(out->edges_[e].midpoint_m);
      hi3 = hi3.cwiseMax(out->edges_[e].midpoint_m);
    }
    const Eigen::Vector3d span3 = (hi3 - lo3).cwiseMax(1e-9);
    auto morton = [&](std::size_t e) {
      std::uint64_t code = 0;
      const Eigen::Vector3d q = ((out->edges_[e].midpoint_m - lo3).cwiseQuotient(span3) * 1023.0).cwiseMax(0.0);
      const std::array<std::uint64_t, 3> c{static_cast<std::uint64_t>(q.x()), static_cast<std::uint64_t>(q.y()),
                                           static_cast<std::uint64_t>(q.z())};
      for (int bit = 9; bit >= 0; --bit) {
        for (std::size_t axis = 0; axis < 3; ++axis) code = (code << 1) | ((c[axis] >> bit) & 1U);
      }
      return code;
    };
    std::vector<std::pair<std::uint64_t, std::size_t>> keyed;
    for (const std::size_t e : list) keyed.emplace_back(morton(e), e);
    std::sort(keyed.begin(), keyed.end());
    for (std::size_t k = 0; k < keyed.size(); ++k) list[k] = keyed[k].second;
    constexpr std::size_t kClusterSize = 16;
    for (std::size_t begin = 0; begin < list.size(); begin += kClusterSize) {
      EdgeCluster cluster;
      cluster.begin = begin;
      cluster.end = std::min(list.size(), begin + kClusterSize);
      Eigen::Vector3d clo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), chi = -clo;
      for (std::size_t k = cluster.begin; k < cluster.end; ++k) {
        const DiffractionEdge& e = out->edges_[list[k]];
        clo = clo.cwiseMin(e.start_m).cwiseMin(e.end_m);
        chi = chi.cwiseMax(e.start_m).cwiseMax(e.end_m);
      }
      cluster.centre_m = 0.5 * (clo + chi);
      cluster.radius_m = 0.5 * (chi - clo).norm();
      out->object_clusters_[o].push_back(cluster);
    }
  }
  // Each object's edges as arrays.
  out->object_edge_arrays_.resize(out->object_edges_.size());
  for (std::size_t o = 0; o < out->object_edges_.size(); ++o) {
    EdgeArrays& arrays = out->object_edge_arrays_[o];
    for (const std::size_t e : out->object_edges_[o]) {
      const DiffractionEdge& edge = out->edges_[e];
      arrays.sx.push_back(edge.start_m.x());
      arrays.sy.push_back(edge.start_m.y());
      arrays.sz.push_back(edge.start_m.z());
      arrays.ax.push_back(edge.axis.x());
      arrays.ay.push_back(edge.axis.y());
      arrays.az.push_back(edge.axis.z());
      arrays.length.push_back(edge.length_m);
    }
  }
  // Each object's clusters as arrays.
  out->object_cluster_arrays_.resize(out->object_clusters_.size());
  for (std::size_t o = 0; o < out->object_clusters_.size(); ++o) {
    SphereArrays& arrays = out->object_cluster_arrays_[o];
    for (const EdgeCluster& cluster : out->object_clusters_[o]) {
      arrays.cx.push_back(cluster.centre_m.x());
      arrays.cy.push_back(cluster.centre_m.y());
      arrays.cz.push_back(cluster.centre_m.z());
      arrays.radius.push_back(cluster.radius_m);
    }
  }
  // The spheres around each object's clusters and groups of them.
  const auto bounding = [](auto begin, auto end) {
    Sphere sphere;
    for (auto it = begin; it != end; ++it) sphere.centre_m += it->centre_m;
    sphere.centre_m /= static_cast<double>(std::max<std::ptrdiff_t>(end - begin, 1));
    for (auto it = begin; it != end; ++it) {
      sphere.radius_m = std::max(sphere.radius_m, (it->centre_m - sphere.centre_m).norm() + it->radius_m);
    }
    sphere.radius_m = sphere.radius_m * (1.0 + 1e-9) + 1e-9;
    return sphere;
  };
  out->object_spheres_.resize(out->object_clusters_.size());
  out->group_spheres_.resize(out->object_clusters_.size());
  for (std::size_t o = 0; o < out->object_clusters_.size(); ++o) {
    const auto& clusters = out->object_clusters_[o];
    out->object_spheres_[o] = bounding(clusters.begin(), clusters.end());
    for (std::size_t g = 0; g < clusters.size(); g += kClustersPerGroup) {
      const auto first = clusters.begin() + static_cast<std::ptrdiff_t>(g);
      out->group_spheres_[o].push_back(bounding(first, first + static_cast<std::ptrdiff_t>(std::min(kClustersPerGroup, clusters.size() - g))));
    }
  }

  // Grid over x, y of the facets.
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (const Facet& f : out->facets_) {
    lo = lo.cwiseMin(f.min_m.head<2>());
    hi = hi.cwiseMax(f.max_m.head<2>());
  }
  if (out->facets_.empty()) return out;
  const Eigen::Vector2d span = hi - lo;
  out->cell_m_ = std::max({20.0, span.x() / 1000.0, span.y() / 1000.0});
  out->grid_min_ = lo;
  out->grid_nx_ = static_cast<int>(std::floor(span.x() / out->cell_m_)) + 1;
  out->grid_ny_ = static_cast<int>(std::floor(span.y() / out->cell_m_)) + 1;
  const auto cells = static_cast<std::size_t>(out->grid_nx_) * static_cast<std::size_t>(out->grid_ny_);
  out->facet_cells_.resize(cells);
  auto insert = [&](std::vector<std::vector<std::size_t>>& grid, std::size_t index, const Eigen::Vector2d& a,
                    const Eigen::Vector2d& b) {
    const int x0 = static_cast<int>((a.x() - lo.x()) / out->cell_m_), x1 = static_cast<int>((b.x() - lo.x()) / out->cell_m_);
    const int y0 = static_cast<int>((a.y() - lo.y()) / out->cell_m_), y1 = static_cast<int>((b.y() - lo.y()) / out->cell_m_);
    for (int x = std::max(0, x0); x <= std::min(out->grid_nx_ - 1, x1); ++x) {
      for (int y = std::max(0, y0); y <= std::min(out->grid_ny_ - 1, y1); ++y) {
        grid[static_cast<std::size_t>(y) * static_cast<std::size_t>(out->grid_nx_) + static_cast<std::size_t>(x)].push_back(index);
      }
    }
  };
  for (std::size_t i = 0; i < out->facets_.size(); ++i) {
    insert(out->facet_cells_, i, out->facets_[i].min_m.head<2>(), out->facets_[i].max_m.head<2>());
  }
  return out;
}

std::vector<RayOutcome> PropagationScene::trace_line_of_sight(const Eigen::Vector3d& origin_m,
                                                              const std::vector<Eigen::Vector3d>& directions) const {
  return scene_->trace_line_of_sight(origin_m, directions);
}

std::vector<RayOutcome> PropagationScene::trace_line_of_sight_from(const std::vector<Eigen::Vector3d>& origins_m,
                                                                   const Eigen::Vector3d& direction) const {
  return scene_->trace_line_of_sight_from(origins_m, direction);
}

std::vector<RayOutcome> PropagationScene::trace(const Eigen::Vector3d& origin_m,
                                                const std::vector<Eigen::Vector3d>& directions) const {
  return scene_->trace(origin_m, directions);
}

std::shared_ptr<const PropagationScene::Candidates> PropagationScene::candidates(const Eigen::Vector3d& origin_m,
                                                                                const PathSearchSettings& settings) const {
  const bool scattering = settings.scattering_coefficient > 0.0;
  const double scattering_radius_m = scattering ? settings.scattering_radius_m : 0.0;
  const double scattering_patch_m = scattering ? settings.scattering_patch_m : 0.0;
  {
    const std::lock_guard lock(cache_mutex_);
    auto cached = candidate_sets_.find([&](const Candidates& c) {
      return (c.origin_m - origin_m).norm() <= kCandidateMargin_m && c.radius_m == settings.radius_m &&
             c.min_area_m2 == settings.min_facet_area_m2 && c.frequency_hz == settings.frequency_hz &&
             c.scattering_radius_m == scattering_radius_m && c.scattering_patch_m == scattering_patch_m;
    });
    if (cached) return cached;
  }
  // The sets kept so far with this patch size: their patches are reused (a facet's patches depend
  // on the facet and the patch size alone). Every set lists its facets in ascending order, as the
  // new one will, so one cursor per set finds a facet's patches as the new set's facets go by.
  std::vector<std::shared_ptr<const Candidates>> kept;
  if (scattering) {
    const std::lock_guard lock(cache_mutex_);
    for (const auto& set : candidate_sets_.kept) {
      if (set && set->scattering_patch_m == scattering_patch_m) kept.push_back(set);
    }
  }
  std::vector<std::size_t> kept_cursor(kept.size(), 0);
  const auto made_patches = [&](std::size_t facet) -> std::shared_ptr<const std::vector<FacetPatch>> {
    for (std::size_t j = 0; j < kept.size(); ++j) {
      const Candidates& set = *kept[j];
      std::size_t& at = kept_cursor[j];
      while (at < set.facets.size() && set.facets[at].index < facet) ++at;
      if (at < set.facets.size() && set.facets[at].index == facet && set.patches[at]) return set.patches[at];
    }
    return nullptr;
  };
  auto c = std::make_shared<Candidates>();
  c->origin_m = origin_m;
  c->radius_m = settings.radius_m;
  c->min_area_m2 = settings.min_facet_area_m2;
  c->frequency_hz = settings.frequency_hz;
  c->scattering_radius_m = scattering_radius_m;
  c->scattering_patch_m = scattering_patch_m;
  if (grid_nx_ > 0) {
    const double r = settings.radius_m + kCandidateMargin_m;
    const int x0 = std::max(0, static_cast<int>(std::floor((origin_m.x() - r - grid_min_.x()) / cell_m_)));
    const int x1 = std::min(grid_nx_ - 1, static_cast<int>(std::floor((origin_m.x() + r - grid_min_.x()) / cell_m_)));
    const int y0 = std::max(0, static_cast<int>(std::floor((origin_m.y() - r - grid_min_.y()) / cell_m_)));
    const int y1 = std::min(grid_ny_ - 1, static_cast<int>(std::floor((origin_m.y() + r - grid_min_.y()) / cell_m_)));
    // The facets of those cells, each once, in ascending order: a facet spans several cells, and
    // marking bits then reading them in order is cheaper than sorting the cells' lists.
    std::vector<std::uint64_t> marked((facets_.size() + 63) / 64, 0);
    for (int x = x0; x <= x1; ++x) {
      for (int y = y0; y <= y1; ++y) {
        const auto cell = static_cast<std::size_t>(y) * static_cast<std::size_t>(grid_nx_) + static_cast<std::size_t>(x);
        for (const std::size_t i : facet_cells_[cell]) marked[i / 64] |= std::uint64_t{1} << (i % 64);
      }
    }
    std::vector<std::size_t> found;
    for (std::size_t word = 0; word < marked.size(); ++word) {
      for (std::uint64_t bits = marked[word]; bits != 0; bits &= bits - 1) {
        found.push_back(word * 64 + static_cast<std::size_t>(std::countr_zero(bits)));
      }
    }
    std::vector<std::complex<double>> eta_of(static_cast<std::size_t>(MaterialClass::kUnknown) + 1);
    for (std::size_t m = 0; m < eta_of.size(); ++m) {
      eta_of[m] = complex_permittivity(static_cast<MaterialClass>(m), settings.frequency_hz);
    }
    for (const std::size_t i : found) {
      // The facet's box within the radius, large enough to reflect coherently.
      const Facet& f = facets_[i];
      const Eigen::Vector3d nearest = origin_m.cwiseMax(f.min_m).cwiseMin(f.max_m);
      if (f.area_m2 < settings.min_facet_area_m2 || (nearest - origin_m).norm() > r) continue;
      c->facets.push_back(NearFacet{i, f.normal, 0.0, eta_of[static_cast<std::size_t>(f.material)], nullptr});
    }
  }
  // The scattering patches: a grid over the facet's plane, at most kMaxPatchesPerFacet cells of
  // about scattering_patch_m, those whose centre lies on the facet.
  c->patches.resize(c->facets.size());
  for (std::size_t k = 0; scattering && k < c->facets.size(); ++k) {
    const Facet& f = facets_[c->facets[k].index];
    if ((origin_m.cwiseMax(f.min_m).cwiseMin(f.max_m) - origin_m).norm() > scattering_radius_m + kCandidateMargin_m) continue;
    if (auto made = made_patches(c->facets[k].index)) {
      c->patches[k] = std::move(made);
      continue;
    }
    auto patches = std::make_shared<std::vector<FacetPatch>>();
    const Eigen::Vector2d span = f.max_uv - f.min_uv;
    const double step = std::max(scattering_patch_m,
                                 std::sqrt(std::max(span.x() * span.y(), 1e-6) / static_cast<double>(kMaxPatchesPerFacet)));
    const int nu = std::max(1, static_cast<int>(std::ceil(span.x() / step)));
    const int nv = std::max(1, static_cast<int>(std::ceil(span.y() / step)));
    const double du = span.x() / nu, dv = span.y() / nv;
    // Facet::contains for every point of the grid, trying for each row only the triangles whose
    // v range, widened by far more than the test's slack and rounding, reaches the row: the
    // others cannot hold its points (a ground facet has hundreds of triangles).
    std::vector<std::vector<std::size_t>> row_triangles(static_cast<std::size_t>(nv));
    const double reach_m = 1e-6 * (1.0 + span.norm() + f.min_uv.cwiseAbs().maxCoeff() + f.max_uv.cwiseAbs().maxCoeff());
    for (std::size_t i = 0; i + 2 < f.triangles_uv.size(); i += 3) {
      const double low = std::min({f.triangles_uv[i].y(), f.triangles_uv[i + 1].y(), f.triangles_uv[i + 2].y()}) - reach_m;
      const double high = std::max({f.triangles_uv[i].y(), f.triangles_uv[i + 1].y(), f.triangles_uv[i + 2].y()}) + reach_m;
      for (int b = 0; b < nv; ++b) {
        const double v = f.min_uv.y() + (b + 0.5) * dv;
        if (v >= low && v <= high) row_triangles[static_cast<std::size_t>(b)].push_back(i);
      }
    }
    for (int a = 0; a < nu; ++a) {
      for (int b = 0; b < nv; ++b) {
        const Eigen::Vector2d uv = f.min_uv + Eigen::Vector2d((a + 0.5) * du, (b + 0.5) * dv);
        const Eigen::Vector3d point = f.origin_m + uv.x() * f.axis_u + uv.y() * f.axis_v;
        const Eigen::Vector2d p = plane_coordinates(f, point);
        if (!within_box(f, p)) continue;
        const auto& near = row_triangles[static_cast<std::size_t>(b)];
        if (std::any_of(near.begin(), near.end(), [&](std::size_t i) { return within_triangle(f, p, i); })) {
          patches->push_back(FacetPatch{point, du * dv});
        }
      }
    }
    c->patches[k] = std::move(patches);
  }
  for (std::size_t k = 0; k < c->facets.size(); ++k) c->facets[k].patches = c->patches[k].get();
  const std::lock_guard lock(cache_mutex_);
  candidate_sets_.keep(c);
  return c;
}

std::shared_ptr<const PropagationScene::PatchSight> PropagationScene::patch_sight(const Eigen::Vector3d& r,
                                                                                  const Candidates& candidates,
                                                                                  const std::vector<NearFacet>& near_facets,
                                                                                  double radius_m) const {
  {
    const std::lock_guard lock(cache_mutex_);
    auto cached = patch_sights_.find([&](const PatchSight& sight) {
      return sight.origin_m == r && sight.candidates == &candidates && sight.radius_m == radius_m &&
             sight.in_view_first.size() == near_facets.size() + 1;
    });
    if (cached) return cached;
    // A moving antenna never comes back to the very same point: keep the view of a point met before.
    if (!patch_sights_.met_before(r)) return nullptr;
  }
  auto sight = std::make_shared<PatchSight>();
  sight->origin_m = r;
  sight->candidates = &candidates;
  sight->radius_m = radius_m;
  std::vector<Eigen::Vector3d> towards;
  std::vector<double> distance_m;
  std::vector<std::size_t> facet_of;
  std::vector<std::uint32_t> patch_of;
  for (std::size_t k = 0; k < near_facets.size(); ++k) {
    const NearFacet& nf = near_facets[k];
    if (nf.patches == nullptr) continue;
    for (std::size_t p_index = 0; p_index < nf.patches->size(); ++p_index) {
      // The same filters and ray as add_scattered_paths.
      const Eigen::Vector3d to_point = (*nf.patches)[p_index].point_m - r;
      const double d = to_point.norm();
      if (d < 0.5 || d > radius_m || -nf.normal.dot(to_point) / d <= 1e-3) continue;
      towards.push_back(to_point / d);
      distance_m.push_back(d);
      facet_of.push_back(k);
      patch_of.push_back(static_cast<std::uint32_t>(p_index));
    }
  }
  // The rays go facet by facet: the patches in view of each are a run of them.
  const std::vector<RayOutcome> seen = scene_->trace(r, towards);
  sight->in_view_first.assign(near_facets.size() + 1, 0);
  for (std::size_t k = 0; k < seen.size(); ++k) {
    const RayOutcome& o = seen[k];
    if (o.blocked && o.blocking_distance_m < distance_m[k] - leg_tolerance_m(distance_m[k])) continue;
    sight->in_view.push_back(patch_of[k]);
    sight->in_view_vegetation_db.push_back(o.vegetation_attenuation_db);
    ++sight->in_view_first[facet_of[k] + 1];
  }
  for (std::size_t k = 0; k < near_facets.size(); ++k) sight->in_view_first[k + 1] += sight->in_view_first[k];
  const std::lock_guard lock(cache_mutex_);
  patch_sights_.keep(sight);
  return sight;
}

void PropagationScene::add_scattered_paths(const Eigen::Vector3d& r, const std::vector<Eigen::Vector3d>& directions,
                                           const PathSearchSettings& settings, const Candidates& candidates,
                                           const std::vector<NearFacet>& near_facets, std::vector<PathSet>& out) const {
  // Effective-roughness model, Lambertian (Degli-Esposti et al., IEEE Trans. Antennas Propag. 55(1),
  // 2007): a patch of area dA lit at incidence theta_i re-radiates S^2 |Gamma|^2 of the power it
  // intercepts with a cos(theta_s) pattern, so that at distance d its power relative to the
  // incident plane wave is S^2 |Gamma|^2 dA cos(theta_i) cos(theta_s) / (pi d^2). The patches of
  // one facade add in power (their phases are random); the path takes their power-weighted delay,
  // direction and point, and half its power in each circular hand (scattering depolarises).
  std::vector<std::size_t> blocked;
  for (std::size_t i = 0; i < directions.size(); ++i) {
    if (out[i].direct.blocked) blocked.push_back(i);
  }
  if (blocked.empty()) return;
  const double s2 = settings.scattering_coefficient * settings.scattering_coefficient;
  const double min_power = std::pow(10.0, settings.min_relative_power_db / 10.0);
  const int lobe_exponent = settings.scattering_lobe_exponent;
  const std::array<double, 91>* lobe = lobe_exponent > 0 ? &directive_lobe_integrals(lobe_exponent) : nullptr;
  // What depends on the facet and the satellite only (a plane wave lights every patch of a facet
  // alike): S^2 |Gamma|^2 cos(theta_i), and the directive lobe's normalisation; 0 when unlit.
  struct Lighting {
    double factor = 0.0, lobe_integral = 1.0;
  };
  const std::size_t n_blocked = blocked.size();
  // Worked out for the facets within the scattering radius only (the others have no patch to use),
  // and only where the facet's patches can matter (patches_can_matter below): elsewhere the factor
  // stays 0, which drops what the sums would drop. Whether they can is judged first with bounds
  // (|Gamma|^2 <= 1 for a passive surface, the lobe's smallest normalisation), before the Fresnel
  // coefficients and the incidence angle are worked out.
  std::vector<Lighting> lighting(n_blocked * near_facets.size());  // [satellite][facet]
  const double least_lobe_integral = lobe != nullptr ? *std::min_element(lobe->begin(), lobe->end()) : 1.0;
  constexpr double kBoundMargin = 1.0 + 1e-9;
  // Whether the facet's patches can matter to a satellite lighting it with `light`: each patch brings
  // at most `patch_bound` times the lighting factor over the lobe's normalisation (a hair high).
  const auto patches_can_matter = [&](const Lighting& light, double patch_bound, std::size_t n_patches) {
    const double bound = kBoundMargin * light.factor * patch_bound / (lobe != nullptr ? light.lobe_integral : 1.0);
    return bound * static_cast<double>(kMaxPatchesPerFacet) >= min_power &&
           bound * static_cast<double>(n_patches) * kBoundMargin >= min_power;
  };
  const auto light_facet = [&](std::size_t k, double patch_bound) {
    const NearFacet& nf = near_facets[k];
    for (std::size_t j = 0; j < n_blocked; ++j) {
      const double cos_incidence = nf.normal.dot(directions[blocked[j]]);
      if (cos_incidence <= 1e-3) continue;  // the satellite lights the other side
      const Lighting brightest{kBoundMargin * s2 * cos_incidence, least_lobe_integral};
      if (!patches_can_matter(brightest, patch_bound, nf.patches->size())) continue;
      Lighting& light = lighting[j * near_facets.size() + k];
      const FresnelCoefficients gamma = fresnel_coefficients(nf.eta, cos_incidence);
      light.factor = s2 * 0.5 * (std::norm(gamma.te) + std::norm(gamma.tm)) * cos_incidence;
      if (lobe != nullptr) {
        const double incidence_deg = std::acos(std::clamp(cos_incidence, 0.0, 1.0)) * 180.0 / std::numbers::pi;
        light.lobe_integral = (*lobe)[static_cast<std::size_t>(std::lround(incidence_deg))];
      }
    }
  };
  struct Patch {
    std::size_t facet = 0;  // index in near_facets
    Eigen::Vector3d point_m;
    double area_m2 = 0.0, distance_m = 0.0, cos_receiver = 0.0, vegetation_db = 0.0;
  };
  // The patches within the radius on the receiver's side of each facet that could matter to a
  // blocked satellite that lights the facet: the power each would bring without vegetation and
  // lit everywhere, an upper bound of what the sums below give it (a hair high). A patch below
  // 1/kMaxPatchesPerFacet of the threshold for every such satellite is left out, as the sums leave
  // it out; a facet whose patches cannot add up to the threshold for any satellite is left out
  // whole, as no path can come of it: the receiver traces no ray to it.
  // A static antenna's view of the patches is kept (traced once): the visible ones go straight on.
  const std::shared_ptr<const PatchSight> sight = patch_sight(r, candidates, near_facets, settings.scattering_radius_m);
  std::vector<Patch> patches, visible;
  std::vector<Eigen::Vector3d> towards;
  std::vector<std::size_t> lit_by;              // blocked satellites lighting the facet (j)
  std::vector<Eigen::Vector3d> specular_of;     // their specular directions off it
  std::vector<double> facet_bound;              // their summed patch bounds
  for (std::size_t k = 0; k < near_facets.size(); ++k) {
    const NearFacet& nf = near_facets[k];
    // A static antenna sees no patch of most facets (the patches out of view add nothing to the
    // bounds below either: what they bound stays an upper bound of what the sums give).
    if (sight && sight->in_view_first[k] == sight->in_view_first[k + 1]) continue;
    const Facet& f = facets_[nf.index];
    const double nearest_m = (r.cwiseMax(f.min_m).cwiseMin(f.max_m) - r).norm();
    if (nf.patches == nullptr || nf.patches->empty() || nearest_m > settings.scattering_radius_m) continue;
    // No patch is nearer than the facet's box nor brighter than the lobe's peak (every patch of a
    // facet has the same area, candidates()): a facet none of whose patches can matter, or whose
    // patches together cannot reach the threshold, is passed over before its patches are.
    const double patch_bound = kBoundMargin * (*nf.patches).front().area_m2 * (lobe != nullptr ? 1.0 : 1.0 / std::numbers::pi) /
                               std::pow(std::max(nearest_m, 0.5) * (1.0 - 1e-9), 2);
    light_facet(k, patch_bound);
    lit_by.clear();
    specular_of.clear();
    for (std::size_t j = 0; j < n_blocked; ++j) {
      const Lighting& light = lighting[j * near_facets.size() + k];
      if (light.factor <= 0.0 || !patches_can_matter(light, patch_bound, nf.patches->size())) continue;
      const Eigen::Vector3d& s = directions[blocked[j]];
      lit_by.push_back(j);
      specular_of.push_back(-s + 2.0 * nf.normal.dot(s) * nf.normal);
    }
    if (lit_by.empty()) continue;
    facet_bound.assign(lit_by.size(), 0.0);
    const std::size_t first_patch = patches.size(), first_visible = visible.size();
    const std::size_t n_considered = sight ? sight->in_view_first[k + 1] - sight->in_view_first[k] : nf.patches->size();
    for (std::size_t c = 0; c < n_considered; ++c) {
      const std::size_t in_view = sight ? sight->in_view_first[k] + c : 0;
      const std::size_t p_index = sight ? sight->in_view[in_view] : c;
      const FacetPatch& facet_patch = (*nf.patches)[p_index];
      const Eigen::Vector3d to_point = facet_patch.point_m - r;
      const double d = to_point.norm();
      if (d < 0.5 || d > settings.scattering_radius_m) continue;
      const double cos_receiver = -nf.normal.dot(to_point) / d;
      if (cos_receiver <= 1e-3) continue;
      bool matters = false;
      for (std::size_t m = 0; m < lit_by.size(); ++m) {
        const Lighting& light = lighting[lit_by[m] * near_facets.size() + k];
        const double pattern =
            lobe != nullptr
                ? lobe_power(0.5 * (1.0 - specular_of[m].dot(to_point) / d), lobe_exponent) / light.lobe_integral
                : cos_receiver / std::numbers::pi;
        const double bound = kBoundMargin * light.factor * facet_patch.area_m2 * pattern / (d * d);
        if (bound * static_cast<double>(kMaxPatchesPerFacet) < min_power) continue;  // cannot matter
        facet_bound[m] += bound;
        matters = true;
      }
      if (!matters) continue;
      if (sight) {
        visible.push_back(Patch{k, facet_patch.point_m, facet_patch.area_m2, d, cos_receiver, sight->in_view_vegetation_db[in_view]});
        continue;
      }
      patches.push_back(Patch{k, facet_patch.point_m, facet_patch.area_m2, d, cos_receiver, 0.0});
      towards.push_back(to_point / d);
    }
    if (*std::max_element(facet_bound.begin(), facet_bound.end()) * kBoundMargin < min_power) {
      patches.resize(first_patch);
      towards.resize(first_patch);
      visible.resize(first_visible);
    }
  }
  if (patches.empty() && visible.empty()) return;
  // Which patches the receiver sees: one batch from it.
  const std::vector<RayOutcome> seen = patches.empty() ? std::vector<RayOutcome>{} : scene_->trace(r, towards);
  for (std::size_t k = 0; k < patches.size(); ++k) {
    const RayOutcome& o = seen[k];
    if (o.blocked && o.blocking_distance_m < patches[k].distance_m - leg_tolerance_m(patches[k].distance_m)) continue;
    patches[k].vegetation_db = o.vegetation_attenuation_db;
    visible.push_back(patches[k]);
  }
  struct Sum {
    double power = 0.0, excess = 0.0;
    Eigen::Vector3d point = Eigen::Vector3d::Zero(), arrival = Eigen::Vector3d::Zero();
  };
  std::vector<Sum> sums(near_facets.size());
  std::vector<std::size_t> tested;           // the visible patches whose lit test is traced
  std::vector<Eigen::Vector3d> lit_from;     // the points those tests start from
  // Per satellite: each visible patch's power before its lit test (negative: it cannot matter), and
  // per facet the sum of those powers through the vegetation towards the receiver, an upper bound
  // of the facet's path power: a facet that cannot reach the threshold traces no lit test.
  std::vector<double> unlit_power(visible.size());
  std::vector<double> facet_potential(near_facets.size());
  for (std::size_t j = 0; j < n_blocked; ++j) {
    const std::size_t i = blocked[j];
    const Eigen::Vector3d& s = directions[i];
    std::fill(sums.begin(), sums.end(), Sum{});
    std::fill(facet_potential.begin(), facet_potential.end(), 0.0);
    for (std::size_t v = 0; v < visible.size(); ++v) {
      const Patch& patch = visible[v];
      unlit_power[v] = -1.0;
      const NearFacet& nf = near_facets[patch.facet];
      const Lighting& light = lighting[j * near_facets.size() + patch.facet];
      if (light.factor <= 0.0) continue;
      // The scattering pattern towards the receiver over its integral on the hemisphere.
      double pattern = patch.cos_receiver / std::numbers::pi;
      if (lobe != nullptr) {
        const Eigen::Vector3d specular = -s + 2.0 * nf.normal.dot(s) * nf.normal;
        const Eigen::Vector3d to_receiver = (r - patch.point_m) / patch.distance_m;
        pattern = lobe_power(0.5 * (1.0 + specular.dot(to_receiver)), lobe_exponent) / light.lobe_integral;
      }
      const double power = light.factor * patch.area_m2 * pattern / (patch.distance_m * patch.distance_m);
      if (power * static_cast<double>(kMaxPatchesPerFacet) < min_power) continue;  // cannot matter
      unlit_power[v] = power;
      facet_potential[patch.facet] += power * power_factor(patch.vegetation_db);
    }
    // Lit or not: the occlusion test alone (free rays carry the vegetation they cross), of all the
    // patches that may matter at once, summed in patch order.
    tested.clear();
    lit_from.clear();
    for (std::size_t v = 0; v < visible.size(); ++v) {
      const Patch& patch = visible[v];
      if (unlit_power[v] < 0.0 || facet_potential[patch.facet] * kBoundMargin < min_power) continue;
      tested.push_back(v);
      lit_from.push_back(patch.point_m + kSurfaceOffset_m * near_facets[patch.facet].normal);
    }
    const std::vector<RayOutcome> lit_tests =
        tested.empty() ? std::vector<RayOutcome>{} : scene_->trace_line_of_sight_from(lit_from, s);
    for (std::size_t t = 0; t < tested.size(); ++t) {
      const std::size_t v = tested[t];
      const Patch& patch = visible[v];
      double power = unlit_power[v];
      const RayOutcome& lit = lit_tests[t];
      if (lit.blocked) continue;
      power *= power_factor(patch.vegetation_db + lit.vegetation_attenuation_db);
      Sum& sum = sums[patch.facet];
      const Eigen::Vector3d to_point = patch.point_m - r;
      sum.power += power;
      sum.excess += power * (patch.distance_m - s.dot(to_point));
      sum.point += power * patch.point_m;
      sum.arrival += power * to_point / patch.distance_m;
    }
    for (std::size_t k = 0; k < sums.size(); ++k) {
      const Sum& sum = sums[k];
      if (sum.power < min_power) continue;
      const Facet& f = facets_[near_facets[k].index];
      SignalPath p;
      p.type = PathType::kScattered;
      p.excess_delay_m = std::max(sum.excess / sum.power, 0.0);
      p.rhcp_amplitude = std::sqrt(0.5 * sum.power);
      p.lhcp_amplitude = std::sqrt(0.5 * sum.power);
      p.point_m = sum.point / sum.power;
      p.arrival_direction = sum.arrival.normalized();
      p.material = f.material;
      p.object = object_names_[f.object];
      // As for a point scatterer at the centroid: excess = |p - r| - s . (p - r).
      p.delay_gradient_origin = s - p.arrival_direction;
      p.delay_gradient_direction = -(p.point_m - r);
      out[i].paths.push_back(std::move(p));
    }
  }
}

// Lists per sky cell, each made when a direction first needs its cell and kept; beyond max_entries
// entries in all cells they start afresh (the satellites have moved on from most of the cells they
// hold). Thread-safe; a list is never changed once made.
template <class List>
class CellLists {
 public:
  CellLists(std::size_t cells, std::size_t max_entries) : cells_(cells), max_entries_(max_entries) {}
  template <class Make>
  std::shared_ptr<const List> get(int cell, Make&& make) const {
    const std::lock_guard lock(mutex_);
    if (lists_.empty()) lists_.resize(cells_);
    auto& list = lists_[static_cast<std::size_t>(cell)];
    if (list) return list;
    if (entries_ >= max_entries_) {
      for (auto& other : lists_) other.reset();
      entries_ = 0;
    }
    auto made = std::make_shared<const List>(make());
    entries_ += made->size();
    list = std::move(made);
    return list;
  }

 private:
  std::size_t cells_, max_entries_;
  mutable std::mutex mutex_;
  mutable std::vector<std::shared_ptr<const List>> lists_;
  mutable std::size_t entries_ = 0;
};

// What a bounce needs first fills the first cache line (the pair is two lines, aligned): a pair
// whose cones a satellite's screen has settled is tested without loading its cones.
struct alignas(64) PropagationScene::FacetPair {
  std::uint32_t a = 0, b = 0;  // indices into the second-order facets
  double hb = 0.0;             // the first image's height above B
  Eigen::Vector3d nb = Eigen::Vector3d::Zero();        // B's normal on the side of the first image
  Eigen::Vector3d image_ab = Eigen::Vector3d::Zero();  // the first image mirrored in B
  // The point on B lies on the ray from image_ab towards the satellite and within B's bounding
  // sphere: only satellites within this cone around the sphere's direction can use the pair.
  Eigen::Vector3d cone_axis = Eigen::Vector3d::Zero();
  double cone_cos = -2.0;  // -2: no cone (image_ab within the sphere)
  // Likewise the point on A lies on the ray from the first image along the satellite's direction
  // mirrored in B, and within A's bounding sphere: a second cone, mirrored back.
  Eigen::Vector3d mirrored_cone_axis = Eigen::Vector3d::Zero();
  double mirrored_cone_cos = -2.0;

  // Whether satellite direction s lies in both cones.
  [[nodiscard]] bool may_carry(const Eigen::Vector3d& s) const {
    return (cone_cos <= -2.0 || cone_axis.dot(s) >= cone_cos) &&
           (mirrored_cone_cos <= -2.0 || mirrored_cone_axis.dot(s) >= mirrored_cone_cos);
  }
  // The narrower cone, or none.
  [[nodiscard]] std::pair<const Eigen::Vector3d*, double> narrower_cone() const {
    if (cone_cos <= -2.0 && mirrored_cone_cos <= -2.0) return {nullptr, -2.0};
    return cone_cos >= mirrored_cone_cos ? std::pair{&cone_axis, cone_cos} : std::pair{&mirrored_cone_axis, mirrored_cone_cos};
  }
};

// The pairs of one antenna position by the sky cells (6 deg in elevation and azimuth) their cones
// overlap, so that a satellite tries only the pairs whose cone may hold it.
struct PropagationScene::DoubleBounceIndex {
  static_assert(sizeof(FacetPair) == 128 && offsetof(FacetPair, cone_axis) == 64);
  static constexpr int kRows = 30, kColumns = 60;
  static constexpr double kCell_rad = std::numbers::pi / kRows;
  static constexpr double kMargin_rad = 1e-6;  // cells a hair wider than the cones need

  // Beyond these the index is not kept (memory grows as the square of the facets): the antenna
  // searches every pair at each epoch as a moving one does.
  static constexpr std::size_t kMaxPairs = 400'000, kMaxEntries = 16'000'000;

  Eigen::Vector3d origin_m = Eigen::Vector3d::Zero();
  bool too_large = false;           // the pairs were too many to keep: nothing else is kept
  std::vector<std::size_t> facets;  // the second-order facets the pairs index (scene indices)
  std::vector<FacetPair> pairs;     // A by A, then B, as append_facet_pairs makes them
  std::vector<std::uint32_t> cell_start, cell_pairs;  // pairs per cell, ascending
  std::vector<std::uint32_t> everywhere;              // pairs without a cone

  // The pairs a cell may hold, copied together with their cones in single precision (a little
  // wider than the exact ones, which are tested after) when a satellite first needs the cell: a
  // satellite then screens them in one pass over contiguous memory. Visiting each pair where the
  // index keeps it (anywhere in tens of megabytes) waited on memory far longer than the tests take.
  struct Screen {
    float axis_x, axis_y, axis_z, cos_wide;
    float mirrored_x, mirrored_y, mirrored_z, mirrored_cos_wide;
  };
  struct CellBlock {
    std::vector<Screen> screens;
    std::vector<FacetPair> pairs;  // ascending in the index's pair order (the everywhere pairs merged in)
    [[nodiscard]] std::size_t size() const { return pairs.size(); }
  };
  static constexpr float kNoCone = -3.0F;
  // Beyond this many pairs in all blocks (some 50 MB) they start afresh.
  static constexpr std::size_t kMaxBlockPairs = 250'000;
  CellLists<CellBlock> blocks{static_cast<std::size_t>(kRows * kColumns), kMaxBlockPairs};

  static Screen screen_of(const FacetPair& pair) {
    const auto wide = [](double cos) { return cos <= -2.0 ? kNoCone : static_cast<float>(cos) - kSinglePrecisionSlack; };
    return {static_cast<float>(pair.cone_axis.x()),          static_cast<float>(pair.cone_axis.y()),
            static_cast<float>(pair.cone_axis.z()),          wide(pair.cone_cos),
            static_cast<float>(pair.mirrored_cone_axis.x()), static_cast<float>(pair.mirrored_cone_axis.y()),
            static_cast<float>(pair.mirrored_cone_axis.z()), wide(pair.mirrored_cone_cos)};
  }
  CellBlock block_of(int cell) const {
    CellBlock made;
    const std::uint32_t* it = cell_pairs.data() + cell_start[static_cast<std::size_t>(cell)];
    const std::uint32_t* end = cell_pairs.data() + cell_start[static_cast<std::size_t>(cell) + 1];
    auto other = everywhere.begin();
    made.pairs.reserve(static_cast<std::size_t>(end - it) + everywhere.size());
    while (it != end || other != everywhere.end()) {
      made.pairs.push_back(pairs[other == everywhere.end() || (it != end && *it < *other) ? *it++ : *other++]);
    }
    made.screens.reserve(made.pairs.size());
    for (const FacetPair& pair : made.pairs) made.screens.push_back(screen_of(pair));
    return made;
  }

  static int row_of(double elevation_rad) {
    return std::clamp(static_cast<int>(std::floor((elevation_rad + std::numbers::pi / 2.0) / kCell_rad)), 0, kRows - 1);
  }
  static int column_of(double azimuth_rad) {
    const int c = static_cast<int>(std::floor((azimuth_rad + std::numbers::pi) / kCell_rad));
    return ((c % kColumns) + kColumns) % kColumns;
  }
  // The cell of unit direction s.
  static int cell_of(const Eigen::Vector3d& s) {
    return row_of(std::asin(std::clamp(s.z(), -1.0, 1.0))) * kColumns + column_of(std::atan2(s.y(), s.x()));
  }
  // Every cell both cones of the pair may reach: the cells of the narrower one's bounding box
  // (rows and columns) whose centre lies within the half angles plus a cell's reach of both axes,
  // and that reach the side of B that the first image faces (the satellite must light it).
  template <class Visit>
  static void for_each_cell(const FacetPair& pair, Visit&& visit) {
    const auto [axis, cone_cos] = pair.narrower_cone();
    if (axis == nullptr) return;
    // No point of a cell is farther than one cell size from its centre.
    const auto reach = [](double cos_half) {
      return cos_half <= -2.0 ? -2.0 : std::cos(std::min(std::acos(std::clamp(cos_half, -1.0, 1.0)) + kCell_rad + kMargin_rad, std::numbers::pi));
    };
    const double reach1 = reach(pair.cone_cos), reach2 = reach(pair.mirrored_cone_cos);
    const double lit_reach = -std::sin(kCell_rad + kMargin_rad);
    const auto& centres = cell_centres();
    for_each_box_cell(*axis, cone_cos, [&](int cell) {
      const Eigen::Vector3d& centre = centres[static_cast<std::size_t>(cell)];
      if (pair.cone_axis.dot(centre) >= reach1 && pair.mirrored_cone_axis.dot(centre) >= reach2 && pair.nb.dot(centre) >= lit_reach) {
        visit(cell);
      }
    });
  }
  // The unit vector of every cell's centre (an index visits each cell for many pairs: worked out
  // once instead of with four trigonometric functions per visit).
  static const std::array<Eigen::Vector3d, static_cast<std::size_t>(kRows * kColumns)>& cell_centres() {
    static const auto centres = [] {
      std::array<Eigen::Vector3d, static_cast<std::size_t>(kRows * kColumns)> out;
      for (int cell = 0; cell < kRows * kColumns; ++cell) {
        const double elevation = (cell / kColumns + 0.5) * kCell_rad - std::numbers::pi / 2.0;
        const double azimuth = (cell % kColumns + 0.5) * kCell_rad - std::numbers::pi;
        out[static_cast<std::size_t>(cell)] =
            Eigen::Vector3d(std::cos(elevation) * std::cos(azimuth), std::cos(elevation) * std::sin(azimuth), std::sin(elevation));
      }
      return out;
    }();
    return centres;
  }
  // Every cell of the bounding box (rows and columns) of the cone (unit axis, cosine of the half angle).
  template <class Visit>
  static void for_each_box_cell(const Eigen::Vector3d& axis, double cone_cos, Visit&& visit) {
    const double half = std::acos(std::clamp(cone_cos, -1.0, 1.0)) + kMargin_rad;
    const double elevation = std::asin(std::clamp(axis.z(), -1.0, 1.0));
    const double azimuth = std::atan2(axis.y(), axis.x());
    const int row0 = row_of(elevation - half), row1 = row_of(elevation + half);
    // A cap that reaches no pole spans azimuths within asin(sin half / cos elevation) of its centre.
    const bool all_columns = elevation + half >= std::numbers::pi / 2.0 || elevation - half <= -std::numbers::pi / 2.0 ||
                             std::sin(half) >= std::cos(elevation);
    int column0 = 0, count = kColumns;
    if (!all_columns) {
      const double spread = std::asin(std::sin(half) / std::cos(elevation)) + kMargin_rad;
      column0 = static_cast<int>(std::floor((azimuth - spread + std::numbers::pi) / kCell_rad));
      count = std::min(kColumns, static_cast<int>(std::floor((azimuth + spread + std::numbers::pi) / kCell_rad)) - column0 + 1);
    }
    for (int row = row0; row <= row1; ++row) {
      for (int k = 0; k < count; ++k) visit(row * kColumns + (((column0 + k) % kColumns) + kColumns) % kColumns);
    }
  }
  // The pairs whose two cones hold satellite direction s (FacetPair::may_carry), in ascending
  // order. The single-precision screen settles all but the pairs within a few times its slack of
  // a cone's edge, which take the exact test.
  template <class Visit>
  void for_each_candidate(const Eigen::Vector3d& s, Visit&& visit) const {
    const int cell = cell_of(s);
    const std::shared_ptr<const CellBlock> block = blocks.get(cell, [&] { return block_of(cell); });
    const float sx = static_cast<float>(s.x()), sy = static_cast<float>(s.y()), sz = static_cast<float>(s.z());
    constexpr float kSure = 3.0F * kSinglePrecisionSlack;
    for (std::size_t k = 0; k < block->pairs.size(); ++k) {
      const Screen& c = block->screens[k];
      const float to_axis = c.axis_x * sx + c.axis_y * sy + c.axis_z * sz;
      const float to_mirrored = c.mirrored_x * sx + c.mirrored_y * sy + c.mirrored_z * sz;
      if (to_axis < c.cos_wide || to_mirrored < c.mirrored_cos_wide) continue;
      const bool sure = to_axis >= c.cos_wide + kSure && to_mirrored >= c.mirrored_cos_wide + kSure;
      if (sure || block->pairs[k].may_carry(s)) visit(block->pairs[k]);
    }
  }
};

void PropagationScene::append_facet_pairs(std::size_t a_index, const std::vector<NearFacet>& facets,
                                          const std::vector<double>& plane_a, const std::vector<Eigen::Vector3d>& image_of,
                                          std::vector<FacetPair>& out) const {
  FacetPair pair;
  for (std::size_t b_index = 0; b_index < facets.size(); ++b_index) {
    if (make_facet_pair(a_index, b_index, facets, plane_a, image_of, pair)) out.push_back(pair);
  }
}

bool PropagationScene::make_facet_pair(std::size_t a_index, std::size_t b_index, const std::vector<NearFacet>& facets,
                                       const std::vector<double>& plane_a, const std::vector<Eigen::Vector3d>& image_of,
                                       FacetPair& pair) const {
  const NearFacet& a = facets[a_index];
  const Facet& fa = facets_[a.index];
  const Eigen::Vector3d& na = a.normal;
  const double ca = plane_a[a_index];
  const Eigen::Vector3d& image_a = image_of[a_index];
  const NearFacet& b = facets[b_index];
  if (b.index == a.index) return false;
  const Facet& fb = facets_[b.index];
  const double hb = fb.normal.dot(image_a) - fb.offset_m;
  if (std::abs(hb) < 1e-6) return false;
  // Necessary for any satellite (the point on B lies within B's bounding sphere, the point
  // on A within A's): B reaches A's receiver side, A reaches B's side of the first image.
  if (na.dot(fb.centre_m) + fb.radius_m <= ca) return false;
  const double side = hb >= 0.0 ? 1.0 : -1.0;
  if (side * (fb.normal.dot(fa.centre_m) - fb.offset_m) + fa.radius_m <= 0.0) return false;
  pair = FacetPair{};
  pair.a = static_cast<std::uint32_t>(a_index);
  pair.b = static_cast<std::uint32_t>(b_index);
  pair.hb = hb;
  pair.nb = hb >= 0.0 ? fb.normal : Eigen::Vector3d(-fb.normal);
  pair.image_ab = image_a - 2.0 * std::abs(hb) * pair.nb;
  const SphereCone to_b = sphere_cone(fb, pair.image_ab, 1e-9);  // a hair wide
  if (to_b.cos > -2.0) {
    pair.cone_axis = to_b.axis;
    pair.cone_cos = to_b.cos;
  }
  // Wider: the axis is reflected.
  const SphereCone to_a = sphere_cone(fa, image_a, kMirroredConeWider);
  if (to_a.cos > -2.0) {
    // Householder reflection in B's plane: the direction from the first image to A becomes a
    // satellite direction.
    pair.mirrored_cone_axis = to_a.axis - 2.0 * pair.nb.dot(to_a.axis) * pair.nb;
    pair.mirrored_cone_cos = to_a.cos;
  }
  return true;
}

void PropagationScene::narrow_cones(FacetPair& pair, const Eigen::Vector3d& image_a, const std::vector<NearFacet>& facets) const {
  // The cone from `apex` around a facet's bounding rectangle (in its plane): it holds every
  // point of the facet. Its cosine, or -2 when it opens 90 deg or more (no longer convex).
  const auto rectangle_cone = [](const Facet& f, const Eigen::Vector3d& apex, Eigen::Vector3d& axis) {
    std::array<Eigen::Vector3d, 4> towards;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (int k = 0; k < 4; ++k) {
      const double u = (k & 1) != 0 ? f.max_uv.x() : f.min_uv.x(), v = (k & 2) != 0 ? f.max_uv.y() : f.min_uv.y();
      const Eigen::Vector3d to_corner = f.origin_m + u * f.axis_u + v * f.axis_v - apex;
      const double distance_m = to_corner.norm();
      if (!(distance_m > 1e-9)) return -2.0;
      towards[static_cast<std::size_t>(k)] = to_corner / distance_m;
      sum += towards[static_cast<std::size_t>(k)];
    }
    if (!(sum.norm() > 1e-9)) return -2.0;
    axis = sum.normalized();
    double cos_half = 1.0;
    for (const Eigen::Vector3d& t : towards) cos_half = std::min(cos_half, axis.dot(t));
    return cos_half > 1e-3 ? cos_half : -2.0;
  };
  const Facet& fa = facets_[facets[pair.a].index];
  const Facet& fb = facets_[facets[pair.b].index];
  Eigen::Vector3d axis = Eigen::Vector3d::Zero();
  // The point on B seen from the first image mirrored in B, along the satellite's direction.
  if (const double c = rectangle_cone(fb, pair.image_ab, axis) - 1e-9; c > pair.cone_cos) {
    pair.cone_axis = axis;
    pair.cone_cos = c;
  }
  // The point on A seen from the first image, along the satellite's direction mirrored in B.
  if (const double c = rectangle_cone(fa, image_a, axis) - 1e-7; c > pair.mirrored_cone_cos) {
    pair.mirrored_cone_axis = axis - 2.0 * pair.nb.dot(axis) * pair.nb;
    pair.mirrored_cone_cos = c;
  }
}

namespace {

// Whether an antenna point's index was made for these facets: the same scene facets in the same
// order (`indexed` holds their scene indices).
template <class NearFacets>
bool indexes_facets(const std::vector<std::size_t>& indexed, const NearFacets& facets) {
  return indexed.size() == facets.size() &&
         std::equal(facets.begin(), facets.end(), indexed.begin(), [](const auto& f, std::size_t i) { return f.index == i; });
}

}  // namespace

std::shared_ptr<const PropagationScene::DoubleBounceIndex> PropagationScene::double_bounce_index(
    const Eigen::Vector3d& origin_m, const std::vector<NearFacet>& facets, const std::vector<double>& plane_a,
    const std::vector<Eigen::Vector3d>& image_of) const {
  {
    const std::lock_guard lock(cache_mutex_);
    auto cached = double_bounce_indexes_.find(
        [&](const DoubleBounceIndex& index) { return index.origin_m == origin_m && indexes_facets(index.facets, facets); });
    if (cached) return cached->too_large ? nullptr : cached;
    // A moving antenna never comes back to the very same point: index only a point met before.
    if (!double_bounce_indexes_.met_before(origin_m)) return nullptr;
  }
  auto index = std::make_shared<DoubleBounceIndex>();
  index->origin_m = origin_m;
  for (const NearFacet& f : facets) index->facets.push_back(f.index);
  for (std::size_t a = 0; a < facets.size() && index->pairs.size() <= DoubleBounceIndex::kMaxPairs; ++a) {
    append_facet_pairs(a, facets, plane_a, image_of, index->pairs);
  }
  // The index is built once and serves every epoch at the point: each pair's cones are narrowed
  // to the facets' rectangles where that is tighter than their spheres.
  if (index->pairs.size() <= DoubleBounceIndex::kMaxPairs) {
    for (FacetPair& pair : index->pairs) narrow_cones(pair, image_of[pair.a], facets);
  }
  constexpr std::size_t kCells = static_cast<std::size_t>(DoubleBounceIndex::kRows * DoubleBounceIndex::kColumns);
  index->cell_start.assign(kCells + 1, 0);
  if (index->pairs.size() <= DoubleBounceIndex::kMaxPairs) {
    for (const FacetPair& pair : index->pairs) {
      DoubleBounceIndex::for_each_cell(pair, [&](int cell) { ++index->cell_start[static_cast<std::size_t>(cell) + 1]; });
    }
    for (std::size_t c = 0; c < kCells; ++c) index->cell_start[c + 1] += index->cell_start[c];
  }
  if (index->pairs.size() > DoubleBounceIndex::kMaxPairs || index->cell_start[kCells] > DoubleBounceIndex::kMaxEntries) {
    auto marker = std::make_shared<DoubleBounceIndex>();
    marker->origin_m = origin_m;
    marker->facets = std::move(index->facets);
    marker->too_large = true;
    const std::lock_guard lock(cache_mutex_);
    double_bounce_indexes_.keep(marker);
    return nullptr;
  }
  index->cell_pairs.resize(index->cell_start[kCells]);
  std::vector<std::uint32_t> filled(index->cell_start.begin(), index->cell_start.end() - 1);
  for (std::size_t k = 0; k < index->pairs.size(); ++k) {
    if (index->pairs[k].narrower_cone().first != nullptr) {
      DoubleBounceIndex::for_each_cell(index->pairs[k], [&](int cell) {
        index->cell_pairs[filled[static_cast<std::size_t>(cell)]++] = static_cast<std::uint32_t>(k);
      });
    } else {
      index->everywhere.push_back(static_cast<std::uint32_t>(k));
    }
  }
  const std::lock_guard lock(cache_mutex_);
  double_bounce_indexes_.keep(index);
  return index;
}

// For diffraction over `edge` then reflection off facet nf (the receiver's image in its plane
// `image`, the plane normal . x = plane): the edge's direction and the band of satellite directions
// s (as s . axis, a little wide) whose stationary point on the edge seen from the image (Keller's
// cone, keller_point) lies above the plane and projects, along the line to the image, into the
// facet's bounding rectangle; none when no direction within cell_reach of cell_axis does.
// The point moves along the edge monotonically with s . axis, which makes the band exact.
std::optional<PropagationScene::FacetEdge> PropagationScene::facet_edge_band(const NearFacet& nf, const Facet& f, const Eigen::Vector3d& image,
                                                          double plane, const DiffractionEdge& edge,
                                                          const Eigen::Vector3d& cell_axis, const ConeReach& cell_reach) {
  const Eigen::Vector3d& axis = edge.axis;
  const double length = edge.length_m;
  if (!(length > 0.0)) return std::nullopt;
  // Where the edge lies above the plane: above(u) = above0 + u rate.
  const double above0 = nf.normal.dot(edge.start_m) - plane;
  const double rate = nf.normal.dot(axis);
  double ua = 0.0, ub = length;
  if (rate == 0.0) {
    if (above0 <= 0.0) return std::nullopt;
  } else if (rate > 0.0) {
    ua = std::max(ua, -above0 / rate);
  } else {
    ub = std::min(ub, -above0 / rate);
  }
  if (!(ua < ub)) return std::nullopt;
  // The projections of the two ends into the plane's (u, v), and their weights above + h.
  const auto project = [&](double u, double& weight) {
    const Eigen::Vector3d q = edge.start_m + u * axis;
    const double above = std::max(above0 + u * rate, 0.0);
    weight = above + nf.height_m;
    const Eigen::Vector3d p = q + above / weight * (image - q) - f.origin_m;
    return Eigen::Vector2d(p.dot(f.axis_u), p.dot(f.axis_v));
  };
  double weight_a = 0.0, weight_b = 0.0;
  const Eigen::Vector2d pa = project(ua, weight_a), pb = project(ub, weight_b);
  // The segment pa-pb clipped to the rectangle (Liang-Barsky), a micrometre wide.
  constexpr double kSlack_m = 1e-6;
  double t0 = 0.0, t1 = 1.0;
  const Eigen::Vector2d d = pb - pa;
  for (int c = 0; c < 2; ++c) {
    const double lo = f.min_uv[c] - kSlack_m - pa[c], hi = f.max_uv[c] + kSlack_m - pa[c];
    if (d[c] == 0.0) {
      if (lo > 0.0 || hi < 0.0) return std::nullopt;
      continue;
    }
    const double ta = lo / d[c], tb = hi / d[c];
    t0 = std::max(t0, std::min(ta, tb));
    t1 = std::min(t1, std::max(ta, tb));
  }
  if (t0 > t1) return std::nullopt;
  // Back to the edge: the projection is projective, t = lambda w_b / ((1 - lambda) w_a + lambda w_b).
  const auto u_at = [&](double t) { return ua + (ub - ua) * (t * weight_a / ((1.0 - t) * weight_b + t * weight_a)); };
  const double u0 = u_at(t0), u1 = u_at(t1);
  const Eigen::Vector3d w = edge.start_m - image;
  const double along = w.dot(axis);
  return band_of(axis, along, (w - along * axis).norm(), u0, u1, cell_axis, cell_reach);
}

std::optional<PropagationScene::FacetEdge> PropagationScene::band_of(const Eigen::Vector3d& axis, double along, double rho,
                                                                    double u0, double u1, const Eigen::Vector3d& cell_axis,
                                                                    const ConeReach& cell_reach) {
  // keller_point: u = c rho / sqrt(1 - c^2) - along, so c = (u + along) / sqrt((u + along)^2 + rho^2),
  // increasing with u.
  const auto cos_at = [&](double u) { return (u + along) / std::hypot(u + along, rho); };
  FacetEdge out;
  out.axis = axis;
  out.cos_min = std::min(cos_at(u0), cos_at(u1)) - 1e-9;
  out.cos_max = std::max(cos_at(u0), cos_at(u1)) + 1e-9;
  // The directions of the cell: s . axis within the cosines of the cell's angle to the axis
  // plus and minus its reach (by the angle-sum formulas; a screen, so a hair wide).
  const double c = std::clamp(cell_axis.dot(axis), -1.0, 1.0), sin_angle = std::sqrt(1.0 - c * c);
  const double cell_max = c >= cell_reach.cos ? 1.0 : c * cell_reach.cos + sin_angle * cell_reach.sin;
  const double cell_min = c <= -cell_reach.cos ? -1.0 : c * cell_reach.cos - sin_angle * cell_reach.sin;
  if (out.cos_max < cell_min - 1e-12 || out.cos_min > cell_max + 1e-12) return std::nullopt;
  return out;
}

// For knife-edge diffraction over `edge` from `origin`: the edge's direction and the band of
// satellite directions s (as s . axis, a little wide) whose stationary point (keller_point) lies
// on the edge within radius_m of the origin; none when no direction within cell_reach of
// cell_axis is in the band.
std::optional<PropagationScene::FacetEdge> PropagationScene::edge_band(const DiffractionEdge& edge, const Eigen::Vector3d& origin,
                                                                      double radius_m, const Eigen::Vector3d& cell_axis,
                                                                      const ConeReach& cell_reach) {
  const Eigen::Vector3d& axis = edge.axis;
  const double length = edge.length_m;
  if (!(length > 0.0)) return std::nullopt;
  const Eigen::Vector3d w = edge.start_m - origin;
  const double along = w.dot(axis);
  // |w + u axis| <= radius_m, a little wide.
  const double reach = radius_m * (1.0 + 1e-9) + 1e-6;
  const double discriminant = along * along - w.squaredNorm() + reach * reach;
  if (discriminant < 0.0) return std::nullopt;
  const double u0 = std::max(0.0, -along - std::sqrt(discriminant));
  const double u1 = std::min(length, -along + std::sqrt(discriminant));
  if (!(u0 <= u1)) return std::nullopt;
  return band_of(axis, along, (w - along * axis).norm(), u0, u1, cell_axis, cell_reach);
}

struct PropagationScene::ReflectorIndex {
  using Cells = DoubleBounceIndex;
  static constexpr std::size_t kCells = static_cast<std::size_t>(Cells::kRows * Cells::kColumns);
  // Beyond this many facets in all cells' lists (16 MB) they start afresh: the satellites have
  // moved on from most of the cells they hold.
  static constexpr std::size_t kMaxEntries = 4'000'000;

  Eigen::Vector3d origin_m = Eigen::Vector3d::Zero();
  std::vector<std::size_t> facets;  // the near facets (scene indices) it indexes
  // Per facet: its normal towards the antenna; the unit vector from the antenna's image to the
  // centre of its bounding sphere; and the cosine of the angle to that vector within which a
  // cell's centre must lie for a direction of the cell to meet the sphere from the image (the
  // sphere's half angle plus a cell's reach; -2: every cell, the image lies within the sphere).
  std::vector<Eigen::Vector3d> normal, axis;
  std::vector<double> reach_cos;
  using List = std::vector<std::uint32_t>;
  CellLists<List> cells{kCells, kMaxEntries};

  // The facets (indices into the near facets, ascending) on which the line from the antenna's
  // image towards direction s may meet the plane within the bounding sphere, and s light the
  // antenna's side: a superset of those where a first-order reflection of s can lie. The list
  // of s's cell is made when a direction first needs it.
  std::shared_ptr<const List> facets_towards(const Eigen::Vector3d& s) const {
    const int cell = Cells::cell_of(s);
    return cells.get(cell, [&] {
      // Every direction of the cell lies within one cell size of its centre.
      const Eigen::Vector3d& centre = Cells::cell_centres()[static_cast<std::size_t>(cell)];
      const double lit_reach = -std::sin(Cells::kCell_rad + Cells::kMargin_rad);
      List made;
      for (std::size_t k = 0; k < facets.size(); ++k) {
        if (normal[k].dot(centre) >= lit_reach && (reach_cos[k] <= -2.0 || axis[k].dot(centre) >= reach_cos[k])) {
          made.push_back(static_cast<std::uint32_t>(k));
        }
      }
      return made;
    });
  }
};

std::shared_ptr<const PropagationScene::ReflectorIndex> PropagationScene::reflector_index(const Eigen::Vector3d& origin_m,
                                                                                          const std::vector<NearFacet>& facets) const {
  {
    const std::lock_guard lock(cache_mutex_);
    auto cached = reflector_indexes_.find(
        [&](const ReflectorIndex& index) { return index.origin_m == origin_m && indexes_facets(index.facets, facets); });
    if (cached) return cached;
    // A moving antenna never comes back to the very same point: index only a point met before.
    if (!reflector_indexes_.met_before(origin_m)) return nullptr;
  }
  auto index = std::make_shared<ReflectorIndex>();
  index->origin_m = origin_m;
  const double cell_reach_rad = ReflectorIndex::Cells::kCell_rad + ReflectorIndex::Cells::kMargin_rad;
  for (const NearFacet& nf : facets) {
    const Facet& f = facets_[nf.index];
    index->facets.push_back(nf.index);
    index->normal.push_back(nf.normal);
    const Eigen::Vector3d to_centre = f.centre_m - (origin_m - 2.0 * nf.height_m * nf.normal);
    const double distance_m = to_centre.norm();
    // A hair wide: the reflection test's rounding is far below a micrometre.
    const double radius_m = f.radius_m * (1.0 + 1e-9) + 1e-6;
    if (!(distance_m > radius_m)) {
      index->axis.push_back(Eigen::Vector3d::Zero());
      index->reach_cos.push_back(-2.0);
      continue;
    }
    const double reach_rad = std::asin(radius_m / distance_m) + cell_reach_rad;
    index->axis.push_back(to_centre / distance_m);
    index->reach_cos.push_back(reach_rad >= std::numbers::pi ? -2.0 : std::cos(reach_rad));
  }
  const std::lock_guard lock(cache_mutex_);
  reflector_indexes_.keep(index);
  return index;
}

struct PropagationScene::ReflectedEdgeIndex {
  // Beyond this many pairs in all cells (48 MB) the index starts afresh: the satellites have moved
  // on from most of the cells it holds.
  static constexpr std::size_t kMaxEntries = 1'000'000;

  Eigen::Vector3d origin_m = Eigen::Vector3d::Zero();
  std::vector<std::size_t> facets;  // the second-order facets (scene indices) the pairs index
  double excess_max_m = 0.0;        // the largest excess over an edge of a blocked satellite's path
  double radius_m = 0.0;            // the search radius
  mutable std::mutex mutex;
  // (cell, object): the pairs for diffraction then reflection; and for knife-edge diffraction
  // over the object alone (`facet` unused).
  mutable std::map<std::pair<int, std::size_t>, std::shared_ptr<const FacetEdgeList>> lists, edge_lists;
  mutable std::size_t entries = 0;
};

std::shared_ptr<const PropagationScene::ReflectedEdgeIndex> PropagationScene::reflected_edge_index(
    const Eigen::Vector3d& origin_m, const std::vector<NearFacet>& facets, double excess_max_m, double radius_m) const {
  const std::lock_guard lock(cache_mutex_);
  auto cached = reflected_edge_indexes_.find([&](const ReflectedEdgeIndex& index) {
    return index.origin_m == origin_m && index.excess_max_m == excess_max_m && index.radius_m == radius_m &&
           indexes_facets(index.facets, facets);
  });
  if (cached) return cached;
  // A moving antenna never comes back to the very same point: index only a point met before.
  if (!reflected_edge_indexes_.met_before(origin_m)) return nullptr;
  auto index = std::make_shared<ReflectedEdgeIndex>();
  index->origin_m = origin_m;
  index->excess_max_m = excess_max_m;
  index->radius_m = radius_m;
  for (const NearFacet& f : facets) index->facets.push_back(f.index);
  reflected_edge_indexes_.keep(index);
  return index;
}

std::shared_ptr<const PropagationScene::FacetEdgeList> PropagationScene::facet_edge_pairs(
    const ReflectedEdgeIndex& index, bool knife_edges, std::size_t object, const Eigen::Vector3d& s,
    const FacetEdgeSearch& search) {
  auto& lists = knife_edges ? index.edge_lists : index.lists;
  using Cells = DoubleBounceIndex;
  const int cell = Cells::cell_of(s);
  const std::pair<int, std::size_t> key{cell, object};
  {
    const std::lock_guard lock(index.mutex);
    if (auto it = lists.find(key); it != lists.end()) return it->second;
    if (index.entries >= ReflectedEdgeIndex::kMaxEntries) {
      index.lists.clear();
      index.edge_lists.clear();
      index.entries = 0;
    }
  }
  const Eigen::Vector3d& centre = Cells::cell_centres()[static_cast<std::size_t>(cell)];
  // No direction of a cell is farther than one cell size from its centre.
  auto made = std::make_shared<FacetEdgeList>();
  static const ConeReach cell_reach(Cells::kCell_rad + Cells::kMargin_rad);
  made->entries = search(centre, cell_reach);
  for (const FacetEdge& entry : made->entries) {
    made->axis_x.push_back(static_cast<float>(entry.axis.x()));
    made->axis_y.push_back(static_cast<float>(entry.axis.y()));
    made->axis_z.push_back(static_cast<float>(entry.axis.z()));
    made->cos_low.push_back(static_cast<float>(entry.cos_min) - kSinglePrecisionSlack);
    made->cos_high.push_back(static_cast<float>(entry.cos_max) + kSinglePrecisionSlack);
  }
  const std::shared_ptr<const FacetEdgeList> pairs = std::move(made);
  const std::lock_guard lock(index.mutex);
  auto [it, inserted] = lists.emplace(key, pairs);
  if (inserted) index.entries += pairs->entries.size();
  return it->second;
}

std::vector<PathSet> PropagationScene::paths(const Eigen::Vector3d& origin_m, const std::vector<Eigen::Vector3d>& directions,
                                             const PathSearchSettings& settings) const {
  if (settings.moving_cell_m > 0.0) return paths_by_moving_cell(origin_m, directions, settings);
  return settings.static_sky_cell_deg > 0.0 ? paths_by_sky_cell(origin_m, directions, settings, SearchScope{})
                                            : search_paths(origin_m, directions, settings, SearchScope{});
}

Eigen::Vector3d moving_cell_centre(const Eigen::Vector3d& point_m, double cell_m) {
  return ((point_m / cell_m).array().floor() + 0.5).matrix() * cell_m;
}

std::vector<PathSet> PropagationScene::paths_by_moving_cell(const Eigen::Vector3d& origin_m,
                                                            const std::vector<Eigen::Vector3d>& directions,
                                                            const PathSearchSettings& settings) const {
  // What changes within a step of the antenna -- the line of sight, the single reflections, the
  // knife edges -- is searched where the antenna is.
  std::vector<PathSet> out = search_paths(origin_m, directions, settings, SearchScope{.near_only = true});
  if (settings.max_reflection_order < 2 && settings.scattering_coefficient <= 0.0) return out;
  // The rest comes from the cube's centre, searched once per sky cell there (with no index of the
  // point: a cube is left within a few epochs), its excess delays carried to the antenna.
  const Eigen::Vector3d centre = moving_cell_centre(origin_m, settings.moving_cell_m);
  PathSearchSettings whole = settings;
  whole.moving_cell_m = 0.0;
  whole.static_sky_cell_deg = PathSearchSettings::kMovingSkyCell_deg;
  std::vector<PathSet> far = paths_by_sky_cell(centre, directions, whole, SearchScope{.point_indexes = false});
  const Eigen::Vector3d offset = origin_m - centre;
  for (std::size_t i = 0; i < out.size(); ++i) {
    for (SignalPath& p : far[i].paths) {
      // Scattering is searched for a satellite hidden from the antenna only (as search_paths does).
      const bool far_kind = (p.type == PathType::kScattered && out[i].direct.blocked) ||
                            (p.type == PathType::kReflected && p.reflections >= 2) ||
                            (p.type == PathType::kDiffracted && p.reflections >= 1);
      if (!far_kind) continue;
      p.excess_delay_m = std::max(p.excess_delay_m + p.delay_gradient_origin.dot(offset), 0.0);
      out[i].paths.push_back(std::move(p));
    }
  }
  sort_indirect_paths_by_power(out);
  return out;
}

// The paths found at a cell's centre, for one antenna point and settings.
struct PropagationScene::SkyCellPaths {
  Eigen::Vector3d origin_m = Eigen::Vector3d::Zero();
  PathSearchSettings settings;
  std::unordered_map<std::uint64_t, std::shared_ptr<const PathSet>> cells;
};

std::vector<PathSet> PropagationScene::paths_by_sky_cell(const Eigen::Vector3d& origin_m,
                                                         const std::vector<Eigen::Vector3d>& directions,
                                                         const PathSearchSettings& settings, SearchScope scope) const {
  // A day at one point passes through about 10^5 cells; the oldest are forgotten (as a cell's paths
  // depend on the cell alone, searching one again gives the same answer).
  constexpr std::size_t kMaxCells = 4096;
  const std::size_t n = directions.size();
  std::vector<SkyCell> cells(n);
  for (std::size_t i = 0; i < n; ++i) cells[i] = sky_cell_of(directions[i], settings.static_sky_cell_deg);
  std::vector<std::shared_ptr<const PathSet>> found(n);
  std::shared_ptr<SkyCellPaths> kept;
  {
    const std::lock_guard lock(sky_cell_mutex_);
    for (const auto& candidate : sky_cell_paths_) {
      if (candidate && candidate->origin_m == origin_m && candidate->settings == settings) kept = candidate;
    }
    if (!kept) {
      kept = std::make_shared<SkyCellPaths>();
      kept->origin_m = origin_m;
      kept->settings = settings;
      sky_cell_paths_[next_sky_cell_paths_] = kept;
      next_sky_cell_paths_ = (next_sky_cell_paths_ + 1) % sky_cell_paths_.size();
    }
    for (std::size_t i = 0; i < n; ++i) {
      if (const auto it = kept->cells.find(cells[i].key); it != kept->cells.end()) found[i] = it->second;
    }
  }
  // The cells not known yet, each searched once at its centre.
  std::vector<Eigen::Vector3d> centres;
  std::vector<std::uint64_t> keys;
  for (std::size_t i = 0; i < n; ++i) {
    if (!found[i] && std::find(keys.begin(), keys.end(), cells[i].key) == keys.end()) {
      keys.push_back(cells[i].key);
      centres.push_back(cells[i].centre);
    }
  }
  if (!keys.empty()) {
    std::vector<PathSet> searched = search_paths(origin_m, centres, settings, scope);
    std::vector<std::shared_ptr<const PathSet>> fresh(keys.size());
    for (std::size_t k = 0; k < keys.size(); ++k) fresh[k] = std::make_shared<const PathSet>(std::move(searched[k]));
    for (std::size_t i = 0; i < n; ++i) {
      if (!found[i]) found[i] = fresh[static_cast<std::size_t>(std::find(keys.begin(), keys.end(), cells[i].key) - keys.begin())];
    }
    const std::lock_guard lock(sky_cell_mutex_);
    if (kept->cells.size() + keys.size() > kMaxCells) kept->cells.clear();
    for (std::size_t k = 0; k < keys.size(); ++k) kept->cells.emplace(keys[k], fresh[k]);
  }
  // Each direction gets its cell's paths, the excess delays carried from the centre to it (exact
  // for reflections, whose excess is linear in the direction; second order in the offset for the
  // others), the direct path arriving from the direction itself.
  std::vector<PathSet> out(n);
  for (std::size_t i = 0; i < n; ++i) {
    out[i] = *found[i];
    const Eigen::Vector3d offset = directions[i] - cells[i].centre;
    for (SignalPath& p : out[i].paths) {
      if (p.type == PathType::kDirect) {
        p.arrival_direction = directions[i];
      } else {
        p.excess_delay_m = std::max(p.excess_delay_m + p.delay_gradient_direction.dot(offset), 0.0);
      }
    }
  }
  return out;
}

std::vector<PathSet> PropagationScene::search_paths(const Eigen::Vector3d& origin_m, const std::vector<Eigen::Vector3d>& directions,
                                                    const PathSearchSettings& settings, SearchScope scope) const {
  const Eigen::Vector3d& r = origin_m;
  // What this search looks for (the settings' reflection coefficients whatever the scope).
  const int max_order = scope.near_only ? std::min(settings.max_reflection_order, 1) : settings.max_reflection_order;
  const bool scattering = !scope.near_only && settings.scattering_coefficient > 0.0;
  const std::size_t n_sat = directions.size();
  const double kInf = std::numeric_limits<double>::infinity();
  std::vector<PathSet> out(n_sat);

  // One batch from the receiver: the direct rays, then (for diffraction) the probe rays around
  // each direction that find the objects whose edges pass close to it.
  constexpr std::array<double, 1> kProbeAngles_rad = {3.5 * std::numbers::pi / 180.0};
  constexpr std::size_t kProbes = 4 * kProbeAngles_rad.size();
  std::vector<Eigen::Vector3d> batch(directions);
  if (settings.diffraction && !edges_.empty()) {
    batch.reserve(n_sat * (1 + kProbes));
    for (const Eigen::Vector3d& s : directions) {
      const Eigen::Vector3d side = std::abs(s.z()) < 0.999 ? Eigen::Vector3d(s.cross(Eigen::Vector3d::UnitZ()).normalized())
                                                           : Eigen::Vector3d::UnitX();
      const Eigen::Vector3d up = side.cross(s);
      for (const double angle : kProbeAngles_rad) {
        for (const Eigen::Vector3d& u : {side, Eigen::Vector3d(-side), up, Eigen::Vector3d(-up)}) {
          batch.push_back(std::cos(angle) * s + std::sin(angle) * u);
        }
      }
    }
  }
  std::vector<RayOutcome> first_batch = scene_->trace(r, batch);
  for (std::size_t i = 0; i < n_sat; ++i) {
    out[i].direct = std::move(first_batch[i]);
    if (!out[i].direct.blocked) {
      SignalPath p;
      p.rhcp_amplitude = amplitude_factor(out[i].direct.vegetation_attenuation_db);
      p.arrival_direction = directions[i];
      p.vegetation_attenuation_db = out[i].direct.vegetation_attenuation_db;
      out[i].paths.push_back(std::move(p));
    }
  }
  // The facet candidates seen from the antenna: normal towards it, its height above the plane.
  std::vector<NearFacet> near_facets;
  const std::shared_ptr<const Candidates> near = settings.max_reflection_order >= 1 || settings.scattering_coefficient > 0.0
                                                     ? candidates(r, settings)
                                                     : std::make_shared<const Candidates>();
  near_facets.reserve(near->facets.size());
  for (const NearFacet& c : near->facets) {
    const double h = c.normal.dot(r) - facets_[c.index].offset_m;
    if (std::abs(h) < 1e-6) continue;  // in the plane: no reflection
    near_facets.push_back(NearFacet{c.index, h >= 0.0 ? c.normal : Eigen::Vector3d(-c.normal), std::abs(h), c.eta, c.patches});
  }
  // A static antenna's first-order reflectors by sky cell; else the facets as arrays, for the first
  // test of the first-order reflections of all facets at once.
  const std::shared_ptr<const ReflectorIndex> first_order_index =
      max_order >= 1 && scope.point_indexes ? reflector_index(r, near_facets) : nullptr;
  ReflectorArrays reflectors;
  std::vector<double> may_reflect;
  if (max_order >= 1 && !first_order_index) {
    may_reflect.resize(near_facets.size());
    for (auto* v : {&reflectors.nx, &reflectors.ny, &reflectors.nz, &reflectors.height, &reflectors.ix, &reflectors.iy,
                    &reflectors.iz, &reflectors.cx, &reflectors.cy, &reflectors.cz, &reflectors.radius2}) {
      v->resize(near_facets.size());
    }
    for (std::size_t k = 0; k < near_facets.size(); ++k) {
      const NearFacet& nf = near_facets[k];
      const Facet& f = facets_[nf.index];
      const Eigen::Vector3d image = r - 2.0 * nf.height_m * nf.normal;
      reflectors.nx[k] = nf.normal.x();
      reflectors.ny[k] = nf.normal.y();
      reflectors.nz[k] = nf.normal.z();
      reflectors.height[k] = nf.height_m;
      reflectors.ix[k] = image.x();
      reflectors.iy[k] = image.y();
      reflectors.iz[k] = image.z();
      reflectors.cx[k] = f.centre_m.x();
      reflectors.cy[k] = f.centre_m.y();
      reflectors.cz[k] = f.centre_m.z();
      reflectors.radius2[k] = f.radius_m * f.radius_m;
    }
  }
  // Double bounces between the facets within second_order_radius_m (their number grows as its square).
  std::vector<NearFacet> second_order_facets;
  if (max_order >= 2) {
    const double radius2_m = settings.second_order_radius_m > 0.0 ? settings.second_order_radius_m : settings.radius_m;
    for (const NearFacet& nf : near_facets) {
      const Facet& f = facets_[nf.index];
      if ((r.cwiseMax(f.min_m).cwiseMin(f.max_m) - r).norm() <= radius2_m) second_order_facets.push_back(nf);
    }
  }
  const double wavelength_m = kSpeedOfLight_mps / settings.frequency_hz;
  const double min_power = std::pow(10.0, settings.min_relative_power_db / 10.0);
  // What a rough facade keeps for its specular reflection: the rest is scattered (power balance of
  // the effective-roughness model, R^2 + S^2 = 1).
  const double specular_factor = std::sqrt(1.0 - std::min(settings.scattering_coefficient, 1.0) *
                                                     std::min(settings.scattering_coefficient, 1.0));

  // A path in the making: its geometry and the legs still to be checked beyond the first.
  struct Leg {
    Eigen::Vector3d origin_m, direction;
    double length_m;  // infinity: towards the satellite
  };
  struct Pending {
    std::size_t satellite = 0;
    SignalPath path;
    double first_leg_m = 0.0;
    std::vector<Leg> legs;
    std::optional<std::size_t> facet;  // a first-order reflection's facet (index in near_facets)
  };
  std::vector<Pending> pending;
  std::vector<Eigen::Vector3d> first_legs;

  // Knife-edge candidates of one satellite before they become paths.
  struct EdgeHit {
    std::size_t edge = 0;
    Eigen::Vector3d point_m;
    double excess_m = 0.0, v = 0.0, loss_db = 0.0;
  };
  std::vector<EdgeHit> hits;
  // Which entries of an index list may hold direction s in their band (1), the others 0.
  std::vector<std::int32_t> within_band;
  const auto screen_bands_of = [&](const FacetEdgeList& list, const Eigen::Vector3d& s) {
    within_band.resize(list.entries.size());
    screen_bands(list.axis_x.data(), list.axis_y.data(), list.axis_z.data(), list.cos_low.data(), list.cos_high.data(),
                 list.entries.size(), static_cast<float>(s.x()), static_cast<float>(s.y()), static_cast<float>(s.z()),
                 within_band.data());
  };
  std::vector<std::size_t> objects;
  // Largest excess over an edge still worth a path (blocked) or a loss (in view), from J(v).
  double v_max = 0.0;
  while (v_max < 100.0 && knife_edge_loss_db(v_max) < std::min(settings.max_diffraction_loss_db, -settings.min_relative_power_db)) v_max += 0.05;
  const double blocked_excess_max_m = v_max * v_max * wavelength_m / 4.0;
  const double grazing_excess_max_m = 0.78 * 0.78 * wavelength_m / 4.0;
  // A static antenna's facet-edge pairs for diffraction then reflection, by sky cell.
  const std::shared_ptr<const ReflectedEdgeIndex> edge_index =
      settings.diffraction && !edges_.empty() && scope.point_indexes
          ? reflected_edge_index(r, second_order_facets, blocked_excess_max_m, settings.radius_m)
          : nullptr;

  // Second order: satellite -> B -> A -> receiver; the image of the receiver's image in A taken in
  // B gives the point on B, the line from there to the first image the point on A. Pairs go facet
  // A by facet A, each with the partners B that can face it whatever the satellite (B reaches A's
  // receiver side, A reaches B's side of the first image): what depends on the pair alone is
  // worked out once instead of once per satellite. Paths are kept per satellite in pair order.
  std::vector<std::vector<Pending>> second_order(n_sat);
  if (max_order >= 2) {
    // Facet A's plane (na . x = ca) and the receiver's image in it.
    std::vector<double> plane_a(second_order_facets.size());
    std::vector<Eigen::Vector3d> image_of(second_order_facets.size());
    for (std::size_t k = 0; k < second_order_facets.size(); ++k) {
      const NearFacet& a = second_order_facets[k];
      plane_a[k] = a.normal.dot(r) - a.height_m;
      image_of[k] = r - 2.0 * a.height_m * a.normal;
    }
    // The double bounce of satellite i off a pair whose cones hold it, if there is one.
    const auto bounce = [&](const FacetPair& pair, std::size_t i) {
      const Eigen::Vector3d& s = directions[i];
      const NearFacet& a = second_order_facets[pair.a];
      const NearFacet& b = second_order_facets[pair.b];
      const Facet& fa = facets_[a.index];
      const Facet& fb = facets_[b.index];
      const Eigen::Vector3d& na = a.normal;
      const double ca = plane_a[pair.a];
      const Eigen::Vector3d& image_a = image_of[pair.a];
      const double hb = pair.hb;
      const Eigen::Vector3d& nb = pair.nb;  // side of image_a
      const double nbs = nb.dot(s);
      if (nbs <= 1e-6) return;
      const Eigen::Vector3d& image_ab = pair.image_ab;
      const Eigen::Vector3d p2 = image_ab + (std::abs(hb) / nbs) * s;
      if ((p2 - fb.centre_m).squaredNorm() > fb.radius_m * fb.radius_m) return;
      const Eigen::Vector3d to_image = image_a - p2;
      const double denom = na.dot(to_image);
      if (std::abs(denom) < 1e-12) return;
      const double lambda = (ca - na.dot(p2)) / denom;
      if (lambda <= 0.0 || lambda >= 1.0) return;
      const Eigen::Vector3d p1 = p2 + lambda * to_image;
      // Both bounces on the facing sides: p2 on the receiver's side of A, p1 on B's lit side.
      if (na.dot(p2) - ca <= 0.0 || nb.dot(p1 - p2) <= 0.0) return;
      const double d1 = (p1 - r).norm(), d12 = (p2 - p1).norm();
      if (d1 > settings.radius_m || d12 < 1e-3 || (p2 - r).norm() > settings.radius_m) return;
      if (!fa.contains(p1) || !fb.contains(p2)) return;
      const Eigen::Vector3d u12 = (p2 - p1) / d12;
      Pending p;
      p.satellite = i;
      p.path.type = PathType::kReflected;
      p.path.reflections = 2;
      p.path.excess_delay_m = d1 + d12 - s.dot(p2 - r);
      p.path.rhcp_amplitude = 1.0;
      p.path.lhcp_amplitude = 0.0;
      reflect_state(p.path.rhcp_amplitude, p.path.lhcp_amplitude, fresnel_coefficients(b.eta, nbs));
      reflect_state(p.path.rhcp_amplitude, p.path.lhcp_amplitude, fresnel_coefficients(a.eta, std::abs(na.dot(u12))));
      p.path.rhcp_amplitude *= specular_factor * specular_factor;
      p.path.lhcp_amplitude *= specular_factor * specular_factor;
      if (p.path.power_linear() < min_power) return;
      p.path.arrival_direction = (p1 - r) / d1;
      p.path.point_m = p1;
      p.path.second_point_m = p2;
      p.path.material = fa.material;
      p.path.object = object_names_[fa.object];
      // excess = -s . (image_ab - r), image_ab = M r + b with M the two Householder reflections.
      const Eigen::Matrix3d m = (Eigen::Matrix3d::Identity() - 2.0 * nb * nb.transpose()) *
                                (Eigen::Matrix3d::Identity() - 2.0 * na * na.transpose());
      p.path.delay_gradient_origin = s - m.transpose() * s;
      p.path.delay_gradient_direction = -(image_ab - r);
      p.first_leg_m = d1;
      p.legs.push_back(Leg{p1 + kSurfaceOffset_m * na, u12, d12});
      p.legs.push_back(Leg{p2 + kSurfaceOffset_m * nb, s, kInf});
      second_order[i].push_back(std::move(p));
    };
    const std::shared_ptr<const DoubleBounceIndex> index =
        scope.point_indexes ? double_bounce_index(r, second_order_facets, plane_a, image_of) : nullptr;
    if (index) {
      // A static antenna: every pair is known, each satellite tries those whose cone covers its
      // sky cell, in pair order (as below).
      for (std::size_t i = 0; i < n_sat; ++i) {
        index->for_each_candidate(directions[i], [&](const FacetPair& pair) { bounce(pair, i); });
      }
    } else {
      // A moving antenna: the pairs of each facet A in turn, screened all at once (the arrays below);
      // a pair's two cones are tested against all satellites at once in single precision, a little
      // wider than the exact test, and only a pair some satellite may use is formed.
      std::vector<FacetPair> pairs;
      std::array<std::vector<float>, 3> sky;
      for (std::size_t c = 0; c < 3; ++c) {
        sky[c].resize(n_sat);
        for (std::size_t i = 0; i < n_sat; ++i) sky[c][i] = static_cast<float>(directions[i][static_cast<Eigen::Index>(c)]);
      }
      std::vector<std::int32_t> within(n_sat);
      std::vector<std::uint32_t> marked(n_sat);
      std::vector<std::vector<std::uint32_t>> candidates(n_sat);  // per satellite, in pair order
      const std::size_t n_facets = second_order_facets.size();
      FacetArrays arrays;
      for (auto* v : {&arrays.nx, &arrays.ny, &arrays.nz, &arrays.offset, &arrays.cx, &arrays.cy, &arrays.cz, &arrays.radius}) v->resize(n_facets);
      for (std::size_t k = 0; k < n_facets; ++k) {
        const Facet& f = facets_[second_order_facets[k].index];
        arrays.nx[k] = f.normal.x();
        arrays.ny[k] = f.normal.y();
        arrays.nz[k] = f.normal.z();
        arrays.offset[k] = f.offset_m;
        arrays.cx[k] = f.centre_m.x();
        arrays.cy[k] = f.centre_m.y();
        arrays.cz[k] = f.centre_m.z();
        arrays.radius[k] = f.radius_m;
      }
      std::vector<std::int32_t> keep(n_facets);
      std::vector<std::uint32_t> kept(n_facets);
      std::vector<float> axis1_x(n_facets), axis1_y(n_facets), axis1_z(n_facets), cos1(n_facets);
      std::vector<float> axis2_x(n_facets), axis2_y(n_facets), axis2_z(n_facets);
      FacetPair pair;
      double lowest_z = 1.0;
      for (const Eigen::Vector3d& s : directions) lowest_z = std::min(lowest_z, s.z());
      for (std::size_t a = 0; a < n_facets; ++a) {
        const Facet& fa = facets_[second_order_facets[a].index];
        // A's mirrored cone before the mirror, as make_facet_pair forms it.
        const SphereCone cone_a = sphere_cone(fa, image_of[a], kMirroredConeWider);
        screen_facet_pairs(arrays, n_facets, a, image_of[a], second_order_facets[a].normal, plane_a[a], fa.centre_m, fa.radius_m,
                           cone_a.axis, cone_a.cos, cone_a.sin, lowest_z, keep.data(), axis1_x.data(), axis1_y.data(), axis1_z.data(), cos1.data(),
                           axis2_x.data(), axis2_y.data(), axis2_z.data());
        pairs.clear();
        for (auto& list : candidates) list.clear();
        // The facets kept, without a branch per facet.
        std::size_t n_kept = 0;
        for (std::size_t b = 0; b < n_facets; ++b) {
          kept[n_kept] = static_cast<std::uint32_t>(b);
          n_kept += static_cast<std::size_t>(keep[b]);
        }
        for (std::size_t kept_index = 0; kept_index < n_kept; ++kept_index) {
          const std::size_t b = kept[kept_index];
          if (mark_within_cones(sky[0].data(), sky[1].data(), sky[2].data(), n_sat, axis1_x[b], axis1_y[b], axis1_z[b], cos1[b],
                                axis2_x[b], axis2_y[b], axis2_z[b], cone_a.cos <= -2.0 ? -2.0F : static_cast<float>(cone_a.cos) - 1e-4F,
                                within.data()) == 0) {
            continue;
          }
          if (!make_facet_pair(a, b, second_order_facets, plane_a, image_of, pair)) continue;
          const auto k = static_cast<std::uint32_t>(pairs.size());
          pairs.push_back(pair);
          // The satellites marked, without a branch per satellite.
          std::size_t n_marked = 0;
          for (std::size_t i = 0; i < n_sat; ++i) {
            marked[n_marked] = static_cast<std::uint32_t>(i);
            n_marked += static_cast<std::size_t>(within[i]);
          }
          for (std::size_t m = 0; m < n_marked; ++m) candidates[marked[m]].push_back(k);
        }
        for (std::size_t i = 0; i < n_sat; ++i) {
          for (const std::uint32_t k : candidates[i]) {
            if (pairs[k].may_carry(directions[i])) bounce(pairs[k], i);
          }
        }
      }
    }
  }

  for (std::size_t i = 0; i < n_sat; ++i) {
    const Eigen::Vector3d& s = directions[i];
    // First order: the image of the receiver in the facet's plane, the line from it towards the
    // satellite meets the plane at the reflection point.
    if (max_order >= 1) {
      const auto reflect_off = [&](std::size_t k) {
        const NearFacet& nf = near_facets[k];
        const double ns = nf.normal.dot(s);
        if (ns <= 1e-6) return;
        const double t = nf.height_m / ns;  // receiver to reflection point
        if (t > settings.radius_m) return;
        const Facet& f = facets_[nf.index];
        const Eigen::Vector3d point = r - 2.0 * nf.height_m * nf.normal + t * s;
        if ((point - f.centre_m).squaredNorm() > f.radius_m * f.radius_m || !f.contains(point)) return;
        Pending p;
        p.satellite = i;
        p.path.type = PathType::kReflected;
        p.path.reflections = 1;
        p.path.excess_delay_m = 2.0 * nf.height_m * ns;
        p.path.rhcp_amplitude = 1.0;
        p.path.lhcp_amplitude = 0.0;
        reflect_state(p.path.rhcp_amplitude, p.path.lhcp_amplitude, fresnel_coefficients(nf.eta, ns));
        p.path.rhcp_amplitude *= specular_factor;
        p.path.lhcp_amplitude *= specular_factor;
        if (p.path.power_linear() < min_power) return;
        p.path.arrival_direction = (point - r) / t;
        p.path.point_m = point;
        p.path.material = f.material;
        p.path.object = object_names_[f.object];
        p.path.delay_gradient_origin = 2.0 * ns * nf.normal;
        p.path.delay_gradient_direction = 2.0 * nf.height_m * nf.normal;
        p.first_leg_m = t;
        p.facet = static_cast<std::size_t>(&nf - near_facets.data());
        p.legs.push_back(Leg{point + kSurfaceOffset_m * nf.normal, s, kInf});
        first_legs.push_back(p.path.arrival_direction);
        pending.push_back(std::move(p));
      };
      // The facets in ascending order either way: a static antenna's listed for the direction's
      // sky cell, else those that pass the screen of all at once (both looser than the test above).
      if (first_order_index) {
        const auto listed = first_order_index->facets_towards(s);  // held: the index may start afresh
        for (const std::uint32_t k : *listed) reflect_off(k);
      } else {
        screen_reflections(reflectors, near_facets.size(), s, settings.radius_m, may_reflect.data());
        for (std::size_t k = 0; k < near_facets.size(); ++k) {
          if (may_reflect[k] != 0.0) reflect_off(k);
        }
      }
    }
    // Second order (found for every satellite before this loop, in the same order).
    for (Pending& p : second_order[i]) {
      first_legs.push_back(p.path.arrival_direction);
      pending.push_back(std::move(p));
    }
    // Knife-edge diffraction: the point of the edge where the incident and diffracted rays make
    // equal angles with it (Keller's cone) is the stationary path over the edge.
    if (settings.diffraction && !edges_.empty()) {
      const bool blocked = out[i].direct.blocked;
      objects.clear();
      auto add_object = [&](const RayOutcome& o) {
        if (!o.blocked || o.blocking_distance_m > settings.radius_m) return;
        const auto it = object_index_.find(std::string(o.blocking_object));
        if (it != object_index_.end() && std::find(objects.begin(), objects.end(), it->second) == objects.end()) {
          objects.push_back(it->second);
        }
      };
      if (blocked) {
        add_object(out[i].direct);
      } else {
        for (std::size_t k = 0; k < kProbes; ++k) add_object(first_batch[n_sat + i * kProbes + k]);
      }
      const double excess_max_m = blocked ? blocked_excess_max_m : grazing_excess_max_m;
      hits.clear();
      auto may_reach = [&](const Eigen::Vector3d& centre_m, double radius_m) {
        return may_reach_line(r, s, excess_max_m, centre_m, radius_m);
      };
      const auto try_knife_edge = [&](std::size_t e) {
        const DiffractionEdge& edge = edges_[e];
        if (!may_reach(edge.midpoint_m, edge.half_length_m)) return;
        const std::optional<Eigen::Vector3d> keller = keller_point(edge, r, s);
        if (!keller) return;
        const Eigen::Vector3d& q = *keller;
        const double d2 = (q - r).norm();
        if (d2 < 1e-3 || d2 > settings.radius_m || (q - r).dot(s) <= 0.0) return;
        const double excess = d2 - s.dot(q - r);
        if (excess > excess_max_m) return;
        const double v_magnitude = std::sqrt(4.0 * std::max(excess, 0.0) / wavelength_m);
        const double v = blocked ? v_magnitude : -v_magnitude;
        hits.push_back(EdgeHit{e, q, excess, v, knife_edge_loss_db(v)});
      };
      // A static antenna behind an object: its edges that may serve a direction of the satellite's
      // sky cell, each with its band of directions (as for diffraction then reflection below).
      std::shared_ptr<const FacetEdgeList> knife_listed;
      if (edge_index && blocked && objects.size() == 1) {
        const std::size_t object = objects.front();
        knife_listed = facet_edge_pairs(*edge_index, true, object, s, [&](const Eigen::Vector3d& cell_axis, const ConeReach& cell_reach) {
          const auto reach_cell = [&](const Eigen::Vector3d& centre_m, double radius_m) {
            return may_reach_cone(r, cell_axis, cell_reach, excess_max_m, centre_m, radius_m);
          };
          std::vector<FacetEdge> entries;
          for (const EdgeCluster& cluster : object_clusters_[object]) {
            if (!reach_cell(cluster.centre_m, cluster.radius_m)) continue;
            for (std::size_t k = cluster.begin; k < cluster.end; ++k) {
              const DiffractionEdge& edge = edges_[object_edges_[object][k]];
              if (!reach_cell(edge.midpoint_m, edge.half_length_m)) continue;
              if (auto entry = edge_band(edge, r, settings.radius_m, cell_axis, cell_reach)) {
                entry->edge = static_cast<std::uint32_t>(k);
                entries.push_back(*entry);
              }
            }
          }
          return entries;
        });
      }
      if (knife_listed) {
        const std::size_t object = objects.front();
        screen_bands_of(*knife_listed, s);
        for (std::size_t k = 0; k < knife_listed->entries.size(); ++k) {
          if (within_band[k] == 0) continue;
          const FacetEdge& entry = knife_listed->entries[k];
          const double c = s.dot(entry.axis);  // as keller_point works it out
          if (c >= entry.cos_min && c <= entry.cos_max) try_knife_edge(object_edges_[object][entry.edge]);
        }
      } else {
        for (const std::size_t object : objects) {
          for (const EdgeCluster& cluster : object_clusters_[object]) {
            if (!may_reach(cluster.centre_m, cluster.radius_m)) continue;
            for_each_edge_keller_may_hit(object_edge_arrays_[object], cluster.begin, cluster.end, r, s,
                                         [&](std::size_t k) { try_knife_edge(object_edges_[object][k]); });
          }
        }
      }
      if (!blocked) {
        // Line of sight grazing an edge: the knife-edge loss applies to the direct signal.
        const auto worst = std::max_element(hits.begin(), hits.end(),
                                            [](const EdgeHit& a, const EdgeHit& b) { return a.v < b.v; });
        if (worst != hits.end() && worst->loss_db > 0.0 && !out[i].paths.empty()) {
          SignalPath& d = out[i].paths.front();
          d.diffraction_v = worst->v;
          d.diffraction_loss_db = worst->loss_db;
          d.rhcp_amplitude *= std::pow(10.0, -worst->loss_db / 20.0);
        }
        continue;
      }
      // A few more than kept, as some fail their leg checks.
      std::sort(hits.begin(), hits.end(), [](const EdgeHit& a, const EdgeHit& b) { return a.loss_db < b.loss_db; });
      if (hits.size() > 4 * kMaxDiffractedPaths) hits.resize(4 * kMaxDiffractedPaths);
      for (const EdgeHit& hit : hits) {
        const DiffractionEdge& edge = edges_[hit.edge];
        const double d2 = (hit.point_m - r).norm();
        const Eigen::Vector3d toward = (hit.point_m - r) / d2;
        Pending p;
        p.satellite = i;
        p.path.type = PathType::kDiffracted;
        p.path.excess_delay_m = hit.excess_m;
        p.path.diffraction_v = hit.v;
        p.path.diffraction_loss_db = hit.loss_db;
        // Keller's diffraction coefficient carries exp(-j pi/4) in the shadow.
        p.path.rhcp_amplitude = std::polar(std::pow(10.0, -hit.loss_db / 20.0), -std::numbers::pi / 4.0);
        p.path.lhcp_amplitude = 0.0;
        p.path.arrival_direction = toward;
        p.path.point_m = hit.point_m;
        p.path.material = edge.material;
        p.path.object = object_names_[edge.object];
        p.path.delay_gradient_origin = s - toward;
        p.path.delay_gradient_direction = -(hit.point_m - r);
        p.first_leg_m = d2;
        p.legs.push_back(Leg{hit.point_m + kEdgeOffset_m * edge.outward, s, kInf});
        first_legs.push_back(toward);
        pending.push_back(std::move(p));
      }
      // Second order: over an edge of the blocking object, then off a facet near the receiver
      // (a street canyon's usual NLOS path: over the roof across the street, down onto a facade
      // and back). The knife edge as seen from the receiver's image in the facet; the reflection
      // point is where the line from the edge point to the image crosses the facet.
      if (max_order < 2 || second_order_facets.empty()) continue;
      struct ReflectedEdgeHit {
        std::size_t facet = 0, edge = 0;  // second-order facet, edge
        Eigen::Vector3d edge_point_m, reflection_point_m;
        double from_image_m = 0.0, v = 0.0, loss_db = 0.0;
      };
      // A few more than kept, as some fail their leg checks: the least lossy, ties in the order of
      // the facets and edges (so that which are kept does not depend on the order they are met).
      constexpr std::size_t kReflectedHitsKept = 4 * kMaxDiffractedPaths;
      const auto less_lossy = [](const ReflectedEdgeHit& a, const ReflectedEdgeHit& b) {
        return std::tie(a.loss_db, a.facet, a.edge) < std::tie(b.loss_db, b.facet, b.edge);
      };
      std::vector<ReflectedEdgeHit> reflected_hits;
      // The blocking objects' spheres (made with the scene).
      std::vector<Sphere> object_spheres;
      std::vector<const std::vector<Sphere>*> group_spheres;
      for (const std::size_t object : objects) {
        object_spheres.push_back(object_spheres_[object]);
        group_spheres.push_back(&group_spheres_[object]);
      }
      double farthest_edge_m = 0.0;  // from the receiver
      for (const Sphere& sphere : object_spheres) farthest_edge_m = std::max(farthest_edge_m, (sphere.centre_m - r).norm() + sphere.radius_m);
      // Only an edge on the object's outline seen from the satellite (one face lit, the other
      // not) bends the wave into the shadow.
      const auto outline = [&](std::size_t e) { return edges_[e].face_normal_a.dot(s) * edges_[e].face_normal_b.dot(s) <= 0.0; };
      // What a second-order facet offers whatever the satellite: the receiver's image in it, its
      // plane, and the cone from the image through its bounding sphere (the reflection point lies
      // on the segment from the image to an edge point, and on the facet).
      struct FacetSight {
        Eigen::Vector3d image = Eigen::Vector3d::Zero();
        double plane = 0.0;  // normal . x = plane
        bool cone = false;
        Eigen::Vector3d axis = Eigen::Vector3d::Zero();
        double sin = 1.0, cos = 0.0;
      };
      const auto facet_sight = [&](std::size_t f_index) {
        const NearFacet& nf = second_order_facets[f_index];
        const Facet& f = facets_[nf.index];
        FacetSight v;
        v.image = r - 2.0 * nf.height_m * nf.normal;
        v.plane = nf.normal.dot(r) - nf.height_m;
        const Eigen::Vector3d to_facet = f.centre_m - v.image;
        const double facet_distance_m = to_facet.norm();
        v.cone = facet_distance_m > f.radius_m;
        if (v.cone) {
          v.axis = to_facet / facet_distance_m;
          v.sin = f.radius_m / facet_distance_m;
          v.cos = std::sqrt(1.0 - v.sin * v.sin);
        }
        return v;
      };
      // Whether a sphere may hold an edge point such a path uses: on the receiver's side of the
      // facet's plane, within the cone through the facet, and near the image's line towards the
      // satellite (excess within the bound), the last as `reach` says.
      const auto may_hold = [&](const NearFacet& nf, const FacetSight& v, const Eigen::Vector3d& centre_m, double radius_m,
                                auto&& reach) {
        if (nf.normal.dot(centre_m) - v.plane + radius_m <= 0.0) return false;
        if (v.cone) {
          const Eigen::Vector3d m = centre_m - v.image;
          const double distance_m = m.norm();
          if (distance_m > radius_m) {
            const double sin_b = radius_m / distance_m, cos_b = std::sqrt(1.0 - sin_b * sin_b);
            // cos of (the facet's half angle + the sphere's), a hair wide
            if (m.dot(v.axis) < distance_m * (v.cos * cos_b - v.sin * sin_b - 1e-9)) return false;
          }
        }
        return reach(v.image, centre_m, radius_m);
      };
      const auto reach_line = [&](const Eigen::Vector3d& image, const Eigen::Vector3d& centre_m, double radius_m) {
        return may_reach_line(image, s, blocked_excess_max_m, centre_m, radius_m);
      };
      // The facet as this satellite sees it: its sight, or none when it cannot come close enough
      // to the image's line (h with h^2 <= 2 D excess, D the edge point's distance from the image).
      const auto facet_for_satellite = [&](std::size_t f_index) -> std::optional<FacetSight> {
        const NearFacet& nf = second_order_facets[f_index];
        const Facet& f = facets_[nf.index];
        FacetSight v = facet_sight(f_index);
        const Eigen::Vector3d m = f.centre_m - v.image;
        const double along = m.dot(s);
        const double reach_m = std::sqrt(2.0 * blocked_excess_max_m * (farthest_edge_m + 2.0 * nf.height_m));
        if (along < -f.radius_m || m.squaredNorm() - along * along > (f.radius_m + reach_m) * (f.radius_m + reach_m)) {
          return std::nullopt;
        }
        return v;
      };
      // One edge of an object's outline with one facet: the edge point where the image's line
      // bends over it, and the reflection point between them on the facet.
      const auto try_edge = [&](std::size_t f_index, const FacetSight& v, std::size_t e) {
        const NearFacet& nf = second_order_facets[f_index];
        const Facet& f = facets_[nf.index];
        const DiffractionEdge& edge = edges_[e];
        // Keller's point first: it lies outside most edges near the facet. Then the exact tests
        // from the cheapest; the bounds of may_hold, which hold for every point they pass (the
        // search stays the same whatever their order), after them.
        const std::optional<Eigen::Vector3d> keller = keller_point(edge, v.image, s);
        if (!keller) return;
        const Eigen::Vector3d& q = *keller;
        const Eigen::Vector3d from_image = q - v.image;
        const double d_image = from_image.norm();
        if (d_image < 1e-3 || from_image.dot(s) <= 0.0) return;
        // The edge on the receiver's side of the facet, and the image in its shadow: the
        // image's line towards the satellite passes on the object's side of the edge.
        const double above = nf.normal.dot(q) - v.plane;
        if (above <= 1e-6) return;
        if ((v.image + from_image.dot(s) * s - q).dot(edge.outward) >= 0.0) return;
        const double excess = d_image - s.dot(from_image);
        if (excess > blocked_excess_max_m) return;
        const double v_fresnel = std::sqrt(4.0 * std::max(excess, 0.0) / wavelength_m);
        ReflectedEdgeHit hit{f_index, e, q, Eigen::Vector3d::Zero(), d_image, v_fresnel, knife_edge_loss_db(v_fresnel)};
        // Only the least lossy hits are kept: one that cannot be among them is dropped before its
        // reflection point is looked for.
        if (reflected_hits.size() == kReflectedHitsKept && !less_lossy(hit, reflected_hits.front())) return;
        if (!may_hold(nf, v, edge.midpoint_m, edge.half_length_m, reach_line)) return;
        const Eigen::Vector3d point = q + above / (above + nf.height_m) * (v.image - q);
        if ((point - f.centre_m).squaredNorm() > f.radius_m * f.radius_m || !f.contains(point)) return;
        const double d1 = (point - r).norm();
        if (d1 < 1e-3 || d1 > settings.radius_m) return;
        hit.reflection_point_m = point;
        // A max-heap of the kept hits, the lossiest on top.
        if (reflected_hits.size() == kReflectedHitsKept) {
          std::pop_heap(reflected_hits.begin(), reflected_hits.end(), less_lossy);
          reflected_hits.back() = hit;
        } else {
          reflected_hits.push_back(hit);
        }
        std::push_heap(reflected_hits.begin(), reflected_hits.end(), less_lossy);
      };
      // A static antenna: the facet-edge pairs that may serve a satellite in its sky cell, found
      // once per cell and object (docs/performance.md); the same hits as the search below.
      std::shared_ptr<const FacetEdgeList> listed;
      if (edge_index && objects.size() == 1) {
        const std::size_t object = objects.front();
        listed = facet_edge_pairs(*edge_index, false, object, s, [&](const Eigen::Vector3d& cell_axis, const ConeReach& cell_reach) {
          // Near the image's line for some direction within the cell: the line's reach at the
          // sphere's distance widened by the cell's angle (or the sphere near the image).
          const auto reach_cell = [&](const Eigen::Vector3d& image, const Eigen::Vector3d& centre_m, double radius_m) {
            return may_reach_cone(image, cell_axis, cell_reach, blocked_excess_max_m, centre_m, radius_m);
          };
          std::vector<FacetEdge> pairs;
          const auto& clusters = object_clusters_[object];
          for (std::size_t f_index = 0; f_index < second_order_facets.size(); ++f_index) {
            const NearFacet& nf = second_order_facets[f_index];
            const FacetSight v = facet_sight(f_index);
            if (!may_hold(nf, v, object_spheres[0].centre_m, object_spheres[0].radius_m, reach_cell)) continue;
            for (std::size_t g = 0; g < group_spheres[0]->size(); ++g) {
              if (!may_hold(nf, v, (*group_spheres[0])[g].centre_m, (*group_spheres[0])[g].radius_m, reach_cell)) continue;
              for (std::size_t c_index = g * kClustersPerGroup; c_index < std::min(clusters.size(), (g + 1) * kClustersPerGroup); ++c_index) {
                const EdgeCluster& cluster = clusters[c_index];
                if (!may_hold(nf, v, cluster.centre_m, cluster.radius_m, reach_cell)) continue;
                for (std::size_t k = cluster.begin; k < cluster.end; ++k) {
                  const DiffractionEdge& edge = edges_[object_edges_[object][k]];
                  if (!may_hold(nf, v, edge.midpoint_m, edge.half_length_m, reach_cell)) continue;
                  if (auto pair = facet_edge_band(nf, facets_[nf.index], v.image, v.plane, edge, cell_axis, cell_reach)) {
                    pair->facet = static_cast<std::uint32_t>(f_index);
                    pair->edge = static_cast<std::uint32_t>(k);
                    pairs.push_back(*pair);
                  }
                }
              }
            }
          }
          return pairs;
        });
      }
      if (listed) {
        const std::size_t object = objects.front();
        std::size_t current = std::numeric_limits<std::size_t>::max();
        std::optional<FacetSight> v;
        screen_bands_of(*listed, s);
        for (std::size_t k = 0; k < listed->entries.size(); ++k) {
          if (within_band[k] == 0) continue;
          const FacetEdge& pair = listed->entries[k];
          const double c = s.dot(pair.axis);  // as keller_point works it out
          if (c < pair.cos_min || c > pair.cos_max) continue;
          if (pair.facet != current) {
            current = pair.facet;
            v = facet_for_satellite(current);
          }
          const std::size_t e = object_edges_[object][pair.edge];
          if (v && outline(e)) try_edge(current, *v, e);
        }
      } else {
        // The clusters of a group that may hold an edge point, tested at once.
        std::array<double, kClustersPerGroup> cluster_holds{};
        for (std::size_t f_index = 0; f_index < second_order_facets.size(); ++f_index) {
          const NearFacet& nf = second_order_facets[f_index];
          const std::optional<FacetSight> v = facet_for_satellite(f_index);
          if (!v) continue;
          const auto hold = [&](const Eigen::Vector3d& centre_m, double radius_m) { return may_hold(nf, *v, centre_m, radius_m, reach_line); };
          for (std::size_t rank = 0; rank < objects.size(); ++rank) {
            if (!hold(object_spheres[rank].centre_m, object_spheres[rank].radius_m)) continue;
            const std::size_t object = objects[rank];
            const auto& clusters = object_clusters_[object];
            const SphereArrays& spheres = object_cluster_arrays_[object];
            for (std::size_t g = 0; g < group_spheres[rank]->size(); ++g) {
              if (!hold((*group_spheres[rank])[g].centre_m, (*group_spheres[rank])[g].radius_m)) continue;
              // The group's clusters at once.
              const std::size_t first = g * kClustersPerGroup, last = std::min(clusters.size(), (g + 1) * kClustersPerGroup);
              screen_spheres(spheres.cx.data(), spheres.cy.data(), spheres.cz.data(), spheres.radius.data(), first, last, nf.normal,
                             v->plane, v->image, v->cone, v->axis, v->sin, v->cos, s, blocked_excess_max_m, cluster_holds.data());
              for (std::size_t c_index = first; c_index < last; ++c_index) {
                const EdgeCluster& cluster = clusters[c_index];
                if (cluster_holds[c_index - first] == 0.0) continue;
                for_each_edge_keller_may_hit(object_edge_arrays_[object], cluster.begin, cluster.end, v->image, s, [&](std::size_t k) {
                  const std::size_t e = object_edges_[object][k];
                  if (outline(e)) try_edge(f_index, *v, e);
                });
              }
            }
          }
        }
      }
      std::sort_heap(reflected_hits.begin(), reflected_hits.end(), less_lossy);
      for (const ReflectedEdgeHit& hit : reflected_hits) {
        const NearFacet& nf = second_order_facets[hit.facet];
        const Facet& f = facets_[nf.index];
        const DiffractionEdge& edge = edges_[hit.edge];
        const Eigen::Vector3d to_edge = hit.edge_point_m - hit.reflection_point_m;
        const double reflection_to_edge_m = to_edge.norm();
        const double d1 = (hit.reflection_point_m - r).norm();
        Pending p;
        p.satellite = i;
        p.path.type = PathType::kDiffracted;
        p.path.reflections = 1;
        // Path length from the edge by way of the facet: the distance from the edge to the image.
        p.path.excess_delay_m = hit.from_image_m - s.dot(hit.edge_point_m - r);
        p.path.diffraction_v = hit.v;
        p.path.diffraction_loss_db = hit.loss_db;
        p.path.rhcp_amplitude = std::polar(std::pow(10.0, -hit.loss_db / 20.0), -std::numbers::pi / 4.0);
        p.path.lhcp_amplitude = 0.0;
        reflect_state(p.path.rhcp_amplitude, p.path.lhcp_amplitude,
                      fresnel_coefficients(nf.eta, nf.normal.dot(to_edge) / reflection_to_edge_m));
        p.path.rhcp_amplitude *= specular_factor;
        p.path.lhcp_amplitude *= specular_factor;
        if (p.path.power_linear() < min_power) continue;
        p.path.arrival_direction = (hit.reflection_point_m - r) / d1;
        p.path.point_m = hit.reflection_point_m;
        p.path.second_point_m = hit.edge_point_m;
        p.path.material = f.material;
        p.path.object = object_names_[f.object];
        // excess = |q - image(r)| - s . (q - r): the image moves with r mirrored in the facet.
        const Eigen::Vector3d from_image = (hit.edge_point_m - (r - 2.0 * nf.height_m * nf.normal)) / hit.from_image_m;
        p.path.delay_gradient_origin = s - (from_image - 2.0 * nf.normal.dot(from_image) * nf.normal);
        p.path.delay_gradient_direction = -(hit.edge_point_m - r);
        p.first_leg_m = d1;
        p.legs.push_back(Leg{hit.reflection_point_m + kSurfaceOffset_m * nf.normal, to_edge / reflection_to_edge_m,
                             reflection_to_edge_m});
        p.legs.push_back(Leg{hit.edge_point_m + kEdgeOffset_m * edge.outward, s, kInf});
        first_legs.push_back(p.path.arrival_direction);
        pending.push_back(std::move(p));
      }
    }
  }
  if (scattering) add_scattered_paths(r, directions, settings, *near, near_facets, out);
  if (pending.empty()) {
    sort_indirect_paths_by_power(out);
    return out;
  }

  // All first legs start at the receiver: one batch. The others one ray each. A first-order
  // reflection whose first leg an object blocks is noted for a reflection, then a diffraction
  // over that object's edge (second order).
  struct HiddenReflection {
    std::size_t satellite = 0, facet = 0, object = 0;
  };
  std::vector<HiddenReflection> hidden_reflections;
  const bool reflection_then_diffraction = max_order >= 2 && settings.diffraction && !edges_.empty();
  std::vector<std::array<std::size_t, 2>> diffracted_kept(n_sat, {0, 0});  // without, with a reflection
  std::vector<Eigen::Vector3d> one(1);
  const auto settle = [&](std::vector<Pending>& candidates, const std::vector<Eigen::Vector3d>& first_directions) {
    const std::vector<RayOutcome> first = scene_->trace(r, first_directions);
    for (std::size_t k = 0; k < candidates.size(); ++k) {
      Pending& p = candidates[k];
      const RayOutcome& o = first[k];
      if (o.blocked && o.blocking_distance_m < p.first_leg_m - leg_tolerance_m(p.first_leg_m)) {
        if (reflection_then_diffraction && p.facet && o.blocking_distance_m <= settings.radius_m) {
          const auto it = object_index_.find(std::string(o.blocking_object));
          if (it != object_index_.end()) hidden_reflections.push_back(HiddenReflection{p.satellite, *p.facet, it->second});
        }
        continue;
      }
      const std::size_t diffraction_kind = p.path.reflections > 0 ? 1 : 0;
      if (p.path.type == PathType::kDiffracted && diffracted_kept[p.satellite][diffraction_kind] >= kMaxDiffractedPaths) continue;
      double vegetation_db = o.vegetation_attenuation_db;
      bool clear = true;
      for (const Leg& leg : p.legs) {
        one[0] = leg.direction;
        const RayOutcome lo = scene_->trace(leg.origin_m, one).front();
        if (lo.blocked && (std::isinf(leg.length_m) || lo.blocking_distance_m < leg.length_m - leg_tolerance_m(leg.length_m))) {
          clear = false;
          break;
        }
        vegetation_db += lo.vegetation_attenuation_db;
      }
      if (!clear) continue;
      const double factor = amplitude_factor(vegetation_db);
      p.path.rhcp_amplitude *= factor;
      p.path.lhcp_amplitude *= factor;
      p.path.vegetation_attenuation_db = vegetation_db;
      if (p.path.power_linear() < min_power) continue;
      // Facets split at a shared triangle edge can both claim the same point.
      auto& list = out[p.satellite].paths;
      const bool duplicate = std::any_of(list.begin(), list.end(), [&](const SignalPath& q) {
        return q.type == p.path.type && q.reflections == p.path.reflections && (q.point_m - p.path.point_m).norm() < 1e-3;
      });
      if (duplicate) continue;
      if (p.path.type == PathType::kDiffracted) ++diffracted_kept[p.satellite][diffraction_kind];
      list.push_back(std::move(p.path));
    }
  };
  settle(pending, first_legs);

  // Second order: a reflection off the facet, then a diffraction over an edge of the object that
  // hid the reflection point from the receiver (a signal round a corner or over a low building
  // after a facade). The reflected wave is a plane wave from the satellite's direction mirrored
  // in the facet: the knife edge is the receiver's over that direction, and the reflection point
  // is where the ray from the edge point back along it meets the facet.
  std::vector<Pending> second_round;
  std::vector<Eigen::Vector3d> second_first_legs;
  for (const HiddenReflection& hidden : hidden_reflections) {
    const std::size_t i = hidden.satellite;
    const Eigen::Vector3d& s = directions[i];
    const NearFacet& nf = near_facets[hidden.facet];
    const Facet& f = facets_[nf.index];
    const double ns = nf.normal.dot(s);
    const Eigen::Vector3d mirrored = s - 2.0 * ns * nf.normal;
    const double plane = nf.normal.dot(r) - nf.height_m;  // nf.normal . x = plane (the receiver's side lit)
    std::vector<EdgeHit> found;
    for (const EdgeCluster& cluster : object_clusters_[hidden.object]) {
      if (!may_reach_line(r, mirrored, blocked_excess_max_m, cluster.centre_m, cluster.radius_m)) continue;
      for_each_edge_keller_may_hit(object_edge_arrays_[hidden.object], cluster.begin, cluster.end, r, mirrored, [&](std::size_t k) {
        const std::size_t e = object_edges_[hidden.object][k];
        const DiffractionEdge& edge = edges_[e];
        // On the object's outline as the reflected wave sees it.
        if (edge.face_normal_a.dot(mirrored) * edge.face_normal_b.dot(mirrored) > 0.0) return;
        if (!may_reach_line(r, mirrored, blocked_excess_max_m, edge.midpoint_m, edge.half_length_m)) return;
        const std::optional<Eigen::Vector3d> keller = keller_point(edge, r, mirrored);
        if (!keller) return;
        const Eigen::Vector3d& q = *keller;
        const double d2 = (q - r).norm();
        if (d2 < 1e-3 || d2 > settings.radius_m || (q - r).dot(mirrored) <= 0.0) return;
        // The receiver in the edge's shadow, the edge on the facet's lit side.
        if ((r + (q - r).dot(mirrored) * mirrored - q).dot(edge.outward) >= 0.0) return;
        if (nf.normal.dot(q) - plane <= 1e-6) return;
        const double excess = d2 - mirrored.dot(q - r);
        if (excess > blocked_excess_max_m) return;
        const double v = std::sqrt(4.0 * std::max(excess, 0.0) / wavelength_m);
        found.push_back(EdgeHit{e, q, excess, v, knife_edge_loss_db(v)});
      });
    }
    std::sort(found.begin(), found.end(), [](const EdgeHit& a, const EdgeHit& b) { return a.loss_db < b.loss_db; });
    if (found.size() > 4 * kMaxDiffractedPaths) found.resize(4 * kMaxDiffractedPaths);
    for (const EdgeHit& hit : found) {
      const Eigen::Vector3d& q = hit.point_m;
      const double back_m = (nf.normal.dot(q) - plane) / ns;  // from the edge back to the facet
      const Eigen::Vector3d point = q + back_m * mirrored;
      if ((point - f.centre_m).squaredNorm() > f.radius_m * f.radius_m || !f.contains(point)) continue;
      if ((point - r).norm() > settings.radius_m) continue;
      const DiffractionEdge& edge = edges_[hit.edge];
      const double d2 = (q - r).norm();
      const Eigen::Vector3d toward = (q - r) / d2;
      Pending p;
      p.satellite = i;
      p.path.type = PathType::kDiffracted;
      p.path.reflections = 1;
      // The edge's excess over the mirrored direction plus the reflection's own, 2 h (n . s).
      p.path.excess_delay_m = hit.excess_m + 2.0 * nf.height_m * ns;
      p.path.diffraction_v = hit.v;
      p.path.diffraction_loss_db = hit.loss_db;
      p.path.rhcp_amplitude = 1.0;
      p.path.lhcp_amplitude = 0.0;
      reflect_state(p.path.rhcp_amplitude, p.path.lhcp_amplitude, fresnel_coefficients(nf.eta, ns));
      const std::complex<double> knife = std::polar(std::pow(10.0, -hit.loss_db / 20.0), -std::numbers::pi / 4.0);
      p.path.rhcp_amplitude *= knife * specular_factor;
      p.path.lhcp_amplitude *= knife * specular_factor;
      if (p.path.power_linear() < min_power) continue;
      p.path.arrival_direction = toward;
      p.path.point_m = q;
      p.path.second_point_m = point;
      p.path.material = edge.material;
      p.path.object = object_names_[edge.object];
      // excess = |q - r| - s'.(q - r) + 2 (n . s)(n . r - c), s' = s - 2 (n . s) n.
      p.path.delay_gradient_origin = s - toward;
      p.path.delay_gradient_direction = -((q - r) - 2.0 * nf.normal.dot(q - r) * nf.normal) + 2.0 * nf.height_m * nf.normal;
      p.first_leg_m = d2;
      p.legs.push_back(Leg{q + kEdgeOffset_m * edge.outward, mirrored, back_m});
      p.legs.push_back(Leg{point + kSurfaceOffset_m * nf.normal, s, kInf});
      second_first_legs.push_back(toward);
      second_round.push_back(std::move(p));
    }
  }
  if (!second_round.empty()) settle(second_round, second_first_legs);
  sort_indirect_paths_by_power(out);
  return out;
}

}  // namespace skytrace::world
