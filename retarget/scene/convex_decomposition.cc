#include "retarget/scene/convex_decomposition.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <array>
#include <map>
#include <limits>
#include <random>
#include <tuple>

#include <hacdHACD.h>
extern "C" {
#include <libqhull_r/qhull_ra.h>
}
#include <spdlog/spdlog.h>

#include "core/error.h"
#include "recon/ray_caster.h"

namespace doasido::retarget {
namespace {

// Parity test: a ray from p crosses a closed mesh an odd number of times
// exactly when p is inside. The ray is tilted slightly to avoid edges.
bool InsideSolid(const recon::RayCaster& solid, const Vec3& p) {
  return solid.Crossings(p, Vec3(1.0, 0.0123, 0.0071)) % 2 == 1;
}

// Fraction of random points of `hull` that lie inside the closed mesh
// `solid`.
double SolidFraction(const recon::RayCaster& solid, const TriMesh& hull, std::mt19937& rng) {
  const Vec3 lo = hull.Min(), hi = hull.Max();
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int in_hull = 0, inside = 0;
  for (int i = 0; i < 800 && in_hull < 96; ++i) {
    const Vec3 p = lo + Vec3(unit(rng), unit(rng), unit(rng)).cwiseProduct(hi - lo);
    if (!InsideHull(hull, p)) continue;
    ++in_hull;
    inside += InsideSolid(solid, p);
  }
  return in_hull ? static_cast<double>(inside) / in_hull : 1.0;
}

// Connected pieces of the triangles `tris` (sharing a vertex connects).
std::vector<std::vector<int>> Components(const TriMesh& mesh, const std::vector<int>& tris) {
  std::map<int, int> parent;  // over vertex ids
  std::function<int(int)> find = [&](int v) {
    auto it = parent.find(v);
    if (it == parent.end()) return parent[v] = v;
    return it->second == v ? v : it->second = find(it->second);
  };
  for (int f : tris) {
    const int a = find(mesh.faces(f, 0));
    parent[find(mesh.faces(f, 1))] = a;
    parent[find(mesh.faces(f, 2))] = a;
  }
  std::map<int, std::vector<int>> groups;
  for (int f : tris) groups[find(mesh.faces(f, 0))].push_back(f);
  std::vector<std::vector<int>> out;
  for (auto& [root, group] : groups) out.push_back(std::move(group));
  return out;
}

}  // namespace

bool InsideHull(const TriMesh& hull, const Vec3& p) {
  for (int f = 0; f < hull.num_faces(); ++f) {
    const Vec3 a = hull.vertices.row(hull.faces(f, 0)).transpose();
    const Vec3 b = hull.vertices.row(hull.faces(f, 1)).transpose();
    const Vec3 c = hull.vertices.row(hull.faces(f, 2)).transpose();
    if ((b - a).cross(c - a).dot(p - a) > 0) return false;
  }
  return true;
}

// Greedy bottom-up merging of neighbouring hulls whose joint hull stays
// solid (>= 90% inside the mesh, at most 15% more volume than the two),
// smallest hulls first, until no merge is left or `max_hulls` is reached.
static void MergeHulls(const recon::RayCaster& solid, const DecompositionConfig& config, std::mt19937& rng,
                std::vector<TriMesh>& hulls, std::vector<std::vector<Vec3>>& points) {
  const double gap = 0.002;
  for (int pass = 0; pass < 16; ++pass) {
    bool merged_any = false;
    std::vector<int> order(hulls.size());
    for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
    std::sort(order.begin(), order.end(),
              [&](int a, int b) { return hulls[a].Volume() < hulls[b].Volume(); });
    std::vector<bool> gone(hulls.size(), false);
    int alive = static_cast<int>(hulls.size());
    for (int i : order) {
      if (gone[i]) continue;
      const Vec3 lo = hulls[i].Min() - Vec3::Constant(gap), hi = hulls[i].Max() + Vec3::Constant(gap);
      const double vi = hulls[i].Volume();
      int best = -1;
      double best_extra = std::numeric_limits<double>::infinity();
      TriMesh best_hull;
      for (size_t j = 0; j < hulls.size(); ++j) {
        if (static_cast<int>(j) == i || gone[j]) continue;
        if ((hulls[j].Min().array() > hi.array()).any() || (hulls[j].Max().array() < lo.array()).any()) {
          continue;
        }
        std::vector<Vec3> joint = points[i];
        joint.insert(joint.end(), points[j].begin(), points[j].end());
        TriMesh h = ConvexHull(joint);
        if (h.num_faces() < 4) continue;
        const double extra = h.Volume() - vi - hulls[j].Volume();
        if (h.Volume() > 1.15 * (vi + hulls[j].Volume()) || extra >= best_extra) continue;
        if (SolidFraction(solid, h, rng) < config.min_solidity) continue;
        best = static_cast<int>(j);
        best_extra = extra;
        best_hull = std::move(h);
      }
      if (best < 0) continue;
      hulls[i] = std::move(best_hull);
      points[i].insert(points[i].end(), points[best].begin(), points[best].end());
      gone[best] = true;
      merged_any = true;
      if (--alive <= config.max_hulls) break;
    }
    std::vector<TriMesh> kept;
    std::vector<std::vector<Vec3>> kept_points;
    for (size_t i = 0; i < hulls.size(); ++i) {
      if (gone[i]) continue;
      kept.push_back(std::move(hulls[i]));
      kept_points.push_back(std::move(points[i]));
    }
    hulls = std::move(kept);
    points = std::move(kept_points);
    if (!merged_any || static_cast<int>(hulls.size()) <= config.max_hulls) break;
  }
}

TriMesh ConvexHull(const std::vector<Vec3>& points) {
  if (points.size() < 4) return {};
  std::vector<coordT> coords;
  coords.reserve(3 * points.size());
  for (const Vec3& p : points) coords.insert(coords.end(), {p.x(), p.y(), p.z()});
  qhT qh_storage;
  qhT* qh = &qh_storage;
  // Qhull reports flat input (a planar patch) on its error stream; flat
  // patches are expected here and simply yield no hull.
  static FILE* quiet = std::fopen("/dev/null", "w");
  FILE* errors = quiet ? quiet : stderr;
  qh_zero(qh, errors);
  // Qt: triangulated output; QJ would jiggle points, not needed for hulls.
  char options[] = "qhull Qt";
  const int status = qh_new_qhull(qh, 3, static_cast<int>(points.size()), coords.data(), False,
                                  options, nullptr, errors);
  TriMesh out;
  if (status == 0) {
    std::map<int, int> remap;
    std::vector<Vec3> verts;
    std::vector<Eigen::Vector3i> faces;
    facetT* facet;
    FORALLfacets {
      int ids[3];
      int k = 0;
      vertexT *vertex, **vertexp;
      FOREACHvertex_(facet->vertices) {
        if (k < 3) ids[k] = qh_pointid(qh, vertex->point);
        ++k;
      }
      if (k != 3) continue;
      for (int& id : ids) {
        auto [it, inserted] = remap.emplace(id, static_cast<int>(verts.size()));
        if (inserted) verts.push_back(points[id]);
        id = it->second;
      }
      const Vec3 n(facet->normal[0], facet->normal[1], facet->normal[2]);
      if ((verts[ids[1]] - verts[ids[0]]).cross(verts[ids[2]] - verts[ids[0]]).dot(n) < 0) {
        std::swap(ids[1], ids[2]);
      }
      faces.emplace_back(ids[0], ids[1], ids[2]);
    }
    out.vertices.resize(static_cast<int>(verts.size()), 3);
    for (size_t i = 0; i < verts.size(); ++i) out.vertices.row(i) = verts[i].transpose();
    out.faces.resize(static_cast<int>(faces.size()), 3);
    for (size_t i = 0; i < faces.size(); ++i) out.faces.row(i) = faces[i].transpose();
  }
  qh_freeqhull(qh, !qh_ALL);
  int curlong = 0, totlong = 0;
  qh_memfreeshort(qh, &curlong, &totlong);
  return out;
}

bool IsClosed(const TriMesh& mesh) {
  std::map<std::pair<int, int>, int> directed;
  for (int f = 0; f < mesh.num_faces(); ++f) {
    for (int k = 0; k < 3; ++k) ++directed[{mesh.faces(f, k), mesh.faces(f, (k + 1) % 3)}];
  }
  for (const auto& [edge, count] : directed) {
    if (count != 1) return false;
    auto twin = directed.find({edge.second, edge.first});
    if (twin == directed.end() || twin->second != 1) return false;
  }
  return !directed.empty();
}

TriMesh WeldVertices(const TriMesh& mesh) {
  std::map<std::array<double, 3>, int> index;
  std::vector<int> remap(mesh.num_vertices());
  TriMesh out;
  std::vector<Vec3> kept;
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    const std::array<double, 3> key{mesh.vertices(v, 0), mesh.vertices(v, 1), mesh.vertices(v, 2)};
    const auto [it, inserted] = index.emplace(key, static_cast<int>(kept.size()));
    if (inserted) kept.push_back(mesh.vertices.row(v).transpose());
    remap[v] = it->second;
  }
  std::vector<Eigen::Vector3i> faces;
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const Eigen::Vector3i t(remap[mesh.faces(f, 0)], remap[mesh.faces(f, 1)], remap[mesh.faces(f, 2)]);
    if (t[0] != t[1] && t[1] != t[2] && t[0] != t[2]) faces.push_back(t);
  }
  out.vertices.resize(static_cast<int>(kept.size()), 3);
  for (size_t i = 0; i < kept.size(); ++i) out.vertices.row(i) = kept[i].transpose();
  out.faces.resize(static_cast<int>(faces.size()), 3);
  for (size_t i = 0; i < faces.size(); ++i) out.faces.row(i) = faces[i].transpose();
  return out;
}

