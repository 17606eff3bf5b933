// The relative-pose accuracy metric of Kümmerle et al., "On Measuring the Accuracy of SLAM Algorithms"
// (Autonomous Robots 27(4), 2009), as used for the Freiburg benchmark logs (`aces.relations`, ...):
// for each manually verified relation (t1, t2, δ*) the estimated relation δ = x(t1)⁻¹·x(t2) is compared with
// δ*, E = δ*⁻¹·δ; translational error |E.t| (m), rotational error |E.θ| (rad). Reported as mean ± std over the
// relations (Hess et al. 2016, Table II, report the same "absolute" errors).
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "cairn/graph_slam/geometry.hpp"

namespace cairn::graph_slam {

struct Relation {
  double t1 = 0.0;
  double t2 = 0.0;
  Pose2 delta;  ///< pose of the scan at t2 in the frame of the scan at t1
  int line = 0; ///< 1-based line in the relations file
};

struct StampedPose {
  double stamp = 0.0;
  Pose2 pose;
};

/// Reads `t1 t2 x y z roll pitch yaw` lines (z, roll, pitch ignored: 2D). Blank lines and `#` comments are
/// skipped. Throws cairn::sim::InputError(file, line, what) on malformed lines or an unreadable file.
std::vector<Relation> readRelations(const std::string& path);
/// Reads `timestamp x y theta` lines (the `cairn slam run` poses.txt). Throws InputError like readRelations.
std::vector<StampedPose> readPoses(const std::string& path);
/// Writes `timestamp x y theta` lines with full precision.
void writePoses(const std::string& path, const std::vector<StampedPose>& poses);

struct RelationsOptions {
  /// Two stamps are the same scan if they differ by at most this (s). CARMEN stamps have µs resolution.
  double stamp_tolerance = 1e-4;
};

struct RelationsResult {
  std::size_t relations = 0;  ///< relations in the file
  std::size_t used = 0;       ///< relations whose both stamps have a pose
  std::size_t missing = 0;    ///< relations skipped because a stamp has no pose
  double trans_mean = 0.0, trans_std = 0.0;  ///< m
  double rot_mean = 0.0, rot_std = 0.0;      ///< rad
  double trans_max = 0.0, rot_max = 0.0;
  /// The first missing relation's file line (0 if none), for the message.
  int first_missing_line = 0;
};

/// Evaluates poses against relations. Poses need not be sorted. Relations whose stamps have no pose within the
/// tolerance are counted in `missing` (the caller decides whether that is an error).
RelationsResult evaluateRelations(const std::vector<Relation>& relations, std::vector<StampedPose> poses,
                                  const RelationsOptions& options = {});

/// Raw odometry of a CARMEN log as a trajectory: the robot (odometry) pose of every laser scan, stamped with the
/// scan's ipc timestamp (the same-run baseline of `cairn slam eval`). Throws sim::InputError (file:line).
std::vector<StampedPose> odometryTrajectory(const std::string& carmen_log);

struct TrajectoryAgreement {
  std::size_t corrected_scans = 0;  ///< laser scans in the corrected log
  std::size_t matched = 0;          ///< of those, found in the raw log (identical ranges) and in the poses
  double ate_rmse = 0.0;            ///< m, position RMSE after the best rigid 2D alignment
  double ate_max = 0.0;             ///< m
  double heading_rmse = 0.0;        ///< rad, after the alignment
};

/// Agreement of a trajectory with a "corrected" log (Radish/ple logs whose FLASER poses are a SLAM-corrected
/// trajectory of a subset of the raw log's scans, with their own time base): corrected scans are matched to
/// raw scans by identical range readings, the raw scan's stamp selects the pose, poses are turned into laser
/// poses with the raw log's laser mount, and the absolute trajectory error is taken after the least-squares
/// rigid alignment (Horn/Umeyama in 2D). Throws sim::InputError for unreadable logs.
TrajectoryAgreement compareWithCorrectedLog(const std::string& corrected_log, const std::string& raw_log,
                                            const std::vector<StampedPose>& poses, double stamp_tolerance = 1e-4);

}  // namespace cairn::graph_slam
