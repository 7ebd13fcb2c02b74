#include "objects/hand_proposals.h"

namespace doasido::objects {

std::vector<cv::Rect2d> HandProposals(const HandPoints2d& hand, const HandProposalConfig& config,
                                      double min_palm_px) {
  const double palm = (hand[9] - hand[0]).norm();
  std::vector<cv::Rect2d> boxes;
  if (!(palm >= min_palm_px)) return boxes;
  const Eigen::Vector2d grasp = (hand[4] + hand[8] + hand[12]) / 3.0;
  const int reach = config.offset > 0 ? 1 : 0;
  for (double size : config.sizes) {
    const double side = size * palm;
    for (int dy = -reach; dy <= reach; ++dy) {
      for (int dx = -reach; dx <= reach; ++dx) {
        const Eigen::Vector2d c = grasp + config.offset * palm * Eigen::Vector2d(dx, dy);
        boxes.emplace_back(c.x() - side / 2, c.y() - side / 2, side, side);
      }
    }
  }
  return boxes;
}

}  // namespace doasido::objects