TriMesh ClusterVertices(const TriMesh& mesh, double cell) {
  std::map<std::tuple<long, long, long>, int> index;
  std::vector<Vec3> sum;
  std::vector<int> count;
  std::vector<int> remap(mesh.num_vertices());
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    const Vec3 p = mesh.vertices.row(v).transpose();
    const auto key = std::make_tuple(std::lround(std::floor(p.x() / cell)),
                                     std::lround(std::floor(p.y() / cell)),
                                     std::lround(std::floor(p.z() / cell)));
    auto [it, inserted] = index.emplace(key, static_cast<int>(sum.size()));
    if (inserted) {
      sum.push_back(Vec3::Zero());
      count.push_back(0);
    }
    sum[it->second] += p;
    ++count[it->second];
    remap[v] = it->second;
  }
  std::vector<Eigen::Vector3i> faces;
  std::map<std::tuple<int, int, int>, bool> seen;
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const int a = remap[mesh.faces(f, 0)], b = remap[mesh.faces(f, 1)], c = remap[mesh.faces(f, 2)];
    if (a == b || b == c || a == c) continue;
    std::array<int, 3> s{a, b, c};
    std::sort(s.begin(), s.end());
    if (!seen.emplace(std::make_tuple(s[0], s[1], s[2]), true).second) continue;
    faces.emplace_back(a, b, c);
  }
  TriMesh out;
  out.vertices.resize(static_cast<int>(sum.size()), 3);
  for (size_t i = 0; i < sum.size(); ++i) out.vertices.row(i) = (sum[i] / count[i]).transpose();
  out.faces.resize(static_cast<int>(faces.size()), 3);
  for (size_t i = 0; i < faces.size(); ++i) out.faces.row(i) = faces[i].transpose();
  return out;
}

