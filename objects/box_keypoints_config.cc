#include "objects/box_keypoints_config.h"

#include "core/config_check.h"
#include "objects/objectron_models.h"

namespace doasido::objects {

void CheckConfig(const BoxKeypointsConfig& c, const std::string& section) {
  std::vector<std::string> names;
  for (const ObjectCategory& category : ObjectCategories()) names.push_back(category.name);
  if (c.categories.empty()) {
    throw Error("bad_config", section + ".categories must name at least one category",
                {.field = section + ".categories"});
  }
  for (const std::string& name : c.categories) RequireOneOf(section, "categories", name, names);
  RequireInRange(section, "max_objects", c.max_objects, 1, 20);
  RequireInRange(section, "detect_every", c.detect_every, 1, 1000);
  RequireInRange(section, "idle_detect_every", c.idle_detect_every, 1, 1000);
  RequireInRange(section, "min_detection_score", c.min_detection_score, 0, 1);
  RequireInRange(section, "nms_iou", c.nms_iou, 0, 1);
  RequireInRange(section, "same_object_iou", c.same_object_iou, 0, 1);
  RequireInRange(section, "min_presence", c.min_presence, 0, 1);
  RequireInRange(section, "crop_scale", c.crop_scale, 1, 4);
  RequireInRange(section, "max_side", c.max_side, 128, 4096);
  RequireInRange(section, "hand_proposal_every", c.hand_proposal_every, 1, 1000);
  RequireInRange(section, "hand_proposal_offset", c.hand_proposal_offset, 0, 2);
  RequireInRange(section, "hand_rejoin_frames", c.hand_rejoin_frames, 0, 1000);
  RequireInRange(section, "prompt_max_missing_frames", c.prompt_max_missing_frames, 0, 1000);
  RequireInRange(section, "prompt_follow_side", c.prompt_follow_side, 16, 1024);
  RequireInRange(section, "prompt_follow_grid", c.prompt_follow_grid, 2, 30);
  RequireInRange(section, "prompt_follow_max_error", c.prompt_follow_max_error, 0.01, 100);
  RequireInRange(section, "prompt_follow_min_points", c.prompt_follow_min_points, 0, 1);
  RequireInRange(section, "prompt_max_jump", c.prompt_max_jump, 0.01, 10);
  if (c.hand_proposal_sizes.empty()) {
    throw Error("bad_config", section + ".hand_proposal_sizes must hold at least one size",
                {.field = section + ".hand_proposal_sizes"});
  }
  for (double size : c.hand_proposal_sizes) RequireInRange(section, "hand_proposal_sizes", size, 0.5, 8.0);
}

}  // namespace doasido::objects
