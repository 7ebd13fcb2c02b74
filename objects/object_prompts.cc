#include "objects/object_prompts.h"

#include "core/error.h"
#include "core/error_codes.h"
#include "ingest/object_prompt.h"
#include "objects/object_categories.h"

namespace doasido::objects {

std::vector<SeedBox> SeedsFromPrompt(const std::string& text, const std::string& clip,
                                     const std::string& field) {
  std::vector<ingest::ObjectPrompt> prompts;
  if (const std::string why = ingest::ParseObjectPrompts(text, &prompts); !why.empty()) {
    throw Error(kBadObjectBox, why, {.clip = clip, .field = field});
  }
  std::vector<SeedBox> seeds;
  for (const ingest::ObjectPrompt& p : prompts) {
    SeedBox seed{.frame = p.frame, .category = p.category.empty() ? kCategoryCup : p.category,
                 .box = cv::Rect2d(p.x, p.y, p.w, p.h)};
    if (!FindCategory(seed.category)) {
      throw Error(kBadObjectBox, "no model knows the category '" + seed.category + "'",
                  {.clip = clip, .field = field});
    }
    seeds.push_back(std::move(seed));
  }
  return seeds;
}

}  // namespace doasido::objects
