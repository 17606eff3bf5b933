// Global 2D scan descriptor for loop-closure verification (Stüde 2024 §3.2.1 after Granström et al. 2009/2010):
// 32 rotation-invariant scalar features χᴵ of the scan's point set and 9 range histograms χᴵᴵ with bin sizes
// b₁..b₉, compared pairwise by |Δχᴵ| and Pearson's correlation of the histograms (41 pair features).
// No OpenCV here: the classifier lives in loop_verifier.hpp / src/loop_verifier.cpp.
#pragma once

#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include "cairn/sim/types.hpp"

namespace cairn::graph_slam {

inline constexpr std::size_t kScalarFeatureCount = 32;  // Stüde §3.2.1: "32 features are computed"
inline constexpr std::size_t kHistogramCount = 9;       // Stüde §3.2.1: "nine varying bin sizes b_1:9"
inline constexpr std::size_t kPairFeatureCount = kScalarFeatureCount + kHistogramCount;  // 41

struct DescriptorOptions {
  /// r_max (Stüde §3.2.1): readings farther than this, and beams without a return (+inf), become points at
  /// r_max ("translated towards the origin so that r_k = r_max"). Not stated in the thesis for 2D: chosen.
  double max_range = 30.0;
  /// Readings at or below this (and NaN, negative, zero) are invalid beams and are dropped.
  double min_range = 0.05;
  /// Beams are resampled to this angular step (rad) before the features are computed, so 180- and 360-beam
  /// scanners over the same FOV give comparable descriptors (the beam nearest each bin centre is kept).
  /// Scans coarser than this keep their own step.
  double angular_resolution = 0.017453292519943295;  // 1°
  /// b₁..b₉ of the range histograms (m); Granström et al. 2009 (range histograms of 2D scans).
  std::array<double, kHistogramCount> histogram_bin_sizes{0.1, 0.25, 0.5, 0.75, 1.0, 1.5, 2.0, 2.5, 3.0};
  /// Consecutive points farther apart than these (m) start a new segment ("gaps", Granström et al. 2009).
  std::array<double, 3> gap_distances{0.5, 1.0, 3.0};
};

/// χ = (χᴵ, χᴵᴵ) of one scan (Stüde eq. 3.7).
struct ScanDescriptor {
  std::vector<double> scalars;                  ///< kScalarFeatureCount values, see scalarFeatureNames()
  std::vector<std::vector<double>> histograms;  ///< kHistogramCount normalized histograms (each sums to 1, or all 0)
  int points = 0;                               ///< resampled beams used (valid or clamped to r_max)
  double fov = 0.0;                             ///< angular extent of the scan (rad), angle_max - angle_min + inc
};

/// Names of the 32 scalar features, in order (for model files and the README table).
const std::vector<std::string>& scalarFeatureNames();

/// Computes the descriptor. Invalid beams (NaN, ≤ min_range) are skipped; a scan without valid beams gives
/// all-zero features. Throws std::invalid_argument on a malformed scan (angle_increment ≤ 0 or not finite,
/// no beams) or bad options.
ScanDescriptor computeDescriptor(const sim::LaserScan& scan, const DescriptorOptions& o = {});

/// The 41 pair features: |χᴵ_a − χᴵ_b| (32) then Pearson's correlation of each histogram pair (9; 0 if either
/// histogram is constant). Symmetric in a, b. Throws std::invalid_argument if the descriptors' sizes differ.
std::vector<double> pairFeatures(const ScanDescriptor& a, const ScanDescriptor& b);

/// Pearson's correlation coefficient of two equally long sequences; 0 if either has zero variance.
double pearsonCorrelation(const std::vector<double>& a, const std::vector<double>& b);

}  // namespace cairn::graph_slam
