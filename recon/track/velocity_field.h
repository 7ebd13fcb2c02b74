// The seam between the guided tracker (recon/track/guided_flow.h) and a
// flow-matching model of objects, SAM 3D's in the paper. The model's state
// is one vector of a shape block and a pose block, generated along the
// linear path x_t = (1 - t) x_0 + t x_1 from noise x_0 ~ N(0, I) at t = 0 to
// data x_1 at t = 1, by integrating dx/dt = v(x_t, t | c) where the
// condition c is the frame (its image, mask and point map).
//
// The pose block is kPoseDim = 7 values, as in a bundle's
// object/candidates.npz: translation xyz in metres (camera frame) then a
// quaternion wxyz. The model's samples are not unit quaternions; readers
// normalise them (PoseFromState).
#pragma once

#include <Eigen/Core>

#include "core/geometry.h"

namespace doasido::recon {

using StateMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

inline constexpr int kPoseDim = 7;

struct FlowLayout {
  int shape_dim = 0;  // the shape block comes first
  int pose_dim = kPoseDim;
  int dim() const { return shape_dim + pose_dim; }
};

class VelocityField {
 public:
  virtual ~VelocityField() = default;

  virtual FlowLayout Layout() const = 0;

  // v(x, t | frame) for every row of `x` (N x Layout().dim()), written to
  // `v` (resized). One call carries a whole batch of candidates: a remote
  // model answers it in one request. Throws Error naming what failed.
  virtual void Velocity(int frame, double t, const StateMatrix& x, StateMatrix* v) = 0;

  // The exact divergence of the pose block, tr(d v_pose / d x_pose), for
  // every row, for likelihood ranking (recon/track/pose_selection.h). A model
  // that cannot give it throws Error("unsupported").
  virtual void PoseDivergence(int frame, double t, const StateMatrix& x, Eigen::VectorXd* div);
  // Whether Velocity and PoseDivergence may run on several threads at once,
  // each on its own block of rows, with a row's answer independent of the
  // other rows (an in-process model). Then the sampler splits a batch over
  // its threads; otherwise (a server, which batches on its side) it sends
  // the whole batch in one call.
  virtual bool ConcurrentRows() const { return false; }
};

// The pose of a state row's pose block (quaternion normalised; a zero
// quaternion becomes the identity).
Pose PoseFromState(const FlowLayout& layout, const Eigen::Ref<const Eigen::RowVectorXd>& row);

// The pose block of `pose`: t xyz, q wxyz.
Eigen::Matrix<double, 1, kPoseDim> PoseBlock(const Pose& pose);

}  // namespace doasido::recon