// HACD's clusters of `input`'s triangles (one list of triangle ids each).
static std::vector<std::vector<int>> HacdPatches(const TriMesh& input, const DecompositionConfig& config) {
  std::vector<HACD::Vec3<HACD::Real>> hacd_points(input.num_vertices());
  for (int v = 0; v < input.num_vertices(); ++v) {
    hacd_points[v] = HACD::Vec3<HACD::Real>(input.vertices(v, 0), input.vertices(v, 1), input.vertices(v, 2));
  }
  std::vector<HACD::Vec3<long>> triangles(input.num_faces());
  for (int f = 0; f < input.num_faces(); ++f) {
    triangles[f] = HACD::Vec3<long>(input.faces(f, 0), input.faces(f, 1), input.faces(f, 2));
  }
  HACD::HACD hacd;
  hacd.SetPoints(hacd_points.data());
  hacd.SetNPoints(hacd_points.size());
  hacd.SetTriangles(triangles.data());
  hacd.SetNTriangles(triangles.size());
  hacd.SetCompacityWeight(0.1);
  hacd.SetVolumeWeight(0.0);
  hacd.SetNClusters(static_cast<size_t>(std::max(1, config.min_hulls)));
  hacd.SetNVerticesPerCH(static_cast<size_t>(config.max_vertices_per_hull));
  // HACD normalises the mesh so that its bounding box fits the scale factor;
  // with the factor at 1 the concavity bound is a fraction of the box.
  hacd.SetScaleFactor(1.0);
  hacd.SetConcavity(config.concavity);
  hacd.SetAddExtraDistPoints(false);
  hacd.SetAddNeighboursDistPoints(false);
  hacd.SetAddFacesPoints(false);
  if (!hacd.Compute()) throw Error("bad_mesh", "HACD convex decomposition failed");
  const long* partition = hacd.GetPartition();
  const size_t clusters = hacd.GetNClusters();
  std::vector<std::vector<int>> patches(clusters);
  for (int f = 0; f < input.num_faces(); ++f) {
    const long c = partition[f];
    if (c >= 0 && static_cast<size_t>(c) < clusters) patches[c].push_back(f);
  }
  return patches;
}

