// `dataset diff vA vB`: which episodes a newer version added, removed or
// changed, and why (a re-threshold, a person's verdict, new stage
// parameters, new files), from the two manifests alone.
#pragma once

#include <string>
#include <vector>

#include "dataset/version.h"

namespace doasido::dataset {

struct EpisodeChange {
  enum class Kind { kAdded, kRemoved, kChanged };
  Kind kind = Kind::kChanged;
  std::int64_t clip_id = 0;
  std::string external_id;
  std::vector<std::string> reasons;  // at least one
};
const char* ToString(EpisodeChange::Kind kind);

// Episodes are matched by clip id. A changed episode differs in a stage's
// verdict, its human verification, its split or the content of its files
// (then stages with new parameters are named too); an episode whose stages
// only got new parameters (a re-threshold that kept its verdict) is not
// listed. A removed or added episode names the stage that decided it.
std::vector<EpisodeChange> DiffVersions(const Manifest& a, const Manifest& b);

}  // namespace doasido::dataset
