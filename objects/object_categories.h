// The object categories the Objectron box-landmark models know, their names
// (as ObjectObservation::category holds them) and the size assumed for each
// when no hand gives the scale (docs/objects.md, "Size priors", has the
// sources).
#pragma once

#include <cmath>
#include <optional>
#include <string>

#include <Eigen/Core>

namespace doasido::objects {

inline constexpr const char* kCategoryCup = "cup";  // coffee cups and mugs (one model)
inline constexpr const char* kCategorySneakers = "sneakers";
inline constexpr const char* kCategoryChair = "chair";
inline constexpr const char* kCategoryCamera = "camera";

struct CategoryPrior {
  std::string category;
  // A typical object's extents along the box's x (right), y (top) and z
  // (front) axes, metres. Only their geometric mean sets the scale: the
  // lifted box's proportions are the measurement, and which way a shoe's
  // length lies in the model's box is not fixed.
  Eigen::Vector3d size_m;
  bool rotationally_symmetric = false;  // about the box's y axis (cups): yaw is not observed
};

// The prior of `category`; nullopt for a category no model knows.
std::optional<CategoryPrior> FindCategory(const std::string& category);

// The geometric mean of three extents: the one number a prior fixes.
inline double CharacteristicSize(const Eigen::Vector3d& size) {
  return std::cbrt(size.x() * size.y() * size.z());
}

}  // namespace doasido::objects
