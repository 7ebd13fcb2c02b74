#include "recon/track/velocity_field.h"

#include "core/error.h"

namespace doasido::recon {

void VelocityField::PoseDivergence(int, double, const StateMatrix&, Eigen::VectorXd*) {
  throw Error("unsupported", "this velocity field gives no divergence (likelihood ranking needs it)");
}

Pose PoseFromState(const FlowLayout& layout, const Eigen::Ref<const Eigen::RowVectorXd>& row) {
  const int p = layout.shape_dim;
  Pose pose;
  pose.t = Vec3(row[p], row[p + 1], row[p + 2]);
  Quat q(row[p + 3], row[p + 4], row[p + 5], row[p + 6]);
  pose.q = q.norm() > 1e-12 ? q.normalized() : Quat::Identity();
  return pose;
}

Eigen::Matrix<double, 1, kPoseDim> PoseBlock(const Pose& pose) {
  Eigen::Matrix<double, 1, kPoseDim> out;
  out << pose.t.x(), pose.t.y(), pose.t.z(), pose.q.w(), pose.q.x(), pose.q.y(), pose.q.z();
  return out;
}

}  // namespace doasido::recon
