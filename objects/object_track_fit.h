// One object track's metric poses, smoothed with the motion model the hands
// stage's skeleton fit uses (hands/hand_skeleton_fit.h): one Ceres problem
// whose unknowns are the box's rotation and centre on every frame of the
// track, its extents fixed (one rigid size per track), with residuals
//   - each observed keypoint's reprojection, in sigmas of the box's image
//     size, under a Huber loss (a thin-slab frame of a round object only its
//     axis: the centre and the top- and bottom-face centres);
//   - the centre's acceleration (t[k+1] - 2 t[k] + t[k-1]) fps² and the
//     rotation's (the change of the relative rotation between frames) fps².
// Frames without an observation get only the motion terms: the fit fills
// them in from their neighbours.
#pragma once

#include <optional>
#include <vector>

#include "core/geometry.h"
#include "objects/box_lifting.h"
#include "objects/objects_config.h"

namespace doasido::objects {

struct TrackFrame {
  std::optional<BoxKeypoints> keypoints;  // nullopt: a gap to fill
  bool axis_only = false;                 // a thin-slab reading of a round object
  Pose start;                             // initial metric pose (object -> camera)
};

// The fitted poses, one per frame. `size` metric extents, fps > 0.
std::vector<Pose> FitTrackPoses(const std::vector<TrackFrame>& frames, const Vec3& size,
                                const Mat3& K, double fps, const ObjectFitConfig& config);

}  // namespace doasido::objects
