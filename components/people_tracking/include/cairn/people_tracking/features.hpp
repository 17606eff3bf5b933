// Per-cluster geometric features (Arras, Mozos, Burgard, ICRA 2007 style) and a versioned feature registry.
//
// The registry is append-only: a feature's index and definition never change once released. A FeatureSet names
// a subset by feature name; model files store the set key ("name@version") and the feature names, so a model
// trained on one definition cannot silently be applied to another.
#pragma once

#include <array>
#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include "cairn/people_tracking/segmentation.hpp"

namespace cairn::people_tracking {

enum class Feature : std::size_t {
  kNumPoints = 0,          // n
  kStdFromCentroid,        // sqrt(sum |p - c|^2 / (n - 1))   (second moment / inertia about the centroid)
  kMeanAbsDevMedian,       // mean |p - median| (component-wise median point)
  kJumpPrev,               // distance to the preceding valid return (capped)
  kJumpNext,               // distance to the following valid return (capped)
  kWidth,                  // |p_first - p_last|
  kLinearity,              // sum of squared orthogonal residuals of a total-least-squares line fit
  kCircularity,            // sum of squared residuals (|p - c| - r)^2 of an algebraic circle fit
  kCircleRadius,           // r of that fit (clamped to 10 m for collinear points)
  kBoundaryLength,         // sum |p_{i+1} - p_i|
  kBoundaryRegularity,     // standard deviation of |p_{i+1} - p_i|
  kMeanCurvature,          // mean Menger curvature of consecutive triples (1/m)
  kMeanAngularDifference,  // mean |angle| between successive boundary vectors (rad)
  kDistance,               // |centroid| (distance to sensor)
  kCount
};
inline constexpr std::size_t kNumFeatures = static_cast<std::size_t>(Feature::kCount);
inline constexpr int kFeatureRegistryVersion = 1;

struct FeatureInfo {
  std::string_view name;
  std::string_view description;
};

// All registered features, indexed by Feature.
const std::array<FeatureInfo, kNumFeatures>& featureRegistry();

using FeatureVector = std::array<double, kNumFeatures>;

// Computes every registered feature of one cluster (sensor frame). Clusters with fewer than 3 points get
// zeros for the fit-based features.
FeatureVector computeFeatures(const Cluster& cluster);

struct FeatureSet {
  std::string name;
  int version = 1;
  std::vector<Feature> features;
  [[nodiscard]] std::string key() const { return name + "@" + std::to_string(version); }
  [[nodiscard]] std::vector<float> select(const FeatureVector& all) const;
  [[nodiscard]] std::vector<std::string> featureNames() const;
};

// Registered sets:
//  "arras14@1": all 14 features above.
//  "stuede5@1": number of points, distance to sensor, second moment about the centroid, width, circularity.
//     Stüde §2.1.3 names a 5-feature SVM (subset of [NMH10; KMW+11], combination from [YDB17]) and lists
//     "number of points, distance to sensor, moment of the inertia tensor" as examples; the other two are our
//     choice from the same Arras-style list.
// Throws InputError for an unknown key.
FeatureSet featureSet(std::string_view key);
std::vector<std::string> featureSetKeys();

}  // namespace cairn::people_tracking
