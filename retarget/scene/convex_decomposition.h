// Convex decomposition of object meshes for simulation, and the 2 mm
// dilation of seed appendix "Retargeting".
//
// Why not CoACD, as in the seed: no Debian package ships it. Debian ships
// Bullet's HACD (hierarchical approximate convex decomposition, Mamou and
// Ghorbel 2009; libbullet-extras-dev), and method "hacd" uses it: HACD
// clusters the surface into patches whose concavity stays under a bound.
// Measured here, its patches are surface pieces, so their hulls are thin
// plates on thin-walled objects, and it over- or under-segments: the mug
// gives 343 clusters at concavity 0.03 and a hull filling its cavity at
// 0.1; the YCB scans give 250-490 patches at 0.01 and take up to 50 s at
// 0.1. The default, method "split", therefore decomposes top-down with the
// acceptance test below and Qhull hulls (the library MuJoCo uses for mesh
// hulls); with "hacd" the HACD patches are the starting pieces instead of
// the whole mesh.
//
// Acceptance test (both methods): a piece is kept when at least
// min_solidity of its hull lies inside the mesh (sampled, parity ray test);
// otherwise its triangles are split in two at the median along their
// longest extent, and a piece made of separate connected parts is split
// into them first. A flat piece gets 1 mm of thickness into the solid.
// This needs a closed mesh; an open scan (most YCB textured meshes after
// simplification) is taken as one convex hull, which suits the nearly
// convex YCB objects. Meshes are first simplified by vertex clustering to at
// most max_input_triangles.
#pragma once

#include <string>
#include <vector>

#include "core/config.h"
#include "core/mesh.h"

namespace doasido::retarget {

struct DecompositionConfig {
  std::string method = "split";     // "split" (top-down, default) or "hacd" (HACD patches first)
  int max_depth = 8;                // binary splits per patch (at most 2^depth pieces)
  double concavity = 0.03;          // "hacd": max concavity, fraction of the bounding box
  int min_hulls = 1;                // "hacd": stops merging at this many clusters
  int max_vertices_per_hull = 64;   // "hacd": vertex budget of its internal hulls
  int max_input_triangles = 3000;   // vertex-clustering target before decomposing
  int max_hulls = 32;               // merging of neighbouring hulls stops here
  double min_solidity = 0.8;        // fraction of a hull that must lie inside the mesh
  bool solidify = false;            // add where inward rays leave the solid to each piece
                                    // (thick wall pieces; off: rays grazing a rim can
                                    // cross a cavity and fill it)
  bool merge = false;               // greedy merging of neighbouring hulls (slow: O(n^2) hulls)
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(DecompositionConfig, method, max_depth,
                                                concavity, min_hulls, max_vertices_per_hull,
                                                max_input_triangles, max_hulls, min_solidity,
                                                solidify, merge)

// Convex pieces whose union approximates `mesh`. Each hull is a closed
// triangle mesh with outward faces. Throws Error("bad_mesh") for an empty
// mesh or when HACD fails. The mug of mug_mesh.h gives about 200 pieces (its
// thin wall is covered by plates), a YCB scan one.
std::vector<TriMesh> ConvexDecomposition(const TriMesh& mesh, const DecompositionConfig& config = {});

// Convex hull of points (Qhull, the library MuJoCo itself uses for mesh
// hulls; HACD's own incremental hull fails on near-coplanar input). Empty
// when the points are flat or fewer than four.
TriMesh ConvexHull(const std::vector<Vec3>& points);

// True when every edge is shared by exactly two faces with opposite
// directions (a closed, consistently oriented surface).
bool IsClosed(const TriMesh& mesh);

// Whether p lies inside (or on) a convex hull with outward-facing faces.
bool InsideHull(const TriMesh& hull, const Vec3& p);

// Merges vertices at identical coordinates (a mesh built with a copy of
// each corner per face, for flat shading, is closed only once welded) and
// drops the triangles that collapse. Files read through core/mesh.h come
// welded already.
TriMesh WeldVertices(const TriMesh& mesh);

// Simplifies by snapping vertices to a grid of `cell` metres, merging
// vertices in one cell (at their mean) and dropping collapsed triangles.
TriMesh ClusterVertices(const TriMesh& mesh, double cell);

// Offsets a convex hull outward by `distance`: each vertex moves along its
// angle-weighted vertex normal n by distance / min_f(n . n_f) over its faces
// f, so every face plane moves out by at least `distance` (exactly for faces
// meeting at a box corner), i.e. the hull grows by a 2 mm skin as in the seed,
// rather than scaling about the centroid, which would thicken long objects
// unevenly.
TriMesh DilateConvex(const TriMesh& hull, double distance);

// Mass properties of a closed, outward-oriented triangle mesh of unit
// density (Eberly's polyhedral mass properties): volume, centre of mass and
// inertia about the centre of mass.
struct MassProperties {
  double volume = 0;
  Vec3 com = Vec3::Zero();
  Mat3 inertia = Mat3::Zero();  // per unit density
};
MassProperties ComputeMassProperties(const TriMesh& mesh);

}  // namespace doasido::retarget
