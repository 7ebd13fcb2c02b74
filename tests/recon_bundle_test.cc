// The clip bundle round-trips through WriteBundle/ReadBundle with every field
// equal, and each kind of bad input is rejected with an error that names the
// file and the field.
#include "recon/bundle/bundle.h"

#include <cmath>
#include <fstream>
#include <random>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "recon/bundle/exr_io.h"
#include "recon/bundle/npy.h"
#include "tests/test_util.h"

namespace doasido::recon {
namespace {

using ::testing::HasSubstr;
using doasido::testing::TempDir;

constexpr int kW = 32, kH = 24, kT = 4;

Quat RandomQuat(std::mt19937& rng) {
  std::normal_distribution<double> n;
  return Quat(n(rng), n(rng), n(rng), n(rng)).normalized();
}

HandTrack MakeHand(std::mt19937& rng, double offset) {
  std::uniform_real_distribution<double> u(-0.2, 0.2);
  HandTrack h;
  for (int t = 0; t < kT; ++t) {
    h.valid.push_back(t != 2);
    Joints21 j;
    for (int k = 0; k < 63; ++k) j.data()[k] = u(rng) + offset;
    h.joints.push_back(j);
    // Frame 2 (not valid) has no mesh, as when a hand is not seen.
    Eigen::MatrixX3d v(t == 2 ? 0 : 5, 3);
    for (int k = 0; k < v.size(); ++k) v.data()[k] = u(rng);
    h.verts.push_back(v);
  }
  h.faces.resize(2, 3);
  h.faces << 0, 1, 2, 2, 3, 4;
  return h;
}

// A bundle with every part filled with random values.
ClipBundle FullBundle() {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  ClipBundle b;
  b.width = kW;
  b.height = kH;
  b.frames = kT;
  b.fps = 29.97;
  b.producers = {{"depth", "synth"}, {"hands", "synth"}};
  for (int t = 0; t < kT; ++t) {
    Mat3 k;
    k << 30 + t, 0, 15.5, 0, 31, 11.5, 0, 0, 1;
    b.K.push_back(k);
    cv::Mat z(kH, kW, CV_32F);
    cv::randu(z, 0.3f, 2.0f);
    z.at<float>(1, 2) = std::numeric_limits<float>::infinity();
    z.at<float>(3, 4) = 0.0f;
    b.depth.push_back(z);
    cv::Mat p(kH, kW, CV_32FC3);
    cv::randu(p, -1.0f, 1.0f);
    p.at<cv::Vec3f>(2, 3)[1] = std::numeric_limits<float>::quiet_NaN();
    b.points.push_back(p);
    for (auto* masks : {&b.mask_object, &b.mask_hand_left, &b.mask_hand_right}) {
      cv::Mat m(kH, kW, CV_8U);
      cv::randu(m, 0, 2);
      masks->push_back(m * 255);
    }
    b.object_poses.push_back({RandomQuat(rng), Vec3(u(rng), u(rng), 1 + u(rng))});
    std::vector<PoseSample> samples;
    for (int i = 0; i < 3; ++i) {
      samples.push_back({{RandomQuat(rng), Vec3(u(rng), u(rng), u(rng))}, 1.0 + 0.1 * i});
    }
    b.candidates.push_back(samples);
    b.gravity_up.push_back(Vec3(u(rng), u(rng), u(rng)).normalized());
  }
  b.hand_left = MakeHand(rng, 0.0);
  b.hand_right = MakeHand(rng, 0.5);
  TriMesh mesh;
  mesh.vertices.resize(4, 3);
  mesh.vertices << 0, 0, 0, 0.1, 0, 0, 0, 0.1, 0, 0, 0, 0.1 / 3.0;
  mesh.faces.resize(4, 3);
  mesh.faces << 0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3;
  b.object_mesh = mesh;
  PointTracks tr;
  const int n = 5;
  tr.x = Eigen::MatrixXf::Random(n, kT) * 10;
  tr.y = Eigen::MatrixXf::Random(n, kT) * 10;
  tr.visible.resize(n, kT);
  for (int i = 0; i < n; ++i) {
    for (int t = 0; t < kT; ++t) tr.visible(i, t) = (i + t) % 3 != 0;
  }
  tr.query = Eigen::MatrixX3f::Random(n, 3);
  b.tracks = tr;
  return b;
}

bool MatEqual(const cv::Mat& a, const cv::Mat& b) {
  if (a.size() != b.size() || a.type() != b.type()) return false;
  // memcmp so that +inf compares equal to +inf.
  for (int y = 0; y < a.rows; ++y) {
    if (std::memcmp(a.ptr(y), b.ptr(y), a.cols * a.elemSize()) != 0) return false;
  }
  return true;
}

void ExpectPoseEq(const Pose& a, const Pose& b) {
  EXPECT_EQ(a.t, b.t);
  EXPECT_EQ(a.q.coeffs(), b.q.coeffs());
}

void ExpectHandEq(const HandTrack& a, const HandTrack& b) {
  EXPECT_EQ(a.valid, b.valid);
  ASSERT_EQ(a.joints.size(), b.joints.size());
  for (size_t t = 0; t < a.joints.size(); ++t) EXPECT_EQ(a.joints[t], b.joints[t]);
  ASSERT_EQ(a.verts.size(), b.verts.size());
  for (size_t t = 0; t < a.verts.size(); ++t) {
    ASSERT_EQ(a.verts[t].rows(), b.verts[t].rows()) << "frame " << t;
    EXPECT_EQ(a.verts[t], b.verts[t]);
  }
  EXPECT_EQ(a.faces, b.faces);
}

TEST(BundleTest, EveryPartRoundTripsExactly) {
  TempDir dir;
  const ClipBundle in = FullBundle();
  WriteBundle(in, dir.path());
  const ClipBundle out = ReadBundle(dir.path());

  EXPECT_EQ(out.width, in.width);
  EXPECT_EQ(out.height, in.height);
  EXPECT_EQ(out.frames, in.frames);
  EXPECT_EQ(out.fps, in.fps);
  EXPECT_EQ(out.producers, in.producers);
  ASSERT_EQ(out.K.size(), in.K.size());
  for (size_t t = 0; t < in.K.size(); ++t) EXPECT_EQ(out.K[t], in.K[t]);
  ASSERT_EQ(out.depth.size(), in.depth.size());
  for (size_t t = 0; t < in.depth.size(); ++t) EXPECT_TRUE(MatEqual(out.depth[t], in.depth[t]));
  ASSERT_EQ(out.points.size(), in.points.size());
  for (size_t t = 0; t < in.points.size(); ++t) EXPECT_TRUE(MatEqual(out.points[t], in.points[t]));
  for (auto member : {&ClipBundle::mask_object, &ClipBundle::mask_hand_left,
                      &ClipBundle::mask_hand_right}) {
    ASSERT_EQ((out.*member).size(), (in.*member).size());
    for (size_t t = 0; t < (in.*member).size(); ++t) {
      EXPECT_TRUE(MatEqual((out.*member)[t], (in.*member)[t]));
    }
  }
  ASSERT_TRUE(out.hand_left && out.hand_right);
  ExpectHandEq(*out.hand_left, *in.hand_left);
  ExpectHandEq(*out.hand_right, *in.hand_right);
  ASSERT_TRUE(out.object_mesh);
  EXPECT_EQ(out.object_mesh->vertices, in.object_mesh->vertices);
  EXPECT_EQ(out.object_mesh->faces, in.object_mesh->faces);
  ASSERT_EQ(out.object_poses.size(), in.object_poses.size());
  for (size_t t = 0; t < in.object_poses.size(); ++t) {
    ExpectPoseEq(out.object_poses[t], in.object_poses[t]);
  }
  ASSERT_EQ(out.candidates.size(), in.candidates.size());
  for (size_t t = 0; t < in.candidates.size(); ++t) {
    ASSERT_EQ(out.candidates[t].size(), in.candidates[t].size());
    for (size_t i = 0; i < in.candidates[t].size(); ++i) {
      ExpectPoseEq(out.candidates[t][i].pose, in.candidates[t][i].pose);
      EXPECT_EQ(out.candidates[t][i].scale, in.candidates[t][i].scale);
    }
  }
  ASSERT_TRUE(out.tracks);
  EXPECT_EQ(out.tracks->x, in.tracks->x);
  EXPECT_EQ(out.tracks->y, in.tracks->y);
  EXPECT_EQ(out.tracks->visible, in.tracks->visible);
  EXPECT_EQ(out.tracks->query, in.tracks->query);
  ASSERT_EQ(out.gravity_up.size(), in.gravity_up.size());
  for (size_t t = 0; t < in.gravity_up.size(); ++t) EXPECT_EQ(out.gravity_up[t], in.gravity_up[t]);
  EXPECT_EQ(out.present.size(), 13u);
}

TEST(BundleTest, SameInputGivesByteIdenticalFiles) {
  TempDir a, b;
  const ClipBundle in = FullBundle();
  WriteBundle(in, a.path());
  WriteBundle(in, b.path());
  int files = 0;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(a.path())) {
    if (!entry.is_regular_file()) continue;
    const auto rel = std::filesystem::relative(entry.path(), a.path());
    EXPECT_EQ(doasido::testing::ReadFile(entry.path()), doasido::testing::ReadFile(b.path() / rel))
        << rel;
    ++files;
  }
  // meta, K, 4 depth, 4 points, 12 masks, hands, mesh, poses, candidates, tracks, gravity
  EXPECT_EQ(files, 1 + 1 + kT + kT + 3 * kT + 6);
}

TEST(BundleTest, MetaOnlyBundleAndConstantK) {
  TempDir dir;
  ClipBundle in;
  in.width = 640;
  in.height = 480;
  in.frames = 10;
  in.fps = 30;
  Mat3 k;
  k << 500, 0, 319.5, 0, 500, 239.5, 0, 0, 1;
  in.K = {k};
  WriteBundle(in, dir.path());
  const ClipBundle out = ReadBundle(dir.path());
  ASSERT_EQ(out.K.size(), 1u);
  EXPECT_EQ(out.KAt(7), k);
  EXPECT_EQ(out.present, std::set<std::string>{"K"});
  EXPECT_FALSE(out.hand_left.has_value());
  EXPECT_TRUE(out.depth.empty());
}

// Expects ReadBundle(dir) to throw bad_bundle whose message mentions each of
// `needles` (file name, field, ...).
void ExpectBad(const std::filesystem::path& dir, const std::vector<std::string>& needles) {
  try {
    ReadBundle(dir);
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "bad_bundle") << e.what();
    for (const std::string& n : needles) EXPECT_THAT(std::string(e.what()), HasSubstr(n));
  }
}

