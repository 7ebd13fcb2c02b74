// The reconstruction artifact (recon/reconstruction.h) round-trips, and a
// damaged one is refused naming the file and the array.
#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
#include "recon/bundle/npy.h"
#include "recon/reconstruction.h"
#include "tests/test_util.h"

namespace doasido::recon {
namespace {

using testing::TempDir;

Reconstruction Sample() {
  Reconstruction r;
  r.fps = 29.97;
  r.floor_z = 0;
  for (int f = 0; f < 5; ++f) {
    r.right_valid.push_back(f != 2);
    Joints21 j;
    for (int i = 0; i < 21; ++i) j.row(i) = Eigen::RowVector3d(0.01 * i, 0.1 * f, 0.2 + 0.001 * i);
    r.right_joints.push_back(j);
    r.object_valid.push_back(f != 4);
    Pose p;
    p.t = Vec3(0.1 * f, -0.05, 0.03);
    p.q = Quat(Eigen::AngleAxisd(0.3 * f, Vec3::UnitZ()));
    r.object_poses.push_back(p);
  }
  r.info = {{"gravity_source", "bundle"}};
  return r;
}

TEST(ReconReconstruction, RoundTripsEveryArray) {
  TempDir dir;
  const Reconstruction r = Sample();
  WriteReconstruction(r, dir / "recon");
  const Reconstruction back = ReadReconstruction(dir / "recon");
  ASSERT_EQ(back.frames(), 5);
  EXPECT_DOUBLE_EQ(back.fps, 29.97);
  EXPECT_EQ(back.right_valid, r.right_valid);
  EXPECT_EQ(back.object_valid, r.object_valid);
  for (int f = 0; f < 5; ++f) {
    if (r.right_valid[f]) {
      EXPECT_EQ(back.right_joints[f], r.right_joints[f]);
    } else {
      EXPECT_FALSE(back.right_joints[f].allFinite());  // written as NaN
    }
    if (r.object_valid[f]) {
      EXPECT_LT((back.object_poses[f].t - r.object_poses[f].t).norm(), 1e-15);
      EXPECT_LT(back.object_poses[f].q.angularDistance(r.object_poses[f].q), 1e-12);
    }
  }
  EXPECT_EQ(back.info["gravity_source"], "bundle");
  EXPECT_TRUE(back.object_mesh.empty());
}

// Both hands: the left one round-trips beside the right one and numpy
// (Debian's python3-numpy, an independent reader) sees the same arrays; a
// file without a left hand reads with none; a NaN joint in a valid left
// frame is named.
TEST(ReconReconstruction, TheLeftHandRoundTripsAndNumpyReadsIt) {
  TempDir dir;
  Reconstruction r = Sample();
  for (int f = 0; f < 5; ++f) {
    r.left_valid.push_back(f != 1);
    r.left_joints.push_back(r.right_joints[f].array() * -1.0 + 0.5);
  }
  WriteReconstruction(r, dir / "recon");
  const Reconstruction back = ReadReconstruction(dir / "recon");
  EXPECT_EQ(back.left_valid, r.left_valid);
  for (int f = 0; f < 5; ++f) {
    if (r.left_valid[f]) {
      EXPECT_EQ(back.left_joints[f], r.left_joints[f]);
    }
  }
  testing::WriteFile(dir / "read.py",
                     "import numpy, sys\n"
                     "z = numpy.load(sys.argv[1])\n"
                     "print(z['left_joints'].shape, z['left_valid'].tolist())\n"
                     "print(bool(numpy.isnan(z['left_joints'][1]).all()))\n"
                     "print(repr(float(z['left_joints'][3, 20, 0])))\n");
  const std::string out = testing::ShellOk("/usr/bin/python3 " + (dir / "read.py").string() + " " +
                                           (dir / "recon/reconstruction.npz").string());
  EXPECT_EQ(out.substr(0, out.rfind('\n', out.size() - 2) + 1), "(5, 21, 3) [1, 0, 1, 1, 1]\nTrue\n") << out;
  EXPECT_EQ(std::stod(out.substr(out.rfind('\n', out.size() - 2) + 1)), r.left_joints[3](20, 0)) << out;

  Reconstruction one = Sample();
  WriteReconstruction(one, dir / "one");
  EXPECT_TRUE(ReadReconstruction(dir / "one").left_valid.empty());

  r.left_joints[2](4, 1) = std::nan("");
  WriteReconstruction(r, dir / "bad");
  try {
    ReadReconstruction(dir / "bad");
    ADD_FAILURE() << "a NaN joint in a valid left frame was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "bad_reconstruction");
    EXPECT_EQ(e.site().field, "left_joints");
  }
}

TEST(ReconReconstruction, RefusesNonFiniteValidJointsNamingTheArray) {
  TempDir dir;
  WriteReconstruction(Sample(), dir / "recon");
  NpzArchive npz = ReadNpz(dir / "recon" / kReconstructionNpz);
  std::vector<double> j = npz["right_joints"].AsDoubleVector();
  j[63 * 1 + 4] = std::nan("");  // frame 1 is valid
  npz["right_joints"] = MakeArray<double>({5, 21, 3}, j);
  WriteNpz(dir / "recon" / kReconstructionNpz, npz);
  try {
    ReadReconstruction(dir / "recon");
    FAIL() << "accepted NaN joints";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "bad_reconstruction");
    EXPECT_EQ(e.site().field, "right_joints");
    EXPECT_NE(e.site().file.find(kReconstructionNpz), std::string::npos);
  }
}

TEST(ReconReconstruction, RefusesAMismatchedFrameCount) {
  TempDir dir;
  WriteReconstruction(Sample(), dir / "recon");
  NpzArchive npz = ReadNpz(dir / "recon" / kReconstructionNpz);
  npz["object_valid"] = MakeArray<std::uint8_t>({4}, {1, 1, 1, 1});
  WriteNpz(dir / "recon" / kReconstructionNpz, npz);
  try {
    ReadReconstruction(dir / "recon");
    FAIL() << "accepted 4 object flags for 5 frames";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "bad_reconstruction");
    EXPECT_EQ(e.site().field, "object_valid");
  }
}

TEST(ReconReconstruction, MissingFolderIsNamed) {
  TempDir dir;
  EXPECT_THROW(ReadReconstruction(dir / "nothing"), Error);
}

}  // namespace
}  // namespace doasido::recon
