// A person's object prompts (ingest/object_prompt.h: a list row's
// object_box, the command's --seed) as the tracker's seed boxes.
#pragma once

#include <string>
#include <vector>

#include "objects/box_tracker.h"

namespace doasido::objects {

// The seed boxes `text` gives (category cup where it names none). Throws
// Error(kBadObjectBox, core/error_codes.h; permanent) naming `clip` and
// `field` when it is malformed or names a category no model knows.
std::vector<SeedBox> SeedsFromPrompt(const std::string& text, const std::string& clip,
                                     const std::string& field);

}  // namespace doasido::objects