class BundleErrorTest : public ::testing::Test {
 protected:
  void SetUp() override { WriteBundle(FullBundle(), dir_.path()); }
  TempDir dir_;
};

TEST_F(BundleErrorTest, NanInValidHandJoints) {
  ClipBundle b = FullBundle();
  b.hand_left->joints[1](5, 2) = std::nan("");
  WriteBundle(b, dir_.path());
  ExpectBad(dir_.path(), {"hands.npz", "left_joints", "frame 1"});
}

TEST_F(BundleErrorTest, NanInInvalidHandFrameIsAllowed) {
  ClipBundle b = FullBundle();
  b.hand_left->joints[2](5, 2) = std::nan("");  // frame 2 has valid = 0
  WriteBundle(b, dir_.path());
  const ClipBundle out = ReadBundle(dir_.path());
  EXPECT_TRUE(std::isnan(out.hand_left->joints[2](5, 2)));
}

TEST_F(BundleErrorTest, WrongKShape) {
  WriteNpz(dir_.path() / "K.npz", {{"K", MakeArray<double>({3, 4}, std::vector<double>(12, 1))}});
  ExpectBad(dir_.path(), {"K.npz", "field K", "(3, 4)", "(3, 3)"});
  WriteNpz(dir_.path() / "K.npz",
           {{"K", MakeArray<double>({kT + 1, 3, 3}, std::vector<double>(9 * (kT + 1), 1))}});
  ExpectBad(dir_.path(), {"K.npz", "field K", "(5, 3, 3)"});
}

