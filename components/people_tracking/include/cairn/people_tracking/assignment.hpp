// Optimal rectangular assignment (Hungarian / Kuhn-Munkres with potentials, O(n^2 m)).
#pragma once

#include <Eigen/Core>
#include <vector>

namespace cairn::people_tracking {

// Minimises the total cost over a one-to-one assignment of rows to columns. Entries >= forbidden are never
// assigned. Returns, per row, the column index or -1.
std::vector<int> solveAssignment(const Eigen::MatrixXd& cost, double forbidden = 1e9);

}  // namespace cairn::people_tracking
