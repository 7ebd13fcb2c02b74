// Objects of the synthetic world as closed, outward-oriented triangle meshes
// in object-local metres: the local frame has +z up and the object resting on
// z = 0 (its lowest point), centred on the z axis, so that "on the table"
// means object pose = translation on the table plane.
#pragma once

#include <filesystem>
#include <string>

#include "core/mesh.h"

namespace doasido::synth {

// Axis-aligned box with the given full extents.
TriMesh MakeBox(double sx, double sy, double sz);
// Vertical cylinder, radius r, height h, `segments` around.
TriMesh MakeCylinder(double r, double h, int segments = 32);
// Sphere of radius r (UV sphere).
TriMesh MakeSphere(double r, int segments = 24, int rings = 16);
// A mug: cylindrical wall of outer radius r and thickness `wall`, closed
// bottom of the same thickness, open top (the cavity is part of the closed
// surface), and a ring handle on +x.
TriMesh MakeMug(double r, double h, double wall = 0.006, int segments = 32);
// A horizontal rectangle z = 0 centred at the origin, normal +z (two faces).
TriMesh MakePlane(double sx, double sy);
// A mesh file (assimp), translated so that it is centred on z and rests on z=0.
TriMesh LoadObjectMesh(const std::filesystem::path& path, double scale = 1.0);

// Appends b's vertices and faces to a.
void AppendMesh(TriMesh& a, const TriMesh& b);

// Object kinds the generator draws from.
enum class ObjectKind { kBox, kCylinder, kSphere, kMug, kMeshFile };
const char* ObjectKindName(ObjectKind kind);

// Whether `p` (object-local) is strictly inside the closed mesh (generalised
// winding number > 0.5).
bool InsideMesh(const TriMesh& mesh, const Vec3& p);
// Unsigned distance from `p` to the mesh surface.
double DistanceToMesh(const TriMesh& mesh, const Vec3& p);

}  // namespace doasido::synth
