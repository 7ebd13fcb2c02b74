#include "cli/hand_render.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/error.h"
#include "core/whole_output.h"
#include "robot/hand_mesh.h"
#include "video/mesh_rasterizer.h"

namespace doasido::cli {
namespace {

using retarget::DataPtr;
using retarget::HandChain;
using retarget::HandCheck;

Vec3 V(const mjtNum* p) { return Vec3(p[0], p[1], p[2]); }
Mat3 M(const mjtNum* p) { return Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(p); }

DataPtr Posed(const mjModel* m, const Eigen::VectorXd& q) {
  DataPtr d = retarget::MakeData(m);
  for (int i = 0; i < m->nq; ++i) d->qpos[i] = q[i];
  mj_kinematics(m, d.get());
  return d;
}

std::vector<std::vector<int>> GeomGroups(const HandCheck& c);

struct View {
  Mat3 rot;  // rows: camera x, y, z in world coordinates
  Vec3 eye;
  Camera camera;
  Vec3 ToCamera(const Vec3& p) const { return rot * (p - eye); }
};

// Fingers up the picture, the palm's flexing side towards the viewer, turned
// a little across the palm and down the fingers so that curled fingers show.
View MakeView(const HandCheck& c, const HandRenderOptions& o) {
  const mjModel* m = c.model.get();
  const Eigen::VectorXd rest_q = Eigen::Map<const Eigen::VectorXd>(m->qpos0, m->nq);
  DataPtr rest = Posed(m, rest_q);
  DataPtr flexed = Posed(m, retarget::FlexedPose(m, c.structure, 1.0));
  Vec3 up = Vec3::UnitZ(), lateral = Vec3::UnitY(), curl = Vec3::Zero();
  if (!c.structure.chains.empty()) {
    up.setZero();
    lateral.setZero();
    const auto& chains = c.structure.chains;
    for (size_t i = 0; i < chains.size(); ++i) {
      const HandChain& ch = chains[i];
      const Vec3 tip = V(rest->xpos + 3 * ch.tip_body);
      if (i > 0 || chains.size() == 1) up += (tip - V(rest->xanchor + 3 * ch.joints.front())).normalized();
      const Vec3 a = V(rest->xaxis + 3 * ch.joints.back());
      lateral += lateral.dot(a) < 0 ? -a : a;
      curl += V(flexed->xpos + 3 * ch.tip_body) - tip;
    }
    up.normalize();
    lateral = (lateral - lateral.dot(up) * up).normalized();
  }
  Vec3 normal = up.cross(lateral);
  if (normal.dot(curl) < 0) normal = -normal;
  // Framed on the palm and the fingers (not a forearm or a mount below them).
  std::vector<int> framed;
  const auto groups = GeomGroups(c);
  for (size_t g = 0; g < groups.size(); ++g) {
    for (int geom : groups[g]) {
      if (g > 0 || m->geom_bodyid[geom] == c.structure.palm) framed.push_back(geom);
    }
  }
  if (framed.empty()) framed = retarget::DrawnGeoms(m);
  const TriMesh mesh = retarget::GeomsMesh(m, rest.get(), framed);
  const Vec3 center = 0.5 * (mesh.Min() + mesh.Max());
  double radius = 1e-3;
  for (int i = 0; i < mesh.num_vertices(); ++i) {
    radius = std::max(radius, (Vec3(mesh.vertices.row(i)) - center).norm());
  }
  const Vec3 towards = (normal + 0.35 * lateral - 0.25 * up).normalized();
  const double half_fov = 20.0 * M_PI / 180.0;
  View v;
  v.eye = center + towards * (1.1 * radius / std::sin(half_fov));
  const Vec3 z = (center - v.eye).normalized();
  const Vec3 y = (-up + up.dot(z) * z).normalized();  // image down = world down
  v.rot.row(0) = y.cross(z);
  v.rot.row(1) = y;
  v.rot.row(2) = z;
  const double f = 0.5 * o.size / std::tan(half_fov);
  v.camera = Camera{o.size, o.size, f, f, 0.5 * o.size, 0.5 * o.size};
  return v;
}

// Surface id per geom: 1 palm and anything else, 2 + chain index for fingers.
std::vector<std::vector<int>> GeomGroups(const HandCheck& c) {
  const mjModel* m = c.model.get();
  std::vector<int> group_of_body(m->nbody, 0);
  for (size_t i = 0; i < c.structure.chains.size(); ++i) {
    for (int b : c.structure.chains[i].bodies) group_of_body[b] = static_cast<int>(i) + 1;
  }
  for (int b = 1; b < m->nbody; ++b) {  // bodies hanging off a chain (parents come first)
    if (!group_of_body[b]) group_of_body[b] = group_of_body[m->body_parentid[b]];
  }
  std::vector<std::vector<int>> groups(c.structure.chains.size() + 1);
  for (int g : retarget::DrawnGeoms(m)) groups[group_of_body[m->geom_bodyid[g]]].push_back(g);
  return groups;
}

cv::Vec3b GroupColour(size_t group) {
  if (group == 0) return {170, 170, 170};   // palm, BGR
  if (group == 1) return {40, 140, 240};    // thumb: orange
  const cv::Vec3b fingers[] = {{220, 120, 40}, {200, 160, 40}, {150, 180, 40}, {90, 170, 60}, {120, 120, 120}};
  return fingers[std::min<size_t>(group - 2, 4)];
}

void DrawPoints(const HandCheck& c, const mjData* d, const View& v, cv::Mat& image) {
  const mjModel* m = c.model.get();
  for (const retarget::EmbodimentPoint& p : c.embodiment.points) {
    const Vec3 offset(p.pos[0], p.pos[1], p.pos[2]);
    Vec3 world;
    if (!p.site.empty()) {
      const int s = retarget::NameToId(m, mjOBJ_SITE, p.site);
      if (s < 0) continue;
      world = V(d->site_xpos + 3 * s) + M(d->site_xmat + 9 * s) * offset;
    } else {
      const int b = retarget::NameToId(m, mjOBJ_BODY, p.body);
      if (b < 0) continue;
      world = V(d->xpos + 3 * b) + M(d->xmat + 9 * b) * offset;
    }
    const Vec3 cam = v.ToCamera(world);
    if (cam.z() <= 0) continue;
    const Vec2 px = v.camera.Project(cam);
    const cv::Point at(static_cast<int>(std::lround(px.x())), static_cast<int>(std::lround(px.y())));
    cv::circle(image, at, 5, cv::Scalar(0, 0, 0), cv::FILLED, cv::LINE_AA);
    cv::circle(image, at, 4, p.fingertip ? cv::Scalar(40, 40, 230) : cv::Scalar(40, 220, 240), cv::FILLED,
               cv::LINE_AA);
  }
}

}  // namespace

void RenderHandPng(const HandCheck& check, const Eigen::VectorXd& qpos, const std::filesystem::path& path,
                   const HandRenderOptions& options) {
  const mjModel* m = check.model.get();
  const View view = MakeView(check, options);
  DataPtr d = Posed(m, qpos);
  video::RasterTarget target;
  target.Reset(options.size, options.size);
  const auto groups = GeomGroups(check);
  std::vector<TriMesh> meshes;
  for (size_t g = 0; g < groups.size(); ++g) {
    TriMesh mesh = retarget::GeomsMesh(m, d.get(), groups[g]);
    for (int i = 0; i < mesh.num_vertices(); ++i) {
      mesh.vertices.row(i) = view.ToCamera(Vec3(mesh.vertices.row(i))).transpose();
    }
    video::Rasterize(mesh, view.camera, static_cast<std::uint8_t>(g + 1), target);
    meshes.push_back(std::move(mesh));
  }
  cv::Mat image(options.size, options.size, CV_8UC3, cv::Scalar(255, 255, 255));
  for (int y = 0; y < options.size; ++y) {
    for (int x = 0; x < options.size; ++x) {
      const int s = target.surface.at<std::uint8_t>(y, x), f = target.face.at<int>(y, x);
      if (s == 0 || f < 0) continue;
      const TriMesh& mesh = meshes[s - 1];
      const Vec3 a = mesh.vertices.row(mesh.faces(f, 0)), b = mesh.vertices.row(mesh.faces(f, 1)),
                 c = mesh.vertices.row(mesh.faces(f, 2));
      const Vec3 n = (b - a).cross(c - a).normalized();
      const double shade = 0.35 + 0.65 * std::abs(n.z());
      const cv::Vec3b colour = GroupColour(static_cast<size_t>(s - 1));
      for (int k = 0; k < 3; ++k) image.at<cv::Vec3b>(y, x)[k] = cv::saturate_cast<std::uint8_t>(colour[k] * shade);
    }
  }
  DrawPoints(check, d.get(), view, image);
  std::vector<std::uint8_t> png;
  if (!cv::imencode(".png", image, png)) throw Error("io", "cannot encode the picture", {.file = path.string()});
  WriteFileWhole(path, std::string(png.begin(), png.end()));
}

}  // namespace doasido::cli
