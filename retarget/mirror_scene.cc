#include "retarget/mirror_scene.h"

namespace doasido::retarget {

std::vector<Keypoints21> MirrorKeypoints(std::vector<Keypoints21> hand) {
  for (Keypoints21& k : hand) k.col(0) *= -1;
  return hand;
}

Pose MirrorPose(const Pose& pose) {
  Pose out;
  out.q = Quat(pose.q.w(), pose.q.x(), -pose.q.y(), -pose.q.z());
  out.t = Vec3(-pose.t.x(), pose.t.y(), pose.t.z());
  return out;
}

std::vector<Pose> MirrorPoses(std::vector<Pose> poses) {
  for (Pose& p : poses) p = MirrorPose(p);
  return poses;
}

TriMesh MirrorMesh(TriMesh mesh) {
  mesh.vertices.col(0) *= -1;
  mesh.faces.col(1).swap(mesh.faces.col(2));  // a reflection turns ccw into cw
  return mesh;
}

recon::Reconstruction MirrorLeftOntoRight(recon::Reconstruction r) {
  r.right_joints = MirrorKeypoints(std::move(r.left_joints));
  r.right_valid = std::move(r.left_valid);
  r.left_joints.clear();
  r.left_valid.clear();
  // Frames without a pose hold NaN: mirrored NaN stays NaN.
  r.object_poses = MirrorPoses(std::move(r.object_poses));
  return r;
}

}  // namespace doasido::retarget