namespace {

// The steps of ConvexDecomposition.

// The welded mesh, clustered (the cell halved until it fits) when it has
// more triangles than the budget.
TriMesh BudgetedInput(const TriMesh& mesh, const DecompositionConfig& config) {
  const double diagonal = (mesh.Max() - mesh.Min()).norm();
  TriMesh input = WeldVertices(mesh);
  if (input.num_faces() <= config.max_input_triangles) return input;
  double cell = diagonal / 20;
  TriMesh best = ClusterVertices(input, cell);
  for (int i = 0; i < 12; ++i) {
    TriMesh finer = ClusterVertices(input, cell * 0.8);
    if (finer.num_faces() > config.max_input_triangles) break;
    best = std::move(finer);
    cell *= 0.8;
  }
  return best;
}

// The surface patches to make solid: HACD's clusters, or the whole mesh.
std::vector<std::vector<int>> InitialPatches(const TriMesh& input, const DecompositionConfig& config) {
  std::vector<std::vector<int>> patches;
  if (config.method == "hacd") {
    patches = HacdPatches(input, config);
  } else if (config.method == "split") {
    patches.emplace_back(input.num_faces());
    for (int f = 0; f < input.num_faces(); ++f) patches.back()[f] = f;
  } else {
    throw Error("bad_config", "decomposition method must be \"split\" or \"hacd\"",
                {.field = "decomposition.method"});
  }
  return patches;
}

// Per triangle: its corners, and (for a closed mesh, when solidifying)
// where rays cast into the solid from inside it (against its normal) leave
// the solid again. Rays start inside the triangle: from a corner they would
// graze the neighbouring faces (a rim edge) and cross the cavity.
std::vector<std::vector<Vec3>> SolidPoints(const TriMesh& input, const recon::RayCaster& caster,
                                           bool solidify) {
  std::vector<std::vector<Vec3>> solid_points(input.num_faces());
  for (int f = 0; f < input.num_faces(); ++f) {
    const Vec3 a = input.vertices.row(input.faces(f, 0)).transpose();
    const Vec3 b = input.vertices.row(input.faces(f, 1)).transpose();
    const Vec3 d = input.vertices.row(input.faces(f, 2)).transpose();
    const Vec3 n = (b - a).cross(d - a);
    if (n.norm() < 1e-18) continue;
    const Vec3 c = (a + b + d) / 3;
    solid_points[f] = {a, b, d};
    if (!solidify) continue;
    for (const Vec3& p : {c, Vec3(c + 0.8 * (a - c)), Vec3(c + 0.8 * (b - c)),
                          Vec3(c + 0.8 * (d - c))}) {
      // t_min steps off triangle f itself.
      if (const auto t = caster.FirstHit(p, -n, 1e-6)) solid_points[f].push_back(p - *t * n.normalized());
    }
  }
  return solid_points;
}

// The hull of a patch's solid points. A flat patch (a mug's bottom disc)
// has no volume: it gets 1 mm of thickness into the solid (added to
// `points`), so it still becomes a collision piece. Empty when the patch
// has no area.
TriMesh PatchHull(const TriMesh& input, const std::vector<int>& tris, std::vector<Vec3>& points) {
  TriMesh h = ConvexHull(points);
  if (h.num_faces() >= 4) return h;
  Vec3 normal = Vec3::Zero();
  for (int f : tris) {
    normal += (Vec3(input.vertices.row(input.faces(f, 1)).transpose()) -
               Vec3(input.vertices.row(input.faces(f, 0)).transpose()))
                  .cross(Vec3(input.vertices.row(input.faces(f, 2)).transpose()) -
                         Vec3(input.vertices.row(input.faces(f, 0)).transpose()));
  }
  if (normal.norm() < 1e-18) return TriMesh();
  const size_t n = points.size();
  for (size_t i = 0; i < n; ++i) points.push_back(points[i] - 0.001 * normal.normalized());
  return ConvexHull(points);
}

// A patch's triangles in two halves along the longest extent of their
// centroids.
std::pair<std::vector<int>, std::vector<int>> SplitPatch(const TriMesh& input,
                                                         const std::vector<int>& tris) {
  Vec3 lo = Vec3::Constant(1e30), hi = Vec3::Constant(-1e30);
  std::vector<std::pair<double, int>> keyed;
  for (int f : tris) {
    const Vec3 c = (Vec3(input.vertices.row(input.faces(f, 0)).transpose()) +
                    Vec3(input.vertices.row(input.faces(f, 1)).transpose()) +
                    Vec3(input.vertices.row(input.faces(f, 2)).transpose())) / 3;
    lo = lo.cwiseMin(c);
    hi = hi.cwiseMax(c);
  }
  int axis = 0;
  (hi - lo).maxCoeff(&axis);
  for (int f : tris) {
    const double c = (input.vertices(input.faces(f, 0), axis) +
                      input.vertices(input.faces(f, 1), axis) +
                      input.vertices(input.faces(f, 2), axis)) / 3;
    keyed.emplace_back(c, f);
  }
  std::sort(keyed.begin(), keyed.end());
  std::pair<std::vector<int>, std::vector<int>> halves;
  for (size_t i = 0; i < keyed.size(); ++i) {
    (i < keyed.size() / 2 ? halves.first : halves.second).push_back(keyed[i].second);
  }
  return halves;
}

}  // namespace

