// CARMEN log playback: a streaming reader (constant memory) for the text logs of the Freiburg SLAM
// evaluation / Radish data sets, plain, gzip or bzip2 (detected from the file's magic bytes).
//
// Records: FLASER / RLASER (`n r1..rn x y theta odom_x odom_y odom_theta ipc_ts host logger_ts`),
// ROBOTLASER1 (`laser_type start_angle fov resolution max_range accuracy remission_mode n r1..rn
// m i1..im laser_x laser_y laser_theta robot_x robot_y robot_theta tv rv forward_safety side_safety
// turn_axis ipc_ts host logger_ts`), RAWLASER1..4 (as ROBOTLASER1 up to the remissions, then
// `ipc_ts host logger_ts`), ODOM (`x y theta tv rv accel ipc_ts host logger_ts`). PARAM, SYNC, NEFF,
// TRUEPOS, comments and unknown message names are skipped. Stamps are the ipc timestamps (sensor time).
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <variant>

#include "cairn/sim/types.hpp"
#include "cairn/sim/world.hpp"  // InputError

namespace cairn::sim {

struct CarmenLaser {
  std::string message;     ///< FLASER, RLASER, ROBOTLASER1, RAWLASER1..4
  LaserScan scan;          ///< stamp = ipc timestamp; ranges >= max range are +inf
  bool has_pose = false;   ///< RAWLASER has no poses
  Pose2 laser_pose;        ///< pose of the laser (FLASER: x y theta; corrected logs: corrected pose)
  Pose2 robot_pose;        ///< odometry pose of the robot at scan time
  double logger_stamp = 0.0;
  std::string host;
};

struct CarmenOdom {
  Pose2 pose;
  double tv = 0.0, rv = 0.0, accel = 0.0;
  double stamp = 0.0;
  double logger_stamp = 0.0;
  std::string host;
};

using CarmenRecord = std::variant<CarmenLaser, CarmenOdom>;

/// How FLASER/RLASER angles are laid out (the message carries only the beam count). Default: the
/// scan covers 180° starting at -90° (RLASER: +90°, i.e. pointing backwards); with an even beam count
/// (180, 360) the increment is fov/n, with an odd one (181, 361) fov/(n-1).
struct CarmenLaserLayout {
  double fov = 3.14159265358979323846;
  double max_range = 81.9;   ///< SICK LMS: readings at/above this are "no return"
  double range_min = 0.0;
};

enum class CarmenLineStatus { Record, Skipped, Malformed };

/// Parses one log line (no trailing newline needed). On Malformed, `error` says what is wrong.
/// Never throws; this is the fuzz target's entry point.
CarmenLineStatus parseCarmenLine(std::string_view line, const CarmenLaserLayout& layout, CarmenRecord& out,
                                 std::string& error);

struct CarmenReaderOptions {
  bool skip_malformed = false;  ///< false: a malformed line throws InputError(file, line, ...)
  CarmenLaserLayout layout;
  /// Called for each skipped malformed line when skip_malformed is set (default: nothing).
  std::function<void(const InputError&)> on_warning;
  std::size_t max_line_length = 1 << 20;  ///< longer lines are malformed (bounded memory)
};

struct CarmenStats {
  std::size_t lines = 0;
  std::size_t lasers = 0;
  std::size_t odoms = 0;
  std::size_t skipped = 0;    ///< comments, PARAM, unknown messages
  std::size_t malformed = 0;  ///< only counted with skip_malformed
};

class CarmenReader {
 public:
  /// Opens the log; throws InputError(path, 0, ...) if it cannot be opened.
  explicit CarmenReader(const std::string& path, CarmenReaderOptions options = {});
  ~CarmenReader();
  CarmenReader(const CarmenReader&) = delete;
  CarmenReader& operator=(const CarmenReader&) = delete;

  /// Next laser or odometry record in file order; false at the end of the log.
  bool next(CarmenRecord& record);
  const CarmenStats& stats() const { return stats_; }
  std::size_t lineNumber() const { return stats_.lines; }

 public:
  class Source;  ///< decompressing byte source (implementation detail)

 private:
  bool readLine(std::string& line);
  std::string path_;
  CarmenReaderOptions options_;
  std::unique_ptr<Source> source_;
  std::string buffer_;
  std::size_t buffer_pos_ = 0;
  bool eof_ = false;
  CarmenStats stats_;
};

/// Stamp of a record.
inline double stampOf(const CarmenRecord& r) {
  return std::holds_alternative<CarmenLaser>(r) ? std::get<CarmenLaser>(r).scan.stamp : std::get<CarmenOdom>(r).stamp;
}

}  // namespace cairn::sim
