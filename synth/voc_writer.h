// 100DOH-style per-frame annotations as Pascal VOC XML (REFERENCE.md §1):
// one file per frame named <genre>_v_<video_id>_frame<6 digits>.xml, where
// the digits are the 0-based frame index in the video. Boxes are 1-based
// inclusive pixel coordinates. Hands carry <contactstate> (0 none, 1 self,
// 2 other person, 3 portable object, 4 stationary object), <handside> (0
// left, 1 right), the touched object's box <objxmin..objymax> ("None" when
// not in contact) and the hand->object offset <unitdx>, <unitdy> (unit
// vector) and <magnitude> (pixels). Objects carry <contactleft> and
// <contactright>.
#pragma once

#include <filesystem>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

namespace doasido::synth {

// A box in 0-based inclusive pixel coordinates.
struct PixelBox {
  int x0 = 0, y0 = 0, x1 = -1, y1 = -1;
  bool empty() const { return x1 < x0 || y1 < y0; }
  double cx() const { return 0.5 * (x0 + x1); }
  double cy() const { return 0.5 * (y0 + y1); }
};
// Bounding box of the non-zero pixels of a mask (empty when none).
PixelBox MaskBox(const cv::Mat& mask);

struct VocHand {
  int side = 1;  // 0 left, 1 right
  PixelBox box;
  int contact_state = 0;               // 0..4 as above
  std::optional<PixelBox> object_box;  // set when in contact
};

struct VocObject {
  PixelBox box;
  bool contact_left = false;
  bool contact_right = false;
};

struct VocFrame {
  std::string genre = "synth";
  std::string video_id;
  int frame = 0;
  int width = 0, height = 0;
  std::vector<VocHand> hands;
  std::vector<VocObject> objects;
};

// "<genre>_v_<video_id>_frame<%06d>".
std::string VocStem(const std::string& genre, const std::string& video_id, int frame);
std::string VocXml(const VocFrame& frame);
// Writes <dir>/<stem>.xml. Throws Error("io") naming the file.
void WriteVoc(const VocFrame& frame, const std::filesystem::path& dir);

}  // namespace doasido::synth
