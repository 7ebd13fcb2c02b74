#include "objects/box_overlay.h"

#include <algorithm>
#include <bitset>
#include <cmath>
#include <cstdio>
#include <iterator>

#include <opencv2/imgproc.hpp>

#include "objects/box_keypoints.h"
#include "objects/box_keypoints_json.h"

namespace doasido::objects {

namespace {

const cv::Scalar kTrackColours[] = {{0, 200, 255}, {255, 80, 200}, {80, 220, 80}, {255, 160, 40},
                                    {60, 60, 255}};

}  // namespace

void DrawObjects(cv::Mat& bgr, const Json& frame_entry, int width, int height) {
  const double sx = static_cast<double>(bgr.cols) / width, sy = static_cast<double>(bgr.rows) / height;
  const int thick = std::max(1, static_cast<int>(std::lround(std::max(bgr.cols, bgr.rows) / 500.0)));
  for (const Json& object : frame_entry.at("objects")) {
    if (object.contains(kKeypoints2dKey) && object.at(kKeypoints2dKey).is_null()) continue;  // filled, not seen
    const ObjectObservation o = ObservationFromJson(object, 0);
    const cv::Scalar colour = kTrackColours[o.track % std::size(kTrackColours)];
    std::vector<cv::Point> p;
    for (const Eigen::Vector2d& q : o.keypoints_2d) {
      p.emplace_back(static_cast<int>(std::lround(q.x() * sx)), static_cast<int>(std::lround(q.y() * sy)));
    }
    // Corners k, j (1-8) share an edge when k-1 and j-1 differ in one bit;
    // bit 0 set is the front face.
    for (int k = 1; k < kBoxKeypoints; ++k) {
      for (int j = k + 1; j < kBoxKeypoints; ++j) {
        if (std::bitset<3>((k - 1) ^ (j - 1)).count() != 1) continue;
        const bool front = ((k - 1) & 1) && ((j - 1) & 1);
        cv::line(bgr, p[k], p[j], colour, front ? 2 * thick : thick, cv::LINE_AA);
      }
    }
    cv::circle(bgr, p[0], 2 * thick, colour, -1, cv::LINE_AA);
    char label[80];
    std::snprintf(label, sizeof label, "%s %.3f #%d", o.category.c_str(), o.score, o.track);
    cv::putText(bgr, label, p[0] + cv::Point(4 * thick, -4 * thick), cv::FONT_HERSHEY_SIMPLEX,
                0.4 * thick, colour, thick, cv::LINE_AA);
  }
}

}  // namespace doasido::objects
