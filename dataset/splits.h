// Train/val/test splits made by video, so that no video is in two splits.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "dataset/version.h"

namespace doasido::dataset {

using SplitFractions = std::vector<std::pair<std::string, double>>;

// Parses "train=0.8,val=0.1,test=0.1". Names are [a-z0-9_]+ and distinct,
// fractions in [0, 1] summing to 1 (within 1e-6). Throws Error("bad_option")
// naming `--split` and the part at fault.
SplitFractions ParseSplits(const std::string& text);

// Sets every episode's `split`. Videos are taken in an order fixed by
// `seed` (a hash of seed and video key, so adding videos does not move the
// others), and each goes whole to the split whose episode count is furthest
// below its share of the episodes placed so far. The same episodes, seed
// and fractions give the same splits on any machine.
void AssignSplits(std::vector<Episode>& episodes, const SplitFractions& fractions,
                  std::int64_t seed);

}  // namespace doasido::dataset
