// Bring your own hand, measured: kinematic retargeting of the real 621-frame
// human hand sequence (../shared/data/retarget/human_hand_keypoints_right.csv)
// onto every hand, with its hand-written description and with the one
// `doasido hand import` generates, side by side in the same run; plus the
// Allegro hand exported here to URDF (links, revolute joints with limits,
// meshes as OBJ and PLY) and imported back through MuJoCo 2.2.2, as a new
// user's URDF hand would be. Fingertip error (mm) is the mean distance of the
// mapped fingertips to the scaled human fingertips, per frame; the table
// gives its mean and 95th percentile over frames. Google Benchmark timings
// of the import and of describing an MJCF follow.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numeric>

#include <benchmark/benchmark.h>
#include <spdlog/spdlog.h>

#include "core/mesh.h"
#include "retarget/kinematic/kinematic_retarget.h"
#include "robot/embodiment.h"
#include "robot/mjcf_compat.h"
#include "robot/urdf_import.h"

namespace {

using namespace doasido;
using namespace doasido::retarget;
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

const fs::path kData = DOASIDO_SHARED_DATA;
const fs::path kWork = fs::temp_directory_path() / "doasido-hands-bench";

std::string F(double v) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.9g", v);
  return buf;
}
std::string F3(const double* v) { return F(v[0]) + " " + F(v[1]) + " " + F(v[2]); }
std::string Rpy(const mjtNum* q) {
  const Mat3 r = Quat(q[0], q[1], q[2], q[3]).normalized().toRotationMatrix();
  const Vec3 ypr = r.eulerAngles(2, 1, 0);  // R = Rz(yaw) Ry(pitch) Rx(roll), URDF's convention
  return F(ypr[2]) + " " + F(ypr[1]) + " " + F(ypr[0]);
}

// Writes mesh `id` of `m` (in its geom frame) as OBJ, or as ASCII PLY.
void WriteMesh(const mjModel* m, int id, const fs::path& path, bool ply) {
  std::ofstream out(path);
  const int nv = m->mesh_vertnum[id], nf = m->mesh_facenum[id];
  if (ply) {
    out << "ply\nformat ascii 1.0\nelement vertex " << nv << "\nproperty float x\nproperty float y\n"
        << "property float z\nelement face " << nf << "\nproperty list uchar int vertex_indices\nend_header\n";
  }
  for (int i = 0; i < nv; ++i) {
    const float* v = m->mesh_vert + 3 * (m->mesh_vertadr[id] + i);
    out << (ply ? "" : "v ") << v[0] << " " << v[1] << " " << v[2] << "\n";
  }
  for (int i = 0; i < nf; ++i) {
    const int* f = m->mesh_face + 3 * (m->mesh_faceadr[id] + i);
    if (ply) out << "3 " << f[0] << " " << f[1] << " " << f[2] << "\n";
    else out << "f " << f[0] + 1 << " " << f[1] + 1 << " " << f[2] + 1 << "\n";
  }
}

// A URDF of an MJCF hand whose bodies carry at most one hinge at their
// origin (Allegro): link per body, mesh geoms as visual and collision.
fs::path ExportUrdf(const fs::path& mjcf, const fs::path& dir) {
  ModelPtr model = CompileMjcfText(PrepareMjcf(mjcf).xml, mjcf.string());
  const mjModel* m = model.get();
  fs::create_directories(dir / "meshes");
  std::string links, joints;
  int mesh_files = 0;
  for (int b = 1; b < m->nbody; ++b) {
    const std::string name = mj_id2name(m, mjOBJ_BODY, b);
    links += "  <link name=\"" + name + "\">\n";
    if (m->body_mass[b] > 0) {
      links += "    <inertial><origin xyz=\"" + F3(m->body_ipos + 3 * b) + "\" rpy=\"" + Rpy(m->body_iquat + 4 * b) +
               "\"/><mass value=\"" + F(m->body_mass[b]) + "\"/><inertia ixx=\"" + F(m->body_inertia[3 * b]) +
               "\" iyy=\"" + F(m->body_inertia[3 * b + 1]) + "\" izz=\"" + F(m->body_inertia[3 * b + 2]) +
               "\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial>\n";
    }
    for (int g = m->body_geomadr[b]; g >= 0 && g < m->body_geomadr[b] + m->body_geomnum[b]; ++g) {
      if (m->geom_type[g] != mjGEOM_MESH) continue;
      const bool ply = mesh_files % 2 == 1;  // half of them go through the assimp conversion
      const std::string file = "meshes/" + name + "_" + std::to_string(g) + (ply ? ".ply" : ".obj");
      WriteMesh(m, m->geom_dataid[g], dir / file, ply);
      ++mesh_files;
      const std::string origin = "<origin xyz=\"" + F3(m->geom_pos + 3 * g) + "\" rpy=\"" + Rpy(m->geom_quat + 4 * g) + "\"/>";
      links += "    <visual>" + origin + "<geometry><mesh filename=\"" + file + "\"/></geometry></visual>\n";
      links += "    <collision>" + origin + "<geometry><mesh filename=\"" + file + "\"/></geometry></collision>\n";
    }
    links += "  </link>\n";
    if (m->body_parentid[b] == 0) continue;  // the root link
    const int j = m->body_jntnum[b] == 1 ? m->body_jntadr[b] : -1;
    joints += "  <joint name=\"" + (j >= 0 ? std::string(mj_id2name(m, mjOBJ_JOINT, j)) : name + "_fixed") +
              "\" type=\"" + (j >= 0 ? "revolute" : "fixed") + "\"><parent link=\"" +
              mj_id2name(m, mjOBJ_BODY, m->body_parentid[b]) + "\"/><child link=\"" + name +
              "\"/><origin xyz=\"" + F3(m->body_pos + 3 * b) + "\" rpy=\"" + Rpy(m->body_quat + 4 * b) + "\"/>";
    if (j >= 0) {
      joints += "<axis xyz=\"" + F3(m->jnt_axis + 3 * j) + "\"/><limit lower=\"" + F(m->jnt_range[2 * j]) +
                "\" upper=\"" + F(m->jnt_range[2 * j + 1]) + "\" effort=\"1\" velocity=\"3\"/>";
    }
    joints += "</joint>\n";
  }
  const fs::path urdf = dir / "allegro_urdf.urdf";
  std::ofstream(urdf) << "<?xml version=\"1.0\"?>\n<robot name=\"allegro_urdf\">\n" << links << joints << "</robot>\n";
  return urdf;
}

