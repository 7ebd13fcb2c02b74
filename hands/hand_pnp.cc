#include "hands/hand_pnp.h"

#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

namespace doasido::hands {

std::optional<HandPose> SolveHandPose(const HandObservation& hand, const Mat3& K) {
  std::vector<cv::Point3d> object;
  std::vector<cv::Point2d> image;
  for (int j = 0; j < kJoints; ++j) {
    if (hand.confidence[j] < 0.05) continue;
    object.emplace_back(hand.world[j].x(), hand.world[j].y(), hand.world[j].z());
    image.emplace_back(hand.uv[j].x(), hand.uv[j].y());
  }
  if (object.size() < 6) return std::nullopt;
  cv::Mat k;
  cv::eigen2cv(K, k);
  cv::Mat rvec, tvec;
  bool ok = false;
  try {
    ok = cv::solvePnP(object, image, k, cv::noArray(), rvec, tvec, false, cv::SOLVEPNP_SQPNP);
  } catch (const cv::Exception&) {
    ok = false;
  }
  if (!ok) return std::nullopt;
  cv::Mat r;
  cv::Rodrigues(rvec, r);
  HandPose pose;
  cv::cv2eigen(r, pose.R);
  cv::cv2eigen(tvec, pose.t);
  if (!(pose.t.z() > 0) || !pose.t.allFinite()) return std::nullopt;
  for (int j = 0; j < kJoints; ++j) pose.joints[j] = pose.R * hand.world[j] + pose.t;
  return pose;
}

}  // namespace doasido::hands
