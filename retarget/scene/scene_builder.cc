#include "retarget/scene/scene_builder.h"

#include <cmath>
#include <fstream>
#include <sstream>

#include <Eigen/Eigenvalues>
#include <spdlog/spdlog.h>

#include "core/error.h"
#include "robot/mj_model.h"
#include "robot/mjcf_compat.h"
#include "robot/trajectory/format.h"

namespace doasido::retarget {
namespace {

std::string Num(double v) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.9g", v);
  return buf;
}

std::string Vec(const Vec3& v) { return Num(v.x()) + " " + Num(v.y()) + " " + Num(v.z()); }

std::string QuatStr(const Quat& q) {
  return Num(q.w()) + " " + Num(q.x()) + " " + Num(q.y()) + " " + Num(q.z());
}

bool PositiveDefinite(const Mat3& m) {
  Eigen::SelfAdjointEigenSolver<Mat3> es(m);
  return es.eigenvalues().minCoeff() > 0;
}

// Volume-weighted union of convex pieces (overlaps counted twice; HACD's
// undilated hulls barely overlap).
MassProperties Combine(const std::vector<TriMesh>& hulls) {
  std::vector<MassProperties> parts;
  MassProperties total;
  for (const TriMesh& h : hulls) {
    parts.push_back(ComputeMassProperties(h));
    total.volume += parts.back().volume;
    total.com += parts.back().volume * parts.back().com;
  }
  total.com /= total.volume;
  for (const MassProperties& p : parts) {
    const Vec3 d = p.com - total.com;
    total.inertia += p.inertia + p.volume * (d.squaredNorm() * Mat3::Identity() - d * d.transpose());
  }
  return total;
}

// The steps of BuildObjectScene.

// Mass, centre of mass and inertia at `config.density`: of the mesh itself
// when it is closed, else of the hulls.
void SetMassProperties(const TriMesh& mesh, const std::vector<TriMesh>& hulls,
                       const SceneConfig& config, ObjectScene& scene) {
  MassProperties mp;
  if (const TriMesh welded = WeldVertices(mesh); IsClosed(welded)) mp = ComputeMassProperties(welded);
  if (!(mp.volume > 0) || !PositiveDefinite(mp.inertia)) {
    mp = Combine(hulls);
    scene.inertia_from_hulls = true;
  }
  scene.volume = mp.volume;
  scene.mass = config.density * mp.volume;
  scene.com = mp.com;
  scene.inertia = config.density * mp.inertia;
}

// World-frame extent of the dilated object at `pose`, for the plate and
// the placement.
struct Extent {
  Vec3 lo = Vec3::Constant(1e30), hi = Vec3::Constant(-1e30);
};

Extent WorldExtent(const std::vector<TriMesh>& dilated, const Pose& pose) {
  Extent e;
  for (const TriMesh& h : dilated) {
    for (int v = 0; v < h.num_vertices(); ++v) {
      const Vec3 w = pose * Vec3(h.vertices.row(v).transpose());
      e.lo = e.lo.cwiseMin(w);
      e.hi = e.hi.cwiseMax(w);
    }
  }
  return e;
}

// Writes the scene's MJCF with the object at `at` (and, the first time,
// its hull meshes); `shift` is how far placing it on the floor raised it.
void WriteSceneXml(const std::vector<TriMesh>& dilated, const SceneConfig& config,
                   const std::filesystem::path& out_dir, const Extent& extent, double shift,
                   const Pose& at, ObjectScene& scene) {
  const Vec3& lo = extent.lo;
  const Vec3& hi = extent.hi;
  std::ostringstream xml;
  xml << "<mujoco model=\"doasido_object_scene\">\n"
      << "  <option timestep=\"" << Num(config.timestep)
      << "\" integrator=\"implicit\" cone=\"elliptic\" impratio=\"10\"/>\n"
      << "  <asset>\n";
  for (size_t i = 0; i < dilated.size(); ++i) {
    const std::string name = (i < 10 ? "object_hull_0" : "object_hull_") + std::to_string(i);
    const std::string file = name + ".obj";
    if (scene.hull_files.size() < dilated.size()) {
      SaveObj(dilated[i], out_dir / file);
      scene.hull_files.push_back(file);
    }
    xml << "    <mesh name=\"" << name << "\" file=\"" << file << "\"/>\n";
  }
  const std::string contact = " condim=\"" + std::to_string(config.condim) + "\" friction=\"" +
                              Num(config.friction[0]) + " " + Num(config.friction[1]) + " " +
                              Num(config.friction[2]) + "\" solref=\"" + Num(config.solref[0]) +
                              " " + Num(config.solref[1]) + "\" solimp=\"" +
                              Num(config.solimp[0]) + " " + Num(config.solimp[1]) + " " +
                              Num(config.solimp[2]) + "\"";
  const Mat3& I = scene.inertia;
  xml << "  </asset>\n  <worldbody>\n"
      << "    <geom name=\"floor\" type=\"plane\" size=\"0 0 0.05\" contype=\"3\" conaffinity=\"3\""
      << contact << "/>\n"
      << "    <body name=\"object\" pos=\"" << Vec(at.t) << "\" quat=\""
      << QuatStr(at.q) << "\">\n"
      << "      <freejoint name=\"object_free\"/>\n"
      << "      <inertial pos=\"" << Vec(scene.com) << "\" mass=\"" << Num(scene.mass)
      << "\" fullinertia=\"" << Num(I(0, 0)) << " " << Num(I(1, 1)) << " " << Num(I(2, 2)) << " "
      << Num(I(0, 1)) << " " << Num(I(0, 2)) << " " << Num(I(1, 2)) << "\"/>\n";
  for (size_t i = 0; i < dilated.size(); ++i) {
    xml << "      <geom name=\"object_hull_" << (i < 10 ? "0" : "") << i << "\" type=\"mesh\" mesh=\""
        << scene.hull_files[i].substr(0, scene.hull_files[i].size() - 4)
        << "\" contype=\"1\" conaffinity=\"1\" group=\"3\"" << contact << "/>\n";
  }
  if (config.base_plate) {
    // A world-horizontal slab under the object's footprint, in body coordinates.
    const Vec3 centre_world(0.5 * (lo.x() + hi.x()), 0.5 * (lo.y() + hi.y()),
                            lo.z() + shift - 0.5 * config.plate_thickness);
    const Quat body_q = scene.pose.q.conjugate();
    const Vec3 centre_body = body_q * (centre_world - scene.pose.t);
    xml << "      <geom name=\"object_base_plate\" type=\"box\" size=\""
        << Vec(Vec3(0.5 * (hi.x() - lo.x()), 0.5 * (hi.y() - lo.y()), 0.5 * config.plate_thickness))
        << "\" pos=\"" << Vec(centre_body) << "\" quat=\"" << QuatStr(body_q)
        << "\" contype=\"2\" conaffinity=\"2\" group=\"3\"" << contact << "/>\n";
  }
  xml << "    </body>\n  </worldbody>\n</mujoco>\n";
  scene.xml_path = out_dir / kSceneFile;
  std::ofstream out(scene.xml_path);
  out << xml.str();
  if (!out) throw Error("io", "cannot write scene", {.file = scene.xml_path.string()});
}

// The object's pose after `seconds` of simulation of the scene at
// `xml_path`, which let it settle on the floor.
Pose SettledPose(const std::filesystem::path& xml_path, double seconds) {
  ModelPtr m = CompileMjcfText(PrepareMjcf(xml_path).xml, xml_path.string());
  DataPtr d = MakeData(m.get());
  const int steps = static_cast<int>(std::lround(seconds / m->opt.timestep));
  for (int i = 0; i < steps; ++i) mj_step(m.get(), d.get());
  const int body = NameToId(m.get(), mjOBJ_BODY, "object");
  return {Quat(d->xquat[4 * body], d->xquat[4 * body + 1], d->xquat[4 * body + 2],
               d->xquat[4 * body + 3]).normalized(),
          Vec3(d->xpos[3 * body], d->xpos[3 * body + 1], d->xpos[3 * body + 2])};
}

}  // namespace