TEST_F(BundleErrorTest, MissingDepthFrame) {
  std::filesystem::remove(dir_.path() / "depth" / "000002.exr");
  ExpectBad(dir_.path(), {"depth/000002.exr", "missing", "field depth"});
}

TEST_F(BundleErrorTest, MissingPointMapFrame) {
  std::filesystem::remove(dir_.path() / "points" / "000001.exr");
  ExpectBad(dir_.path(), {"points/000001.exr", "missing", "field points"});
}

TEST_F(BundleErrorTest, ExtraDepthFrame) {
  WriteDepthExr(dir_.path() / "depth" / "000004.exr", cv::Mat(kH, kW, CV_32F, cv::Scalar(1)));
  ExpectBad(dir_.path(), {"depth/000004.exr", "beyond"});
}

TEST_F(BundleErrorTest, NanDepth) {
  cv::Mat z(kH, kW, CV_32F, cv::Scalar(1));
  z.at<float>(5, 7) = std::nanf("");
  WriteDepthExr(dir_.path() / "depth" / "000001.exr", z);
  ExpectBad(dir_.path(), {"depth/000001.exr", "x=7, y=5", "field depth"});
}

TEST_F(BundleErrorTest, DepthOfWrongSize) {
  WriteDepthExr(dir_.path() / "depth" / "000000.exr", cv::Mat(kH, kW + 1, CV_32F, cv::Scalar(1)));
  ExpectBad(dir_.path(), {"depth/000000.exr", "33x24", "32x24"});
}

TEST_F(BundleErrorTest, MaskOfWrongSize) {
  cv::imwrite((dir_.path() / "masks" / "hand_left" / "000003.png").string(),
              cv::Mat(kH / 2, kW, CV_8U, cv::Scalar(255)));
  ExpectBad(dir_.path(), {"masks/hand_left/000003.png", "mask_hand_left", "32x12"});
}

