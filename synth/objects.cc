#include "synth/objects.h"

#include <cmath>
#include <limits>
#include <vector>

#include "core/mesh_builder.h"

namespace doasido::synth {
namespace {

constexpr double kPi = 3.14159265358979323846;

using Builder = MeshBuilder;

// A surface of revolution about z from a profile of (radius, z) points;
// each consecutive pair makes a band (a fan where the radius is 0). Bands
// are oriented consistently along the profile; FlipIfInverted fixes the sign.
void Revolve(Builder& b, const std::vector<Vec2>& profile, int seg) {
  std::vector<int> first(profile.size());
  for (size_t i = 0; i < profile.size(); ++i) {
    const double r = profile[i].x(), z = profile[i].y();
    if (r == 0) {
      first[i] = b.Add(Vec3(0, 0, z));
      continue;
    }
    first[i] = static_cast<int>(b.vertices.size());
    for (int k = 0; k < seg; ++k) {
      const double th = 2 * kPi * k / seg;
      b.Add(Vec3(r * std::cos(th), r * std::sin(th), z));
    }
  }
  for (size_t i = 0; i + 1 < profile.size(); ++i) {
    const bool a0 = profile[i].x() == 0, a1 = profile[i + 1].x() == 0;
    for (int k = 0; k < seg; ++k) {
      const int k1 = (k + 1) % seg;
      if (a0 && a1) continue;
      if (a0) {
        b.Tri(first[i], first[i + 1] + k1, first[i + 1] + k);
      } else if (a1) {
        b.Tri(first[i] + k, first[i] + k1, first[i + 1]);
      } else {
        b.Quad(first[i] + k, first[i] + k1, first[i + 1] + k1, first[i + 1] + k);
      }
    }
  }
}

TriMesh FlipIfInverted(TriMesh m) {
  if (m.Volume() < 0) {
    for (int i = 0; i < m.num_faces(); ++i) std::swap(m.faces(i, 1), m.faces(i, 2));
  }
  return m;
}

double PointTriangleDistance(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  // Ericson, Real-Time Collision Detection, 5.1.5 (closest point on triangle).
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return ap.norm();
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return bp.norm();
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return (p - (a + d1 / (d1 - d3) * ab)).norm();
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return cp.norm();
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return (p - (a + d2 / (d2 - d6) * ac)).norm();
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return (p - (b + w * (c - b))).norm();
  }
  const double denom = 1.0 / (va + vb + vc);
  return (p - (a + ab * (vb * denom) + ac * (vc * denom))).norm();
}

}  // namespace

const char* ObjectKindName(ObjectKind kind) {
  switch (kind) {
    case ObjectKind::kBox:
      return "box";
    case ObjectKind::kCylinder:
      return "cylinder";
    case ObjectKind::kSphere:
      return "sphere";
    case ObjectKind::kMug:
      return "mug";
    case ObjectKind::kMeshFile:
      return "mesh";
  }
  return "unknown";
}

void AppendMesh(TriMesh& a, const TriMesh& b) {
  const int nv = a.num_vertices(), nf = a.num_faces();
  a.vertices.conservativeResize(nv + b.num_vertices(), 3);
  a.faces.conservativeResize(nf + b.num_faces(), 3);
  a.vertices.bottomRows(b.num_vertices()) = b.vertices;
  a.faces.bottomRows(b.num_faces()) = b.faces.array() + nv;
}

TriMesh MakeBox(double sx, double sy, double sz) {
  Builder b;
  const double x = sx / 2, y = sy / 2;
  // Each face gets its own four corners so flat shading stays exact.
  auto face = [&](Vec3 p0, Vec3 p1, Vec3 p2, Vec3 p3) {
    const int i = b.Add(p0), j = b.Add(p1), k = b.Add(p2), l = b.Add(p3);
    b.Quad(i, j, k, l);
  };
  face({-x, -y, 0}, {-x, y, 0}, {x, y, 0}, {x, -y, 0});      // bottom (-z)
  face({-x, -y, sz}, {x, -y, sz}, {x, y, sz}, {-x, y, sz});  // top (+z)
  face({-x, -y, 0}, {x, -y, 0}, {x, -y, sz}, {-x, -y, sz});  // -y
  face({x, y, 0}, {-x, y, 0}, {-x, y, sz}, {x, y, sz});      // +y
  face({x, -y, 0}, {x, y, 0}, {x, y, sz}, {x, -y, sz});      // +x
  face({-x, y, 0}, {-x, -y, 0}, {-x, -y, sz}, {-x, y, sz});  // -x
  return FlipIfInverted(b.Mesh());
}

TriMesh MakeCylinder(double r, double h, int segments) {
  Builder b;
  Revolve(b, {{0, 0}, {r, 0}, {r, h}, {0, h}}, segments);
  return FlipIfInverted(b.Mesh());
}

