#include "retarget/dynamic/knot_spline.h"

#include <algorithm>
#include <cmath>

namespace doasido::retarget {

int KnotCount(double horizon, double knot_dt) {
  return static_cast<int>(std::ceil(horizon / knot_dt - 1e-9)) + 1;
}

void EvaluateKnots(const double* knots, int num_knots, int dim, double knot_dt, double t,
                   double* out) {
  const double u = std::max(0.0, t / knot_dt);
  const int k = static_cast<int>(u);
  if (k >= num_knots - 1) {
    std::copy(knots + (num_knots - 1) * dim, knots + num_knots * dim, out);
    return;
  }
  const double a = u - k;
  const double* lo = knots + k * dim;
  const double* hi = lo + dim;
  for (int i = 0; i < dim; ++i) out[i] = (1 - a) * lo[i] + a * hi[i];
}

}  // namespace doasido::retarget
