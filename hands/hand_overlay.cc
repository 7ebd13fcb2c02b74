#include "hands/hand_overlay.h"

#include <algorithm>
#include <cstdio>

#include <opencv2/imgproc.hpp>

#include "hands/hand_observation.h"

namespace doasido::hands {

void DrawHands(cv::Mat& bgr, const Json& frame_entry, int width, int height) {
  const double sx = static_cast<double>(bgr.cols) / width, sy = static_cast<double>(bgr.rows) / height;
  const int thick = std::max(1, static_cast<int>(std::lround(std::max(bgr.cols, bgr.rows) / 400.0)));
  for (const Json& hand : frame_entry.at("hands")) {
    const bool right = hand.at("side") == "right";
    const bool filled = hand.value("filled", false);
    const cv::Scalar colour = right ? cv::Scalar(40, 40, 230) : cv::Scalar(230, 120, 30);
    std::vector<cv::Point> p;
    for (const Json& uv : hand.at("keypoints_2d")) {
      p.emplace_back(static_cast<int>(std::lround(uv.at(0).get<double>() * sx)),
                     static_cast<int>(std::lround(uv.at(1).get<double>() * sy)));
    }
    const int line = filled ? std::max(1, thick / 2) : thick;
    for (int j = 1; j < kJoints; ++j) cv::line(bgr, p[j], p[kParent[j]], colour, line, cv::LINE_AA);
    for (int j = 0; j < kJoints; ++j) cv::circle(bgr, p[j], line + 1, cv::Scalar(255, 255, 255), -1, cv::LINE_AA);
    char label[64];
    std::snprintf(label, sizeof label, "%s %.2f%s", right ? "R" : "L", hand.value("score", 0.0),
                  filled ? " filled" : "");
    cv::putText(bgr, label, p[0] + cv::Point(4 * thick, 4 * thick), cv::FONT_HERSHEY_SIMPLEX,
                0.4 * thick, colour, line, cv::LINE_AA);
  }
}

}  // namespace doasido::hands
