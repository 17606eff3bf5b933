// Learned loop-closure verifier (Stüde 2024 §3.2.1, Granström et al. 2009): AdaBoost with T = 50 decision
// stumps on the 41 pair features of two scan descriptors. It screens loop-closure candidates before geometric
// matching; adding a wrong loop is fatal, so the shipped threshold is chosen for a low false-positive rate.
// OpenCV (cv::ml::Boost) stays in src/loop_verifier.cpp.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "cairn/graph_slam/scan_descriptor.hpp"
#include "cairn/sim/types.hpp"

namespace cairn::graph_slam {

class LoopVerifier {
 public:
  /// An untrained verifier: score()/accept() throw std::logic_error. Copies share the (immutable) model.
  LoopVerifier();

  /// Reads a model written by save(). Throws std::runtime_error "<path>: <what>" if the file is missing,
  /// corrupt, not a cairn loop verifier, or of another format version.
  static LoopVerifier load(const std::string& path);
  /// The shipped model (models/loop_verifier.yml.gz): the build tree's models/ directory, then
  /// <prefix>/share/cairn_graph_slam/models for this library's install prefix and every prefix in
  /// $CMAKE_PREFIX_PATH / $COLCON_PREFIX_PATH. Throws std::runtime_error naming what was tried.
  static std::string defaultModelPath();
  /// load(defaultModelPath()).
  static LoopVerifier loadDefault();
  /// Writes the model (OpenCV FileStorage; ".gz" compresses). Throws std::runtime_error "<path>: <what>".
  void save(const std::string& path) const;

  /// Boosted sum Σ αₜ hₜ (Real AdaBoost, oriented so that higher = more likely the same place).
  double score(const ScanDescriptor& a, const ScanDescriptor& b) const;
  /// Same on precomputed pairFeatures() (kPairFeatureCount values; std::invalid_argument otherwise).
  double scorePairFeatures(const std::vector<double>& pair_features) const;
  /// score(a, b) >= threshold().
  bool accept(const ScanDescriptor& a, const ScanDescriptor& b) const;
  /// Logistic of the boosted sum, 1/(1+exp(-2·score)): Stüde's p_c (Real AdaBoost approximates half the log-odds).
  static double probability(double score);

  double threshold() const { return threshold_; }
  void setThreshold(double t) { threshold_ = t; }
  bool trained() const { return impl_ != nullptr; }
  int weakCount() const;
  /// The descriptor options the model was trained with (stored in the model file); compute descriptors with these.
  const DescriptorOptions& descriptorOptions() const;

  /// Trains Real AdaBoost with `weak_count` depth-1 trees (Stüde §3.2.1: T = 50). labels: 1 = same place,
  /// 0 = different. The threshold is left at 0 (use thresholdForFpr to pick one). Throws std::invalid_argument
  /// on empty/mismatched input, a wrong feature count, or a single class.
  static LoopVerifier train(const std::vector<std::vector<double>>& pair_features, const std::vector<int>& labels,
                            int weak_count = 50, const DescriptorOptions& descriptor_options = {});

 private:
  struct Impl;
  std::shared_ptr<const Impl> impl_;
  double threshold_ = 0.0;
};

// ---- Training data from CARMEN logs with corrected poses, and evaluation ---------------------------------

/// One scan of a log with its (corrected) laser pose and descriptor.
struct VerifierNode {
  double stamp = 0.0;
  sim::Pose2 pose;
  ScanDescriptor descriptor;
};

struct NodeSamplingOptions {
  double min_distance = 0.0;  ///< keep a scan only after the laser moved this far (m) or turned min_rotation
  double min_rotation = 0.0;  ///< (rad) since the last kept scan; 0/0 keeps every scan
};

/// Reads every FLASER/RLASER/ROBOTLASER1 scan with a pose from a CARMEN log (corrected logs: SLAM-corrected
/// laser poses). Throws sim::InputError (file:line) on unreadable logs or malformed lines.
std::vector<VerifierNode> loadVerifierNodes(const std::string& carmen_log, const DescriptorOptions& descriptor = {},
                                            const NodeSamplingOptions& sampling = {});

/// Pair labelling rule (documented in the README, section "Loop-closure verifier").
struct PairLabelOptions {
  double positive_distance = 1.0;   ///< positive: poses closer than this (m) ...
  double positive_heading = 0.7853981633974483;  ///< ... and headings within this (rad) when a scan's FOV < 350°
  double negative_distance = 3.0;   ///< negative: poses farther apart than this (m)
  double near_negative_distance = 10.0;  ///< "near" negatives: negative_distance < d ≤ this (inside a search radius)
  double near_negative_fraction = 0.5;   ///< share of sampled negatives drawn from the near ones
  double min_time_gap = 10.0;       ///< pairs closer in time than this (s) are skipped (not revisits)
  std::size_t max_positives = 5000;  ///< per log, sampled without replacement (seeded)
  std::size_t max_negatives = 5000;
  bool balance = true;              ///< negatives capped at the number of positives
  std::uint64_t seed = 1;
};

struct LabelledPairs {
  std::vector<std::vector<double>> features;  ///< pairFeatures() of each pair
  std::vector<int> labels;                    ///< 1 positive, 0 negative
  std::vector<std::pair<std::size_t, std::size_t>> nodes;  ///< indices into the node list
  std::size_t positives = 0, negatives = 0;
  std::size_t candidate_positives = 0, candidate_negatives = 0;  ///< before sampling
  void append(const LabelledPairs& other);  ///< concatenates (node indices keep referring to their own lists)
};

/// Labels pairs of nodes by the rule above and samples them deterministically (options.seed).
LabelledPairs labelPairs(const std::vector<VerifierNode>& nodes, const PairLabelOptions& options = {});

struct VerifierMetrics {
  std::size_t tp = 0, fp = 0, tn = 0, fn = 0;
  double tpr = 0.0, fpr = 0.0, precision = 0.0;
  double auc = 0.0;  ///< area under the ROC curve (ties counted half)
  double threshold = 0.0;
};

/// Scores all pairs and reports TPR/FPR/precision at the verifier's threshold and the ROC AUC.
VerifierMetrics evaluate(const LoopVerifier& verifier, const LabelledPairs& pairs);
/// ROC AUC of scores against 0/1 labels (Mann–Whitney U; ties count half). 0.5 if a class is missing.
double rocAuc(const std::vector<double>& scores, const std::vector<int>& labels);
/// Smallest threshold whose false-positive rate (score >= t among label-0 samples) is ≤ target_fpr.
double thresholdForFpr(const std::vector<double>& scores, const std::vector<int>& labels, double target_fpr);

}  // namespace cairn::graph_slam
