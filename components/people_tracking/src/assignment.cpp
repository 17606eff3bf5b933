#include "cairn/people_tracking/assignment.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace cairn::people_tracking {

namespace {
// Rows <= cols. Classic shortest augmenting path formulation with row/column potentials (1-based internally).
std::vector<int> hungarian(const Eigen::MatrixXd& a) {
  const int n = static_cast<int>(a.rows()), m = static_cast<int>(a.cols());
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<double> u(n + 1, 0.0), v(m + 1, 0.0), minv(m + 1);
  std::vector<int> p(m + 1, 0), way(m + 1, 0);
  std::vector<char> used(m + 1);
  for (int i = 1; i <= n; ++i) {
    p[0] = i;
    int j0 = 0;
    std::fill(minv.begin(), minv.end(), inf);
    std::fill(used.begin(), used.end(), 0);
    do {
      used[j0] = 1;
      const int i0 = p[j0];
      double delta = inf;
      int j1 = 0;
      for (int j = 1; j <= m; ++j) {
        if (used[j]) continue;
        const double cur = a(i0 - 1, j - 1) - u[i0] - v[j];
        if (cur < minv[j]) minv[j] = cur, way[j] = j0;
        if (minv[j] < delta) delta = minv[j], j1 = j;
      }
      for (int j = 0; j <= m; ++j) {
        if (used[j]) u[p[j]] += delta, v[j] -= delta;
        else minv[j] -= delta;
      }
      j0 = j1;
    } while (p[j0] != 0);
    do {
      const int j1 = way[j0];
      p[j0] = p[j1];
      j0 = j1;
    } while (j0);
  }
  std::vector<int> row_to_col(n, -1);
  for (int j = 1; j <= m; ++j)
    if (p[j]) row_to_col[p[j] - 1] = j - 1;
  return row_to_col;
}
}  // namespace

std::vector<int> solveAssignment(const Eigen::MatrixXd& cost, double forbidden) {
  const auto rows = cost.rows(), cols = cost.cols();
  std::vector<int> result(static_cast<std::size_t>(rows), -1);
  if (rows == 0 || cols == 0) return result;
  // Clamp forbidden entries to one finite big value so the potentials stay finite; a non-finite cost (NaN from a
  // degenerate covariance) is forbidden too — NaN compares false everywhere and the augmenting search would never end.
  const Eigen::MatrixXd c = cost.unaryExpr([forbidden](double x) { return std::isfinite(x) ? std::min(x, forbidden) : forbidden; });
  if (rows <= cols) {
    result = hungarian(c);
  } else {
    const std::vector<int> col_to_row = hungarian(c.transpose());
    for (std::size_t j = 0; j < col_to_row.size(); ++j)
      if (col_to_row[j] >= 0) result[static_cast<std::size_t>(col_to_row[j])] = static_cast<int>(j);
  }
  for (std::size_t i = 0; i < result.size(); ++i)
    if (result[i] >= 0 && !(c(static_cast<long>(i), result[i]) < forbidden)) result[i] = -1;
  return result;
}

}  // namespace cairn::people_tracking
