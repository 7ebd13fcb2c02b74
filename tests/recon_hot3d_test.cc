// Real ground truth through the bundle: HOT3D's object trajectory
// (dynamic_objects.csv) and headset trajectory, expressed in the headset
// frame, with the object's real GLB model, written as a clip bundle and read
// back unchanged. Skipped when ../shared/data/hot3d_sample is absent.
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>

#include <gtest/gtest.h>

#include "core/mesh.h"
#include "recon/bundle.h"
#include "recon/recon_metrics.h"
#include "tests/test_util.h"

namespace doasido::recon {
namespace {

using doasido::testing::SharedData;
using doasido::testing::TempDir;

const char kMouse[] = "265826671143948";

std::filesystem::path Sample() { return SharedData() / "hot3d_sample"; }
std::filesystem::path Recording() { return Sample() / "Aria" / "P0003_c701bd11"; }

// Rows of a HOT3D pose CSV (object_uid, timestamp[ns], t xyz [m], q wxyz)
// for one uid, keyed by timestamp.
std::map<long long, Pose> ReadPoses(const std::filesystem::path& csv, const std::string& uid) {
  std::ifstream in(csv);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line.rfind("object_uid,timestamp[ns],t_wo_x[m]", 0), 0u) << csv;
  std::map<long long, Pose> out;
  while (std::getline(in, line)) {
    std::stringstream ss(line);
    std::string cell;
    std::vector<std::string> cells;
    while (std::getline(ss, cell, ',')) cells.push_back(cell);
    if (cells.size() != 9 || cells[0] != uid) continue;
    Pose p;
    p.t = Vec3(std::stod(cells[2]), std::stod(cells[3]), std::stod(cells[4]));
    p.q = Quat(std::stod(cells[5]), std::stod(cells[6]), std::stod(cells[7]), std::stod(cells[8]));
    out[std::stoll(cells[1])] = p;
  }
  return out;
}

class Hot3dBundleTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!std::filesystem::exists(Recording() / "dynamic_objects.csv")) {
      GTEST_SKIP() << "HOT3D sample not found under " << Sample();
    }
  }
};

TEST_F(Hot3dBundleTest, ObjectTrajectoryAndModelRoundTrip) {
  const auto objects = ReadPoses(Recording() / "dynamic_objects.csv", kMouse);
  const auto headset = ReadPoses(Recording() / "headset_trajectory.csv", "5411364721403");
  ASSERT_GT(objects.size(), 10u);

  ClipBundle b;
  b.width = 1408;  // Aria RGB
  b.height = 1408;
  std::vector<long long> stamps;
  for (const auto& [stamp, world_object] : objects) {
    auto it = headset.find(stamp);
    if (it == headset.end()) continue;
    // object -> headset = (headset -> world)^-1 * (object -> world)
    b.object_poses.push_back(it->second.Inverse() * world_object);
    stamps.push_back(stamp);
  }
  ASSERT_EQ(stamps.size(), objects.size()) << "every object pose has a headset pose";
  b.frames = static_cast<int>(stamps.size());
  b.fps = 1e9 * (b.frames - 1) / static_cast<double>(stamps.back() - stamps.front());
  b.producers = {{"object_poses", "hot3d ground truth"}};

  const auto glb = Sample() / "object_library" / (std::string(kMouse) + ".glb");
  const TriMesh raw = LoadMesh(glb);
  b.object_mesh = raw;
  const double extent = (raw.Max() - raw.Min()).maxCoeff();
  EXPECT_GT(extent, 0.05) << "HOT3D models are in metres; a computer mouse is 5-15 cm long";
  EXPECT_LT(extent, 0.15);

  TempDir dir;
  WriteBundle(b, dir.path());
  const ClipBundle r = ReadBundle(dir.path());
  EXPECT_EQ(r.frames, b.frames);
  EXPECT_EQ(r.fps, b.fps);
  ASSERT_EQ(r.object_poses.size(), b.object_poses.size());
  for (size_t t = 0; t < b.object_poses.size(); ++t) {
    EXPECT_EQ(r.object_poses[t].t, b.object_poses[t].t);
    EXPECT_EQ(r.object_poses[t].q.coeffs(), b.object_poses[t].q.coeffs());
    // A hand-held object stays within arm's reach of the head.
    EXPECT_LT(r.object_poses[t].t.norm(), 1.5) << "frame " << t;
  }
  ASSERT_TRUE(r.object_mesh);
  EXPECT_EQ(r.object_mesh->vertices, b.object_mesh->vertices);
  EXPECT_EQ(r.object_mesh->faces, b.object_mesh->faces);

  // The model handed in as the GLB itself (the form SAM 3D writes) reads
  // through assimp.
  std::filesystem::remove(dir.path() / "object" / "mesh.obj");
  std::filesystem::copy_file(glb, dir.path() / "object" / "mesh.glb");
  const ClipBundle g = ReadBundle(dir.path());
  ASSERT_TRUE(g.object_mesh);
  EXPECT_EQ(g.object_mesh->vertices, raw.vertices);

  // The same model in millimetres is caught as a units error naming the file.
  std::filesystem::remove(dir.path() / "object" / "mesh.glb");
  TriMesh mm = raw;
  mm.vertices *= 1000.0;
  SaveObj(mm, dir.path() / "object" / "mesh.obj");
  try {
    ReadBundle(dir.path());
    ADD_FAILURE() << "millimetre mesh accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "bad_bundle");
    EXPECT_NE(e.site().file.find("object/mesh.obj"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("millimetres"), std::string::npos) << e.what();
  }

  // The model compared with itself gives a perfect score; against its
  // millimetre twin it does not.
  ReconMetricsConfig cfg;
  cfg.samples = 3000;
  EXPECT_EQ(CompareSurfaces(raw, *r.object_mesh, cfg).f_5mm, 1.0);
  EXPECT_LT(CompareSurfaces(mm, raw, cfg).f_10mm, 0.01);
}

}  // namespace
}  // namespace doasido::recon
