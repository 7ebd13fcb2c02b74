// Kinematic retargeting (seed section 3.2 and appendix "Robust Kinematic
// Retargeting"): per frame, the floating-wrist pose and finger joints whose
// mapped points (fingertips, optionally knuckles) match the human keypoints.
//
// Per frame it minimises, in the spirit of mink's damped least squares,
//   sum_i w_i |p_i(q) - x_i|^2 / sigma^2  +  lambda |q - q_prev|^2
// over q within the joint limits, where x_i = wrist + s (k_i - wrist) are
// the human keypoints scaled about the wrist by the human->robot scale s,
// and p_i(q) come from MuJoCo forward kinematics with Jacobians from mj_jac.
// The solver is Ceres' Levenberg-Marquardt with the analytic Jacobians, the
// joint limits as parameter bounds (with an active set: joints pushed against
// a limit are held there and the rest solved again, the first set being
// those the start already pushes against a limit) and optionally a Huber
// loss per point (robust_loss_scale, in sigma; off by default, since on the
// real-hand bench it did not lower the fingertip error). Each frame is
// solved from the previous frame's answer (warm start); a track's first
// frame and a frame after a jump (keypoints moved more than jump_distance)
// also from `restarts` random configurations (wrist from a Kabsch fit of
// the palm points, fingers uniform in their ranges); the lowest objective
// wins, which avoids the local minima a single start falls into (a thumb on
// the wrong side of a finger). Between jumps the warm start keeps the
// previous frame's basin, so further starts rarely win and cost 5x.
//
// Scale adaptation: s = sum_f L_robot(f) / sum_f L_human(f) over the mapped
// fingers other than the thumb, where L = |wrist -> knuckle| + straight
// finger length knuckle -> tip (robot at qpos0, whose fingers are straight;
// human: median bone lengths over the sequence). The thumb is left out
// because robot thumbs differ most in where they sit on the palm.
//
// Grasp terms (contact_weight > 0 and the object's poses given to Solve;
// the model must hold the body "object" with a free joint, as the
// dynamics-aware retargeting's scene does): the object is posed per frame
// and the hand's collision geoms get residuals on their signed distance d to
// the object's collision surface (object_surface.h GeomDistance). A
// fingertip whose human fingertip lies within contact_epsilon of the object
// has its fingertip geom pulled into it, sqrt(contact_weight) (d +
// contact_depth) / sigma: the position targets then squeeze what the human
// held. Only while kMinGraspFingertips or more fingertips touch: a single
// fingertip pressed into a free object pushes it (it tips a standing
// cylinder before the opposing finger arrives, and the grasp then closes on
// a tilted object and loses the lift). Every other geom is kept out,
// sqrt(contact_weight) min(0, d) / sigma.
// Scaling the human hand to the robot's moves its fingertips off the object
// it holds; without these terms the robot grasps beside it, or through it.
#pragma once

#include <filesystem>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/config.h"
#include "core/geometry.h"
#include "retarget/scene/object_surface.h"
#include "robot/embodiment.h"
#include "robot/trajectory/format.h"

namespace doasido::retarget {

// Fingertips that must touch the object together before the grasp terms
// press them into it (see "Grasp terms" above).
inline constexpr int kMinGraspFingertips = 2;

struct KinematicConfig {
  int restarts = 4;              // random starts at a track's start and after a jump, besides the warm start
  // m: a frame whose keypoints moved farther than this from the last solved
  // frame's (largest over the 21) is a jump and gets the random starts;
  // other frames are solved from the previous frame's answer alone.
  double jump_distance = 0.05;
  int max_iterations = 100;      // Levenberg-Marquardt iterations per start
  // Ceres' function and parameter tolerances: a start stops when an
  // iteration changes the objective (relative) or q by less (1e-12 before
  // 2026-11-28: iterations that moved fingertips by micrometres).
  double tolerance = 1e-6;
  double sigma = 0.01;           // m: position residual unit
  double smooth_weight = 1e-3;   // lambda, per rad^2 (or m^2) of change from the previous frame
  bool use_intermediate = true;  // also match knuckles and other non-fingertip points
  double scale = 0;              // > 0 fixes s; 0 uses the embodiment's, else adapts
  unsigned seed = 0;             // random starts
  double wrist_noise_rad = 0.3;  // spread of random starts' wrist rotation
  double wrist_noise_m = 0.01;   // and translation
  double robust_loss_scale = 0;  // > 0: Huber threshold per point, in sigma
  // Grasp terms, used when Solve is given the object's poses (see the
  // header comment); 0 turns them off.
  double contact_weight = 0;
  double contact_epsilon = 0.02;   // m: a human fingertip this close to the object touches it
  double contact_depth = 0.002;    // m: how far a touching fingertip geom is asked into the object
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(KinematicConfig, restarts, jump_distance, max_iterations, tolerance, sigma,
                                                smooth_weight, use_intermediate, scale, seed,
                                                wrist_noise_rad, wrist_noise_m, robust_loss_scale,
                                                contact_weight, contact_epsilon, contact_depth)

struct FrameSolution {
  Eigen::VectorXd qpos;
  double objective = 0;        // the minimised objective
  double fingertip_mean = 0;   // m
  double fingertip_max = 0;    // m
  int best_start = 0;          // 0 = warm start (or Kabsch start on the first frame)
};

class KinematicRetargeter {
 public:
  // `hand` must outlive the retargeter and have a floating base.
  KinematicRetargeter(const HandModel& hand, KinematicConfig config = {});