std::vector<TriMesh> ConvexDecomposition(const TriMesh& mesh, const DecompositionConfig& config) {
  if (mesh.num_faces() == 0) throw Error("bad_mesh", "empty mesh has no convex decomposition");
  const TriMesh input = BudgetedInput(mesh, config);
  const bool closed = IsClosed(input);
  std::vector<std::vector<int>> patches = InitialPatches(input, config);
  // HACD's clusters are surface patches, and the hull of a patch of a thin
  // wall is a thin plate. Each patch is made solid by adding, for every
  // vertex of its triangles, the point where a ray into the solid (against
  // the face normal) leaves it again: a mug wall patch then spans the wall's
  // thickness. A patch whose solid hull would swallow empty space (a flat
  // rim ring spans the mug's opening) is split in two along its longest
  // extent until its hull is at least 90% solid.
  const recon::RayCaster caster(input.vertices, input.faces);
  const std::vector<std::vector<Vec3>> solid_points =
      SolidPoints(input, caster, closed && config.solidify);
  std::mt19937 rng(1);
  std::vector<TriMesh> hulls;
  std::vector<std::vector<Vec3>> hull_points;
  std::vector<std::pair<std::vector<int>, int>> work;  // (triangles, depth)
  for (auto& p : patches) {
    if (!p.empty()) work.emplace_back(std::move(p), 0);
  }
  while (!work.empty()) {
    auto [tris, depth] = std::move(work.back());
    work.pop_back();
    std::vector<Vec3> points;
    for (int f : tris) points.insert(points.end(), solid_points[f].begin(), solid_points[f].end());
    // A patch made of separate pieces (a slab through both sides of a mug)
    // is first split into its connected pieces.
    std::vector<std::vector<int>> pieces = Components(input, tris);
    if (pieces.size() > 1) {
      for (auto& piece : pieces) work.emplace_back(std::move(piece), depth);
      continue;
    }
    TriMesh h = PatchHull(input, tris, points);
    if (h.num_faces() < 4 || h.Volume() < 1e-12) continue;  // flat sliver
    const bool splittable = tris.size() > 1 && depth < config.max_depth;
    if (closed && splittable && SolidFraction(caster, h, rng) < config.min_solidity) {
      auto [left, right] = SplitPatch(input, tris);
      work.emplace_back(std::move(left), depth + 1);
      work.emplace_back(std::move(right), depth + 1);
      continue;
    }
    hulls.push_back(std::move(h));
    hull_points.push_back(std::move(points));
  }
  if (closed && config.merge) MergeHulls(caster, config, rng, hulls, hull_points);
  if (hulls.empty()) throw Error("bad_mesh", "convex decomposition returned no usable hull");
  spdlog::debug("convex decomposition: {} triangles -> {} hulls", input.num_faces(), hulls.size());
  return hulls;
}