TriMesh MakeSphere(double r, int segments, int rings) {
  std::vector<Vec2> profile;
  for (int i = 0; i <= rings; ++i) {
    const double phi = -kPi / 2 + kPi * i / rings;
    profile.emplace_back(i == 0 || i == rings ? 0.0 : r * std::cos(phi), r + r * std::sin(phi));
  }
  Builder b;
  Revolve(b, profile, segments);
  return FlipIfInverted(b.Mesh());
}

TriMesh MakeMug(double r, double h, double wall, int segments) {
  Builder b;
  // Profile: bottom centre, outside up, rim, inside down to the cavity floor.
  Revolve(b, {{0, 0}, {r, 0}, {r, h}, {r - wall, h}, {r - wall, wall}, {0, wall}}, segments);
  TriMesh mug = FlipIfInverted(b.Mesh());
  // Handle: a torus segment in the xz plane on +x, overlapping the wall.
  Builder t;
  const double R = 0.3 * h, rt = 0.22 * wall + 0.004;
  const Vec3 c(r + 0.25 * R, 0, 0.55 * h);
  const int n_major = 20, n_minor = 10;
  for (int i = 0; i <= n_major; ++i) {
    const double a = -kPi / 2 + kPi * i / n_major;  // half ring on the +x side
    const Vec3 centre = c + R * Vec3(std::cos(a), 0, std::sin(a));
    const Vec3 radial(std::cos(a), 0, std::sin(a));
    for (int k = 0; k < n_minor; ++k) {
      const double th = 2 * kPi * k / n_minor;
      t.Add(centre + rt * (std::cos(th) * radial + std::sin(th) * Vec3::UnitY()));
    }
  }
  for (int i = 0; i < n_major; ++i) {
    for (int k = 0; k < n_minor; ++k) {
      const int k1 = (k + 1) % n_minor;
      t.Quad(i * n_minor + k, (i + 1) * n_minor + k, (i + 1) * n_minor + k1, i * n_minor + k1);
    }
  }
  // Caps at both ends of the tube (they sit inside the wall).
  const int e0 = t.Add(c + R * Vec3(0, 0, -1)), e1 = t.Add(c + R * Vec3(0, 0, 1));
  for (int k = 0; k < n_minor; ++k) {
    const int k1 = (k + 1) % n_minor;
    t.Tri(e0, k, k1);
    t.Tri(e1, n_major * n_minor + k1, n_major * n_minor + k);
  }
  AppendMesh(mug, FlipIfInverted(t.Mesh()));
  return mug;
}

TriMesh MakePlane(double sx, double sy) {
  Builder b;
  const int i = b.Add({-sx / 2, -sy / 2, 0}), j = b.Add({sx / 2, -sy / 2, 0}),
            k = b.Add({sx / 2, sy / 2, 0}), l = b.Add({-sx / 2, sy / 2, 0});
  b.Quad(i, j, k, l);
  return b.Mesh();
}

TriMesh LoadObjectMesh(const std::filesystem::path& path, double scale) {
  TriMesh m = LoadMesh(path, scale);
  const Vec3 lo = m.Min(), hi = m.Max();
  const Vec3 shift(-(lo.x() + hi.x()) / 2, -(lo.y() + hi.y()) / 2, -lo.z());
  for (int i = 0; i < m.num_vertices(); ++i) m.vertices.row(i) += shift.transpose();
  return m;
}

bool InsideMesh(const TriMesh& mesh, const Vec3& p) {
  // Generalised winding number (Jacobson et al. 2013): sum of signed solid
  // angles (Van Oosterom & Strackee) over 4 pi.
  double total = 0;
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const Vec3 a = mesh.vertices.row(mesh.faces(f, 0)).transpose() - p;
    const Vec3 b = mesh.vertices.row(mesh.faces(f, 1)).transpose() - p;
    const Vec3 c = mesh.vertices.row(mesh.faces(f, 2)).transpose() - p;
    const double la = a.norm(), lb = b.norm(), lc = c.norm();
    const double num = a.dot(b.cross(c));
    const double den = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
    total += 2 * std::atan2(num, den);
  }
  return total / (4 * kPi) > 0.5;
}

double DistanceToMesh(const TriMesh& mesh, const Vec3& p) {
  double best = std::numeric_limits<double>::infinity();
  for (int f = 0; f < mesh.num_faces(); ++f) {
    best = std::min(best, PointTriangleDistance(p, mesh.vertices.row(mesh.faces(f, 0)),
                                                mesh.vertices.row(mesh.faces(f, 1)),
                                                mesh.vertices.row(mesh.faces(f, 2))));
  }
  return best;
}

}  // namespace doasido::synth
