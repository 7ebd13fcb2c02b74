#include "objects/box_follower.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

namespace doasido::objects {

namespace {

// Lucas-Kanade's window and pyramid on the follower's frame: with the box
// ~48 px long a 9-px window holds a corner of it, and two levels above
// follow ~4 times the window's reach (a held cup moves up to ~5 px a frame
// there on 02_cups).
const cv::Size kWindow(9, 9);
constexpr int kLevels = 2;
const cv::TermCriteria kStop(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 20, 0.03);

double Median(std::vector<double> v) {
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

// The median ratio of the kept points' pairwise distances after to before:
// how much the box grew.
double MedianGrowth(const std::vector<cv::Point2f>& from, const std::vector<cv::Point2f>& to,
                    const std::vector<int>& kept) {
  std::vector<double> ratios;
  for (std::size_t a = 0; a < kept.size(); ++a) {
    for (std::size_t b = a + 1; b < kept.size(); ++b) {
      const double before = cv::norm(from[kept[a]] - from[kept[b]]);
      if (before > 1e-3) ratios.push_back(cv::norm(to[kept[a]] - to[kept[b]]) / before);
    }
  }
  return ratios.empty() ? 1.0 : Median(std::move(ratios));
}

}  // namespace

cv::Mat BoxFollower::Grey(const cv::Mat& frame) const {
  // Grey first: shrinking one channel costs a third of shrinking three.
  cv::Mat grey, small;
  cv::cvtColor(frame, grey, cv::COLOR_RGB2GRAY);
  if (scale_ >= 1.0) return grey;
  cv::resize(grey, small, {}, scale_, scale_, cv::INTER_AREA);
  return small;
}

void BoxFollower::Start(const cv::Mat& frame, const cv::Rect2d& box) {
  scale_ = std::min(1.0, config_.side / std::max(box.width, box.height));
  box_ = box;
  previous_ = Grey(frame);
}

bool BoxFollower::Follow(const cv::Mat& frame) {
  cv::Mat next = Grey(frame);
  const int n = config_.grid;
  from_.clear();
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {  // cell centres of an n x n grid over the box
      from_.emplace_back(static_cast<float>((box_.x + box_.width * (j + 0.5) / n) * scale_ - 0.5),
                         static_cast<float>((box_.y + box_.height * (i + 0.5) / n) * scale_ - 0.5));
    }
  }
  std::vector<unsigned char> ok, ok_back;
  std::vector<float> unused;
  cv::calcOpticalFlowPyrLK(previous_, next, from_, to_, ok, unused, kWindow, kLevels, kStop);
  cv::calcOpticalFlowPyrLK(next, previous_, to_, back_, ok_back, unused, kWindow, kLevels, kStop);
  previous_ = next;
  std::vector<int> kept;
  std::vector<double> dx, dy;
  for (std::size_t k = 0; k < from_.size(); ++k) {
    const double e = cv::norm(from_[k] - back_[k]);
    if (!ok[k] || !ok_back[k] || !(e <= config_.max_error)) continue;
    kept.push_back(static_cast<int>(k));
    dx.push_back(to_[k].x - from_[k].x);
    dy.push_back(to_[k].y - from_[k].y);
  }
  if (kept.size() < std::max<std::size_t>(2, std::ceil(config_.min_points * n * n))) return false;
  const double grow = MedianGrowth(from_, to_, kept);
  const double cx = box_.x + box_.width / 2 + Median(dx) / scale_;
  const double cy = box_.y + box_.height / 2 + Median(dy) / scale_;
  box_.width *= grow;
  box_.height *= grow;
  box_.x = cx - box_.width / 2;
  box_.y = cy - box_.height / 2;
  return box_.width > 1 && box_.height > 1;
}

}  // namespace doasido::objects
