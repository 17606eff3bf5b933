// Initial guesses for graphs whose stored values are poor:
//  * odometry / spanning tree: breadth-first tree from the anchor pose over relative-pose factors, composing
//    the measurements (X_j = X_i * Z_ij);
//  * chordal: rotations from the linear chordal relaxation R_j = R_i R_ij (least squares over the rotation
//    matrix entries, then projection onto SO(2)/SO(3); Carlone et al., ICRA 2015), translations from the
//    linear least-squares problem t_j - t_i = R_i t_ij with those rotations fixed.
// The anchor is the first fixed pose, else the first pose; it keeps its value. Variables not connected to
// the anchor keep their values. Points are placed from their first pose-point observation.
#pragma once

#include <string>

#include "cairn/graph_slam/pose_graph.hpp"

namespace cairn::graph_slam {

enum class Initialization { kGuess, kOdometry, kChordal };

/// Parses "guess", "odometry", "chordal"; throws std::invalid_argument.
Initialization parseInitialization(const std::string& name);

void initializeOdometry(PoseGraph& graph);
/// Needs all relative-pose factors of one dimension (SE2 or SE3); throws std::invalid_argument otherwise.
void initializeChordal(PoseGraph& graph);
void initialize(PoseGraph& graph, Initialization method);

}  // namespace cairn::graph_slam
