// Each REFERENCE.md §3 "trap" conversion checked against an independent
// construction of what the convention means (a row-vector product, a
// field-of-view camera, a pitched camera under gravity, joints labelled by
// finger and segment), not against the conversion's own formula.
#include "recon/bundle/conventions.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>

namespace doasido::recon {
namespace {

constexpr double kPi = 3.14159265358979323846;

Quat RandomQuat(std::mt19937& rng) {
  std::normal_distribution<double> n;
  return Quat(n(rng), n(rng), n(rng), n(rng)).normalized();
}

TEST(ConventionsTest, Sam3dQuaternionActsOnRowVectors) {
  std::mt19937 rng(1);
  for (int trial = 0; trial < 20; ++trial) {
    const Quat q = RandomQuat(rng);
    const Mat3 r = q.toRotationMatrix();
    const Vec3 p = Vec3::Random();
    // SAM 3D: p_row' = p_row * R(q).
    const Eigen::RowVector3d row = p.transpose() * r;
    const Vec3 column = Sam3dQuatToColumn(q) * p;
    EXPECT_LT((column - row.transpose()).norm(), 1e-12);
  }
}

TEST(ConventionsTest, PyTorch3dLeftUpBecomesOpenCvLeftUp) {
  // PyTorch3D: +x is left, +y is up. OpenCV: left is -x, up is -y.
  EXPECT_EQ(PyTorch3dToOpenCv(Vec3(1, 0, 0)), Vec3(-1, 0, 0));
  EXPECT_EQ(PyTorch3dToOpenCv(Vec3(0, 1, 0)), Vec3(0, -1, 0));
  EXPECT_EQ(PyTorch3dToOpenCv(Vec3(0, 0, 1)), Vec3(0, 0, 1));
  const Mat3 f = PyTorch3dToOpenCvMatrix();
  EXPECT_DOUBLE_EQ(f.determinant(), 1.0);  // a rotation (180 degrees about z)
  EXPECT_TRUE((f * f).isIdentity());
}

TEST(ConventionsTest, Sam3dPoseMatchesRowVectorTransformThenFlip) {
  std::mt19937 rng(2);
  for (int trial = 0; trial < 20; ++trial) {
    const Quat q = RandomQuat(rng);
    const Vec3 t(0.1 * trial, -0.2, 1.5);
    const double s = 0.5 + 0.05 * trial;
    const PoseSample cv = Sam3dPoseToOpenCv(q, t, s);
    EXPECT_EQ(cv.scale, s);
    EXPECT_NEAR(cv.pose.R().determinant(), 1.0, 1e-12);
    for (int k = 0; k < 5; ++k) {
      const Vec3 x = Vec3::Random();
      // SAM 3D in PyTorch3D: row vector (s x) R(q) + t; then flip x and y.
      const Eigen::RowVector3d p3d = (s * x).transpose() * q.toRotationMatrix() + t.transpose();
      const Vec3 expected(-p3d(0), -p3d(1), p3d(2));
      EXPECT_LT((cv.pose * (cv.scale * x) - expected).norm(), 1e-12);
    }
  }
}

TEST(ConventionsTest, GlbYUpBecomesZUpByQuarterTurnAboutX) {
  const Eigen::AngleAxisd quarter(kPi / 2, Vec3::UnitX());
  for (const Vec3& p : {Vec3(1, 2, 3), Vec3(-0.5, 0.1, 7), Vec3(0, 1, 0)}) {
    EXPECT_LT((Sam3dGlbToObjectLocal(p) - quarter * p).norm(), 1e-12);
  }
  EXPECT_EQ(Sam3dGlbToObjectLocal(Vec3::UnitY()), Vec3::UnitZ());  // GLB up -> local up
  // A tetrahedron keeps its volume and orientation.
  TriMesh tet;
  tet.vertices.resize(4, 3);
  tet.vertices << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1;
  tet.faces.resize(4, 3);
  tet.faces << 0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3;
  const TriMesh local = Sam3dGlbMeshToObjectLocal(tet);
  EXPECT_NEAR(local.Volume(), tet.Volume(), 1e-15);
  EXPECT_GT(local.Volume(), 0);
}

TEST(ConventionsTest, MogeFieldOfViewCameraMapsEdgesToPixelBorders) {
  // MoGe builds normalised intrinsics from the field of view: the image spans
  // [0, 1] in both axes with the principal point at 0.5.
  const int w = 640, h = 480;
  const double fov_x = 70 * kPi / 180, fov_y = 55 * kPi / 180;
  Mat3 k_norm = Mat3::Identity();
  k_norm(0, 0) = 0.5 / std::tan(fov_x / 2);
  k_norm(1, 1) = 0.5 / std::tan(fov_y / 2);
  k_norm(0, 2) = 0.5;
  k_norm(1, 2) = 0.5;
  const Camera cam = Camera::FromK(MogeIntrinsicsToPixels(k_norm, w, h), w, h);
  // With pixel centres at integers the image spans [-0.5, W - 0.5]: the
  // optical axis hits the middle of that span and the field-of-view edges its ends.
  const Vec2 centre = cam.Project(Vec3(0, 0, 1));
  EXPECT_NEAR(centre.x(), (w - 1) / 2.0, 1e-9);
  EXPECT_NEAR(centre.y(), (h - 1) / 2.0, 1e-9);
  const Vec2 right = cam.Project(Vec3(std::tan(fov_x / 2), 0, 1));
  const Vec2 left = cam.Project(Vec3(-std::tan(fov_x / 2), 0, 1));
  const Vec2 bottom = cam.Project(Vec3(0, std::tan(fov_y / 2), 1));
  EXPECT_NEAR(right.x(), w - 0.5, 1e-9);
  EXPECT_NEAR(left.x(), -0.5, 1e-9);
  EXPECT_NEAR(bottom.y(), h - 0.5, 1e-9);
}

TEST(ConventionsTest, GeoCalibUpIsOppositePhysicalGravity) {
  // World z up. A level camera looking along world +y has OpenCV axes
  // x = world x, y (down) = world -z, z (forward) = world y; a second camera
  // pitches down by 30 degrees about its own x axis.
  Mat3 r_cw_level;  // rows: camera axes in world coordinates
  r_cw_level << 1, 0, 0, 0, 0, -1, 0, 1, 0;
  const double pitch = 30 * kPi / 180;
  // Pitched down: forward tilts towards world -z, image-down towards forward.
  Mat3 r_cw;
  r_cw.row(0) << 1, 0, 0;
  r_cw.row(1) << 0, -std::sin(pitch), -std::cos(pitch);
  r_cw.row(2) << 0, std::cos(pitch), -std::sin(pitch);
  ASSERT_NEAR(r_cw.determinant(), 1.0, 1e-12);
  const Vec3 gravity_cam = r_cw * Vec3(0, 0, -9.81);
  const Vec3 geocalib = r_cw * Vec3(0, 0, 1);  // what GeoCalib reports: up
  EXPECT_LT((PhysicalGravityDirection(GeoCalibUp(geocalib)) - gravity_cam.normalized()).norm(),
            1e-12);
  // A level camera sees gravity pointing down the image (+y).
  EXPECT_LT((PhysicalGravityDirection(r_cw_level * Vec3::UnitZ()) - Vec3::UnitY()).norm(), 1e-12);
  // Pitched down, gravity gains a forward (+z) component.
  EXPECT_GT(gravity_cam.z(), 0);
}

// MANO native joints labelled by (finger, segment): finger in OpenPose
// numbering (0 wrist, 1 thumb, 2 index, 3 middle, 4 ring, 5 pinky), segment
// 0 for the wrist, 1-3 base to distal, 4 for the tip.
struct Hand {
  Eigen::MatrixX3d native16 = Eigen::MatrixX3d::Zero(16, 3);
  Eigen::MatrixX3d verts = Eigen::MatrixX3d::Constant(778, 3, -99);
};

Hand LabelledHand(ManoSource source, double unit) {
  // Native order as documented: wrist, index, middle, pinky, ring, thumb.
  const int native_fingers[5] = {2, 3, 5, 4, 1};
  Hand h;
  for (int f = 0; f < 5; ++f) {
    for (int s = 1; s <= 3; ++s) h.native16.row(1 + 3 * f + (s - 1)) << native_fingers[f], s, 0;
  }
  const auto tips = ManoFingertipVertices(source);  // thumb, index, middle, ring, pinky
  for (int f = 0; f < 5; ++f) h.verts.row(tips[static_cast<size_t>(f)]) << f + 1, 4, 0;
  h.native16 *= unit;
  h.verts *= unit;
  return h;
}

TEST(ConventionsTest, ManoNativePlusTipsGiveOpenPose21) {
  for (ManoSource source : {ManoSource::kSmplx, ManoSource::kManopth}) {
    const double unit = source == ManoSource::kManopth ? 1000.0 : 1.0;
    const Hand h = LabelledHand(source, unit);
    const Joints21 j = ManoToOpenPose21(h.native16, h.verts, source);
    EXPECT_EQ(j.row(0), Eigen::RowVector3d(0, 0, 0));
    for (int k = 1; k < 21; ++k) {
      // OpenPose-21: thumb 1-4, index 5-8, middle 9-12, ring 13-16, pinky 17-20.
      EXPECT_EQ(j(k, 0), (k - 1) / 4 + 1) << "joint " << k;
      EXPECT_EQ(j(k, 1), (k - 1) % 4 + 1) << "joint " << k;
    }
  }
}

TEST(ConventionsTest, ManoFingertipIdsDifferBetweenImplementations) {
  // The smplx vertex ids read from a manopth-labelled hand pick no tip.
  const Hand h = LabelledHand(ManoSource::kManopth, 1.0);
  const Joints21 wrong = ManoToOpenPose21(h.native16, h.verts, ManoSource::kSmplx);
  EXPECT_EQ(wrong(4, 0), -99);
}

TEST(ConventionsTest, ManoMillimetresAndMetresAgree) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-0.1, 0.1);
  Eigen::MatrixX3d joints_m(16, 3), verts_m(778, 3);
  for (int i = 0; i < joints_m.size(); ++i) joints_m.data()[i] = u(rng);
  for (int i = 0; i < verts_m.size(); ++i) verts_m.data()[i] = u(rng);
  // The same hand as manopth reports it: millimetres, its own tip vertex ids.
  Eigen::MatrixX3d verts_mm = verts_m * 1000.0;
  const auto smplx_tips = ManoFingertipVertices(ManoSource::kSmplx);
  const auto manopth_tips = ManoFingertipVertices(ManoSource::kManopth);
  for (int f = 0; f < 5; ++f) {
    verts_mm.row(manopth_tips[static_cast<size_t>(f)]) =
        verts_m.row(smplx_tips[static_cast<size_t>(f)]) * 1000.0;
  }
  const Joints21 a = ManoToOpenPose21(joints_m, verts_m, ManoSource::kSmplx);
  const Joints21 b = ManoToOpenPose21(joints_m * 1000.0, verts_mm, ManoSource::kManopth);
  EXPECT_LT((a - b).cwiseAbs().maxCoeff(), 1e-15);
  // A hand 8 cm from wrist to middle MCP, in both units.
  Joints21 hand = Joints21::Zero();
  hand.row(9) << 0, -0.08, 0;
  EXPECT_FALSE(JointsLookLikeMillimetres(hand));
  EXPECT_TRUE(JointsLookLikeMillimetres(hand * 1000.0));
}

