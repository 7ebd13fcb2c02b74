// Pictures of a robot hand for `doasido hand check`: the model's geometry at
// a pose, drawn with the project's CPU rasteriser (video/mesh_rasterizer.h),
// shaded by surface normal, one colour per finger chain (thumb orange, the
// other fingers blue to green, palm grey) and the description's points as
// dots (fingertips red, others yellow).
#pragma once

#include <filesystem>

#include <Eigen/Core>

#include "robot/hand_check.h"

namespace doasido::cli {

struct HandRenderOptions {
  int size = 480;  // square image, pixels
};

// Renders `check.model` at `qpos` (size nq) to a PNG at `path`. The view is
// fixed by the hand's rest geometry (fingers up, palm towards the viewer,
// turned a little), so the rest and the flexed pictures line up. Throws
// Error("io") when the PNG cannot be written.
void RenderHandPng(const retarget::HandCheck& check, const Eigen::VectorXd& qpos,
                   const std::filesystem::path& path, const HandRenderOptions& options = {});

}  // namespace doasido::cli
