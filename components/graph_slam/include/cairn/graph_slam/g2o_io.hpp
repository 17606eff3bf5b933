// Reading and writing g2o pose-graph files: VERTEX_SE2, VERTEX_SE3:QUAT, VERTEX_XY, EDGE_SE2, EDGE_SE3:QUAT,
// EDGE_SE2_XY, EDGE_PRIOR_SE2, FIX. Information matrices are given as their upper triangle, row by row.
// Every problem is reported as G2oError naming file:line.
#pragma once

#include <cstddef>
#include <iosfwd>
#include <stdexcept>
#include <string>
#include <vector>

#include "cairn/graph_slam/pose_graph.hpp"

namespace cairn::graph_slam {

class G2oError : public std::runtime_error {
 public:
  G2oError(std::string file, std::size_t line, const std::string& what);
  const std::string& file() const { return file_; }
  std::size_t line() const { return line_; }  ///< 1-based; 0 if the error concerns the whole file
  const std::string& message() const { return message_; }

 private:
  std::string file_;
  std::size_t line_;
  std::string message_;
};

struct G2oReadOptions {
  enum class InformationFix { kReject, kClamp };
  /// kReject: a non symmetric-positive-definite information matrix is an error.
  /// kClamp: project it onto the nearest positive semidefinite matrix (eigenvalues clamped to
  /// max(lambda, 1e-9 * lambda_max) so the result stays invertible) and count it.
  InformationFix information_fix = InformationFix::kReject;
  /// Skip lines with unknown tags (counted, one warning per tag) instead of failing.
  bool skip_unknown_tags = false;
};

struct G2oReadReport {
  std::size_t clamped_information = 0;
  std::size_t skipped_lines = 0;
  std::vector<std::string> warnings;  ///< "file:line: ..." lines
};

/// Reads a g2o file. Throws G2oError (file:line) on malformed or truncated lines, non-numeric fields, NaN/Inf,
/// duplicate vertex ids, edges naming missing vertices, non-SPD information (unless clamped), unknown tags
/// (unless skipped), and when the file cannot be opened.
PoseGraph readG2o(const std::string& path, const G2oReadOptions& options = {}, G2oReadReport* report = nullptr);
/// Same, from a stream; `name` is used in error messages.
PoseGraph readG2o(std::istream& in, const std::string& name, const G2oReadOptions& options = {},
                  G2oReadReport* report = nullptr);

/// Writes vertices (in insertion order), FIX lines and edges with round-trip exact numbers.
/// SE3 priors and 3D points have no plain g2o tag here and are rejected with std::invalid_argument.
void writeG2o(const PoseGraph& graph, std::ostream& out);
void writeG2o(const PoseGraph& graph, const std::string& path);

}  // namespace cairn::graph_slam
