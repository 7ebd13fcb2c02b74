#include "objects/object_categories.h"

#include <vector>

namespace doasido::objects {

std::optional<CategoryPrior> FindCategory(const std::string& category) {
  // docs/objects.md "Size priors" gives where each figure comes from.
  static const std::vector<CategoryPrior> kPriors = {
      {kCategoryCup, Eigen::Vector3d(0.082, 0.095, 0.082), true},   // an 11 oz mug
      {kCategorySneakers, Eigen::Vector3d(0.10, 0.11, 0.29), false},    // an adult's shoe
      {kCategoryChair, Eigen::Vector3d(0.50, 0.85, 0.55), false},   // a dining chair
      {kCategoryCamera, Eigen::Vector3d(0.13, 0.10, 0.10), false},  // a camera with a lens
  };
  for (const CategoryPrior& p : kPriors) {
    if (p.category == category) return p;
  }
  return std::nullopt;
}

}  // namespace doasido::objects