TriMesh DilateConvex(const TriMesh& hull, double distance) {
  const int nv = hull.num_vertices();
  std::vector<Vec3> normal(nv, Vec3::Zero());
  std::vector<std::vector<Vec3>> face_normals(nv);
  for (int f = 0; f < hull.num_faces(); ++f) {
    const Vec3 a = hull.vertices.row(hull.faces(f, 0)).transpose();
    const Vec3 b = hull.vertices.row(hull.faces(f, 1)).transpose();
    const Vec3 c = hull.vertices.row(hull.faces(f, 2)).transpose();
    const Vec3 n = (b - a).cross(c - a);
    if (n.norm() < 1e-18) continue;
    const Vec3 corner[3] = {a, b, c};
    for (int k = 0; k < 3; ++k) {
      // Angle-weighted, so the normal does not depend on the triangulation.
      const Vec3 u = corner[(k + 1) % 3] - corner[k], w = corner[(k + 2) % 3] - corner[k];
      const double angle = std::atan2(u.cross(w).norm(), u.dot(w));
      normal[hull.faces(f, k)] += angle * n.normalized();
      face_normals[hull.faces(f, k)].push_back(n.normalized());
    }
  }
  TriMesh out = hull;
  for (int v = 0; v < nv; ++v) {
    if (normal[v].norm() < 1e-18) continue;
    const Vec3 n = normal[v].normalized();
    double min_cos = 1.0;
    for (const Vec3& nf : face_normals[v]) min_cos = std::min(min_cos, n.dot(nf));
    const double length = distance / std::max(min_cos, 1.0 / 3.0);
    out.vertices.row(v) += (length * n).transpose();
  }
  return out;
}

