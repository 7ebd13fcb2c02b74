// A person's prompt for the object a clip is about, as SAM2 takes one: a
// box around the object on one frame of the video, optionally with the
// object's category. A clip list carries it in the column kObjectBoxColumn
// (kept in the clip's metadata under that name); `doasido objects --seed`
// takes the same text. The objects stage starts a track there and follows
// it (objects/box_tracker.h BoxTracker::Seed, docs/objects.md).
//
// Text: "FRAME:X,Y,W,H[:CATEGORY]", several separated by ';' (one object
// boxed on several frames, or several objects). FRAME is the video file's
// frame index (not counted from the clip's start), X,Y the box's top-left
// corner and W,H its size in pixels of the video as displayed (W, H > 0);
// CATEGORY a category name the objects stage knows (checked there), empty
// for its default.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace doasido::ingest {

inline constexpr const char* kObjectBoxColumn = "object_box";

struct ObjectPrompt {
  std::int64_t frame = 0;
  double x = 0, y = 0, w = 0, h = 0;
  std::string category;  // empty: the objects stage's default
};

// Parses `text` into `out`. Returns "" when it is well formed, else what is
// wrong (for an error that names the clip or row and the field).
std::string ParseObjectPrompts(const std::string& text, std::vector<ObjectPrompt>* out);

}  // namespace doasido::ingest