  // Sets and returns s for `human` (see the header comment).
  double AdaptScale(const std::vector<Keypoints21>& human);
  void set_scale(double s) { scale_ = s; }
  double scale() const { return scale_; }

  // Solves one frame. `previous` (size nq) is the warm start and the target
  // of the smoothness term; without it the first start is the Kabsch wrist
  // fit with fingers at qpos0 and no smoothness term. `restarts` < 0 means
  // config.restarts.
  FrameSolution SolveFrame(const Keypoints21& human, const Eigen::VectorXd* previous,
                           int restarts = -1);

  // Solves a sequence (scale adapted first unless fixed): the first valid
  // frame and every jump (jump_distance) with the random restarts, the
  // others from the previous answer alone. Frames with valid[t] false hold
  // the previous pose. `valid` may be empty (all valid).
  // `progress` (may be empty) is called with the number of frames done
  // after each frame. `object` (one pose per frame, or null) turns on the
  // grasp terms (header comment); `contacts` (may be null) receives, per
  // frame, how many robot fingertips were asked to touch the object.
  HandTrajectory Solve(const std::vector<Keypoints21>& human, const std::vector<bool>& valid,
                       double fps, const std::function<void(std::size_t)>& progress = {},
                       const std::vector<Pose>* object = nullptr,
                       std::vector<int>* contacts = nullptr);

  // The frames of the last Solve that got the random starts (a track's
  // first valid frame and every jump), ascending.
  const std::vector<std::size_t>& restart_frames() const { return restart_frames_; }

  // Poses the object for the next SolveFrame calls and chooses the grasp
  // terms from `human` (unscaled); returns the number of touching
  // fingertips (0 when fewer than kMinGraspFingertips touch). No-op
  // returning 0 without grasp terms.
  int PoseObject(const Keypoints21& human, const Pose& object);
  // The signed distance of a world point to the posed object (m; +inf
  // without an object).
  double ObjectDistance(const Vec3& p) const;
  // The grasp terms the last PoseObject chose, each with its geom's signed
  // distance to the object (ObjectSurface::GeomDistance) with the hand at `qpos`.
  struct GraspGap {
    int geom = -1;
    bool touch = false;  // else kept out
    double distance = 0; // m
  };
  std::vector<GraspGap> GraspGaps(const Eigen::VectorXd& qpos);

  // Names of the variables, the order of FrameSolution::qpos.
  std::vector<std::string> VariableNames() const;
  // Robot positions of the mapped points (in description order) at `qpos`.
  std::vector<Vec3> Points(const Eigen::VectorXd& qpos);
  // The human keypoints scaled by scale_ about the wrist (keypoint 0).
  Keypoints21 Reference(const Keypoints21& human) const;
  // Reference's rows of the mapped points, in description order.
  std::vector<Vec3> Targets(const Keypoints21& human) const;

 private:
  double Objective(const Eigen::VectorXd& q, const std::vector<Vec3>& targets,
                   const Eigen::VectorXd* previous, Eigen::VectorXd* residual,
                   Eigen::MatrixXd* jacobian);
  Eigen::VectorXd Minimise(Eigen::VectorXd q, const std::vector<Vec3>& targets,
                           const Eigen::VectorXd* previous, double* objective);
  // One Ceres solve from q (in place) with the variables `held` constant.
  void SolveHolding(Eigen::VectorXd& q, const std::vector<Vec3>& targets,
                    const Eigen::VectorXd* previous, const std::vector<int>& held);
  // Variables at a limit that the objective's gradient pushes outward.
  std::vector<int> PushedAgainstLimits(const Eigen::VectorXd& q, const std::vector<Vec3>& targets,
                                       const Eigen::VectorXd* previous);
  static constexpr int kActiveSetRounds = 4;
  class PointEvaluator;
  Eigen::VectorXd KabschStart(const std::vector<Vec3>& targets) const;
  void Clamp(Eigen::VectorXd& q) const;

  const HandModel& hand_;
  KinematicConfig config_;
  DataPtr data_;
  double scale_ = 1.0;
  std::vector<int> qpos_adr_, dof_adr_;  // per variable: wrist (6) then fingers
  std::vector<int> active_;            // indices into hand_.points that are matched
  std::vector<GraspGap> geom_terms_;   // this frame's grasp terms (distance unused)
  std::vector<int> hand_geoms_;        // the hand's geoms GeomDistance measures
  std::vector<int> tip_geom_;          // per active_ entry: its fingertip geom, or -1
  ObjectSurface surface_;
  int object_qpos_ = -1;               // the object's free joint, or -1
  std::vector<Vec3> palm_at_zero_;     // palm points at zero wrist, fingers at qpos0
  std::vector<int> palm_points_;       // indices into hand_.points (wrist + knuckles)
  Eigen::VectorXd lower_, upper_;      // per qpos; +-inf when unlimited
  std::mt19937 rng_;
  std::vector<std::size_t> restart_frames_;  // of the last Solve
};

}  // namespace doasido::retarget