ObjectScene BuildObjectScene(const TriMesh& mesh, const Pose& pose, const SceneConfig& config,
                             const std::filesystem::path& out_dir) {
  std::error_code ec;
  std::filesystem::create_directories(out_dir, ec);
  if (ec) throw Error("io", "cannot create scene folder: " + ec.message(), {.file = out_dir.string()});
  const std::vector<TriMesh> hulls = ConvexDecomposition(mesh, config.decomposition);
  ObjectScene scene;
  SetMassProperties(mesh, hulls, config, scene);
  std::vector<TriMesh> dilated;
  for (const TriMesh& h : hulls) dilated.push_back(DilateConvex(h, config.dilation));
  const Extent extent = WorldExtent(dilated, pose);
  const double bottom = config.base_plate ? extent.lo.z() - config.plate_thickness : extent.lo.z();
  scene.pose = pose;
  if (config.place_on_floor) scene.pose.t.z() -= bottom;
  const double shift = scene.pose.t.z() - pose.t.z();
  WriteSceneXml(dilated, config, out_dir, extent, shift, scene.pose, scene);
  if (config.place_on_floor && config.settle_seconds > 0) {
    const Pose settled = SettledPose(scene.xml_path, config.settle_seconds);
    scene.settle_shift = (settled.t - scene.pose.t).norm();
    scene.settle_angle = RotationAngle(settled.q, scene.pose.q);
    scene.pose = settled;
    WriteSceneXml(dilated, config, out_dir, extent, shift, scene.pose, scene);
  }
  spdlog::info("scene: {} hulls, mass {:.3f} kg ({}), written to {}", dilated.size(), scene.mass,
               scene.inertia_from_hulls ? "from hulls" : "from mesh", scene.xml_path.string());
  return scene;
}

}  // namespace doasido::retarget
