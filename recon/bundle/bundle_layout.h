// Internal to recon/: the names the bundle reader and writer share.
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "recon/bundle/bundle.h"

namespace doasido::recon::layout {

struct MaskPart {
  const char* part;    // name in ClipBundle::present and in error fields
  const char* folder;  // under masks/
};
inline constexpr MaskPart kMaskParts[] = {
    {"mask_object", "object"}, {"mask_hand_left", "hand_left"}, {"mask_hand_right", "hand_right"}};

// The ClipBundle member holding mask part i of kMaskParts.
inline std::vector<cv::Mat> ClipBundle::*MaskMember(int i) {
  switch (i) {
    case 0: return &ClipBundle::mask_object;
    case 1: return &ClipBundle::mask_hand_left;
    default: return &ClipBundle::mask_hand_right;
  }
}

}  // namespace doasido::recon::layout