TEST_F(BundleErrorTest, ColourMask) {
  cv::imwrite((dir_.path() / "masks" / "object" / "000000.png").string(),
              cv::Mat(kH, kW, CV_8UC3, cv::Scalar(255, 0, 0)));
  ExpectBad(dir_.path(), {"masks/object/000000.png", "3-channel", "field mask_object"});
}

TEST_F(BundleErrorTest, UnitsInMillimetres) {
  doasido::testing::WriteFile(dir_.path() / "meta.json",
                              R"({"width": 32, "height": 24, "frames": 4, "fps": 30,
                                  "units": "mm"})");
  ExpectBad(dir_.path(), {"meta.json", "field units", "\"mm\""});
}

TEST_F(BundleErrorTest, MetaFieldMissingOrWrong) {
  doasido::testing::WriteFile(dir_.path() / "meta.json",
                              R"({"width": 32, "height": 24, "fps": 30, "units": "m"})");
  ExpectBad(dir_.path(), {"meta.json", "field frames", "missing"});
  doasido::testing::WriteFile(dir_.path() / "meta.json",
                              R"({"width": 32.5, "height": 24, "frames": 4, "fps": 30,
                                  "units": "m"})");
  ExpectBad(dir_.path(), {"meta.json", "field width"});
  doasido::testing::WriteFile(dir_.path() / "meta.json", "{not json");
  ExpectBad(dir_.path(), {"meta.json", "JSON"});
}

TEST_F(BundleErrorTest, FrameCountDisagreesWithMeta) {
  // meta says 3 frames: every per-frame array (K, poses, ...) has 4.
  doasido::testing::WriteFile(
      dir_.path() / "meta.json",
      R"({"width": 32, "height": 24, "frames": 3, "fps": 30, "units": "m"})");
  ExpectBad(dir_.path(), {"K.npz", "(4, 3, 3)", "(3, 3, 3)"});
}

TEST_F(BundleErrorTest, NonUnitQuaternion) {
  ClipBundle b = FullBundle();
  b.object_poses[3].q.coeffs() *= 2.0;
  WriteBundle(b, dir_.path());
  ExpectBad(dir_.path(), {"object/poses.npz", "field poses", "frame 3", "norm"});
}

TEST_F(BundleErrorTest, WrongDtype) {
  WriteNpz(dir_.path() / "gravity.npz",
           {{"up", MakeArray<std::int32_t>({kT, 3}, std::vector<std::int32_t>(3 * kT, 0))}});
  ExpectBad(dir_.path(), {"gravity.npz", "field up", "i4"});
}

TEST_F(BundleErrorTest, MissingKey) {
  WriteNpz(dir_.path() / "tracks.npz",
           {{"xy", MakeArray<float>({1, kT, 2}, std::vector<float>(2 * kT, 0))}});
  ExpectBad(dir_.path(), {"tracks.npz", "field visible", "missing"});
}

TEST_F(BundleErrorTest, JointOrderMustBeOpenPose) {
  NpzArchive npz = ReadNpz(dir_.path() / "hands.npz");
  npz["joint_order"] = MakeStringArray("mano16");
  WriteNpz(dir_.path() / "hands.npz", npz);
  ExpectBad(dir_.path(), {"hands.npz", "joint_order"});
}

TEST_F(BundleErrorTest, NamesTheClip) {
  std::filesystem::remove(dir_.path() / "masks" / "object" / "000000.png");
  try {
    ReadBundle(dir_.path());
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.site().clip, dir_.path().filename().string());
  }
}

TEST(BundleWriteTest, RewritingWithFewerFramesLeavesNoStaleFrames) {
  TempDir dir;
  WriteBundle(FullBundle(), dir.path());
  ClipBundle shorter = FullBundle();
  shorter.frames = 2;
  shorter.K.resize(1);
  shorter.depth.resize(2);
  shorter.points.clear();
  shorter.mask_object.resize(2);
  shorter.mask_hand_left.clear();
  shorter.mask_hand_right.clear();
  shorter.hand_left.reset();
  shorter.hand_right.reset();
  shorter.object_poses.resize(2);
  shorter.candidates.resize(2);
  shorter.tracks.reset();
  shorter.gravity_up.resize(2);
  WriteBundle(shorter, dir.path());
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "depth" / "000002.exr"));
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "masks" / "object" / "000003.png"));
  // Parts the new bundle does not hold are left alone, so the old 4-frame
  // ones now disagree with meta.json and are reported.
  ExpectBad(dir.path(), {"points/000002.exr", "beyond"});
}

TEST(BundleWriteTest, InconsistentStructIsRejected) {
  TempDir dir;
  ClipBundle b = FullBundle();
  b.gravity_up.pop_back();
  try {
    WriteBundle(b, dir.path());
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "bad_bundle");
    EXPECT_EQ(e.site().field, "gravity_up");
  }
}

}  // namespace
}  // namespace doasido::recon