MassProperties ComputeMassProperties(const TriMesh& mesh) {
  // Eberly, "Polyhedral Mass Properties (Revisited)", 2002.
  double intg[10] = {0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
  auto sub = [](double w0, double w1, double w2, double& f1, double& f2, double& f3, double& g0,
                double& g1, double& g2) {
    const double t0 = w0 + w1, t1 = w0 * w0, t2 = t1 + w1 * t0;
    f1 = t0 + w2;
    f2 = t2 + w2 * f1;
    f3 = w0 * t1 + w1 * t2 + w2 * f2;
    g0 = f2 + w0 * (f1 + w0);
    g1 = f2 + w1 * (f1 + w1);
    g2 = f2 + w2 * (f1 + w2);
  };
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const Vec3 p0 = mesh.vertices.row(mesh.faces(f, 0)).transpose();
    const Vec3 p1 = mesh.vertices.row(mesh.faces(f, 1)).transpose();
    const Vec3 p2 = mesh.vertices.row(mesh.faces(f, 2)).transpose();
    const Vec3 d = (p1 - p0).cross(p2 - p0);
    double f1x, f2x, f3x, g0x, g1x, g2x, f1y, f2y, f3y, g0y, g1y, g2y, f1z, f2z, f3z, g0z, g1z, g2z;
    sub(p0.x(), p1.x(), p2.x(), f1x, f2x, f3x, g0x, g1x, g2x);
    sub(p0.y(), p1.y(), p2.y(), f1y, f2y, f3y, g0y, g1y, g2y);
    sub(p0.z(), p1.z(), p2.z(), f1z, f2z, f3z, g0z, g1z, g2z);
    intg[0] += d.x() * f1x;
    intg[1] += d.x() * f2x;
    intg[2] += d.y() * f2y;
    intg[3] += d.z() * f2z;
    intg[4] += d.x() * f3x;
    intg[5] += d.y() * f3y;
    intg[6] += d.z() * f3z;
    intg[7] += d.x() * (p0.y() * g0x + p1.y() * g1x + p2.y() * g2x);
    intg[8] += d.y() * (p0.z() * g0y + p1.z() * g1y + p2.z() * g2y);
    intg[9] += d.z() * (p0.x() * g0z + p1.x() * g1z + p2.x() * g2z);
  }
  const double mult[10] = {1. / 6, 1. / 24, 1. / 24, 1. / 24, 1. / 60,
                           1. / 60, 1. / 60, 1. / 120, 1. / 120, 1. / 120};
  for (int i = 0; i < 10; ++i) intg[i] *= mult[i];
  MassProperties mp;
  mp.volume = intg[0];
  if (!(mp.volume > 0)) return mp;
  const Vec3 c(intg[1] / mp.volume, intg[2] / mp.volume, intg[3] / mp.volume);
  mp.com = c;
  Mat3& I = mp.inertia;
  I(0, 0) = intg[5] + intg[6] - mp.volume * (c.y() * c.y() + c.z() * c.z());
  I(1, 1) = intg[4] + intg[6] - mp.volume * (c.z() * c.z() + c.x() * c.x());
  I(2, 2) = intg[4] + intg[5] - mp.volume * (c.x() * c.x() + c.y() * c.y());
  I(0, 1) = I(1, 0) = -(intg[7] - mp.volume * c.x() * c.y());
  I(1, 2) = I(2, 1) = -(intg[8] - mp.volume * c.y() * c.z());
  I(0, 2) = I(2, 0) = -(intg[9] - mp.volume * c.z() * c.x());
  return mp;
}

}  // namespace doasido::retarget