TEST(ConventionsTest, ManoShapesAreChecked) {
  EXPECT_THROW(ManoToOpenPose21(Eigen::MatrixX3d::Zero(21, 3), Eigen::MatrixX3d::Zero(778, 3),
                                ManoSource::kSmplx),
               Error);
  EXPECT_THROW(ManoToOpenPose21(Eigen::MatrixX3d::Zero(16, 3), Eigen::MatrixX3d::Zero(700, 3),
                                ManoSource::kSmplx),
               Error);
}

TEST(ConventionsTest, TapirTracksAreXyAndQueriesTyx) {
  // Two points moving right by 2 px per frame; point i starts at x = 10 + i,
  // y = 50 + 5 i and is queried at frame i + 1.
  const int n = 2, t = 4;
  std::vector<float> tracks, query;
  std::vector<std::uint8_t> occluded;
  for (int i = 0; i < n; ++i) {
    for (int f = 0; f < t; ++f) {
      tracks.insert(tracks.end(), {10.0f + i + 2.0f * f, 50.0f + 5.0f * i});
      occluded.push_back(f == 3 && i == 0);
    }
    const float qx = 10.0f + i + 2.0f * (i + 1), qy = 50.0f + 5.0f * i;
    query.insert(query.end(), {static_cast<float>(i + 1), qy, qx});  // (t, y, x)
  }
  const PointTracks tr = TracksFromTapir(MakeArray<float>({n, t, 2}, tracks),
                                         MakeArray<std::uint8_t>({n, t}, occluded),
                                         MakeArray<float>({n, 3}, query));
  for (int i = 0; i < n; ++i) {
    const int qt = TapirQueryFrame(tr.query.row(i).transpose());
    EXPECT_EQ(qt, i + 1);
    const Eigen::Vector2f q = TapirQueryPixel(tr.query.row(i).transpose());
    // The query lies on the track at its own frame.
    EXPECT_EQ(q.x(), tr.x(i, qt));
    EXPECT_EQ(q.y(), tr.y(i, qt));
    EXPECT_EQ(TapirQuery(qt, q.x(), q.y()), tr.query.row(i).transpose());
  }
  EXPECT_EQ(tr.x(1, 2), 15.0f);
  EXPECT_EQ(tr.y(1, 2), 55.0f);
  EXPECT_EQ(tr.visible(0, 3), 0);
  EXPECT_EQ(tr.visible(0, 2), 1);
  EXPECT_THROW(TracksFromTapir(MakeArray<float>({n, t, 2}, tracks),
                               MakeArray<std::uint8_t>({n, t - 1}, std::vector<std::uint8_t>(6)),
                               MakeArray<float>({n, 3}, query)),
               Error);
}

}  // namespace
}  // namespace doasido::recon
