// Controls parameterised by knots (SPIDER, seed appendix: knot_dt): K knots
// spaced `dt` apart from time 0 of a plan, linearly interpolated between
// knots and held beyond the last one. A plan covering a horizon H needs
// K = ceil(H / dt) + 1 knots.
#pragma once

#include <Eigen/Core>

namespace doasido::retarget {

using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// Knots needed to cover `horizon` seconds at spacing `knot_dt`.
int KnotCount(double horizon, double knot_dt);

// Writes the controls at time t (seconds from the first knot) into out[0..dim).
// `knots` is (K, dim), row-major, one row a knot; K >= 1. No allocation.
void EvaluateKnots(const double* knots, int num_knots, int dim, double knot_dt, double t,
                   double* out);

}  // namespace doasido::retarget