double Mean(const std::vector<double>& v) { return std::accumulate(v.begin(), v.end(), 0.0) / v.size(); }
double P95(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[static_cast<size_t>(0.95 * (v.size() - 1))];
}

struct Row {
  std::string hand, description;
  int tips = 0;
  double scale = 0, mean = 0, p95 = 0, ms = 0;
};

Row Measure(const std::string& hand, const std::string& description, const Embodiment& e,
            const std::vector<Keypoints21>& frames) {
  Row row{hand, description};
  const HandModel model = BuildHandModel(e);
  for (const ModelPoint& p : model.points) row.tips += p.fingertip;
  KinematicRetargeter solver(model);
  const auto t0 = Clock::now();
  const HandTrajectory t = solver.Solve(frames, {}, 30);  // adapts the scale, then warm-started frames
  row.ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count() / frames.size();
  row.scale = t.scale;
  const std::vector<double>& err = t.fingertip_error;
  row.mean = Mean(err);
  row.p95 = P95(err);
  return row;
}

void BM_ImportUrdf(benchmark::State& state) {
  const fs::path urdf = kWork / "allegro_urdf/allegro_urdf.urdf";
  for (auto _ : state) ImportUrdf(urdf, kWork / "bm_import");
}
BENCHMARK(BM_ImportUrdf)->Unit(benchmark::kMillisecond);

void BM_DescribeMjcf(benchmark::State& state) {
  const fs::path mjcf = kData / "robots/wonik_allegro/right_hand.xml";
  for (auto _ : state) DescribeMjcf(mjcf, kWork / "bm_describe");
}
BENCHMARK(BM_DescribeMjcf)->Unit(benchmark::kMillisecond);

}  // namespace

int main(int argc, char** argv) {
  spdlog::set_level(spdlog::level::err);
  const auto frames = ReadKeypointCsv(kData / "retarget/human_hand_keypoints_right.csv");
  fs::remove_all(kWork);
  std::vector<Row> rows;
  for (const char* name : {"sharpa_right", "shadow", "allegro"}) {
    const Embodiment written = FindEmbodiment(name, kData / "robots");
    rows.push_back(Measure(name, "hand-written", written, frames));
    HandImportOptions options;
    options.name = std::string(name) + "_generated";
    const ImportedHand gen = DescribeMjcf(written.model_path, kWork / "generated", options);
    rows.push_back(Measure(name, "generated", LoadEmbodiment(gen.description), frames));
  }
  const fs::path urdf = ExportUrdf(kData / "robots/wonik_allegro/right_hand.xml", kWork / "allegro_urdf");
  const ImportedHand imported = ImportUrdf(urdf, kWork / "allegro_imported");
  rows.push_back(Measure("allegro (URDF)", "imported", LoadEmbodiment(imported.description), frames));

  std::printf("Kinematic retargeting of %zu real frames (dex-retargeting sample), 4 random starts + warm\n"
              "start per frame, scale adapted; fingertip error in mm over frames.\n\n", frames.size());
  std::printf("%-15s %-13s %4s %6s | %8s %8s | %8s %9s\n", "hand", "description", "tips", "scale",
              "mean", "p95", "ms/frame", "vs written");
  double written_ms = 0;
  for (const Row& r : rows) {
    if (r.description == "hand-written") written_ms = r.ms;
    std::printf("%-15s %-13s %4d %6.3f | %8.2f %8.2f | %8.2f %8.2fx\n", r.hand.c_str(), r.description.c_str(),
                r.tips, r.scale, 1000 * r.mean, 1000 * r.p95, r.ms, r.ms / written_ms);
  }
  std::printf("\nallegro (URDF): the Allegro MJCF exported here to URDF (%zu meshes, half as PLY) and brought\n"
              "back by `doasido hand import`; compare with allegro's rows. vs written: time per frame\n"
              "against the hand-written description of the same hand (allegro's for the URDF row).\n\n",
              imported.meshes.size());
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  return 0;
}
