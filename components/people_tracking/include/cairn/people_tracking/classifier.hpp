// Learned leg/person cluster classifiers: AdaBoost over decision stumps and an RBF SVM (OpenCV cv::ml behind a
// pimpl; OpenCV never appears in this header). Model files are OpenCV YAML with cairn metadata: format tag,
// classifier kind, feature-set key and names, feature standardisation, score sign and threshold.
#pragma once

#include <cstddef>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "cairn/people_tracking/features.hpp"
#include "cairn/people_tracking/scene.hpp"
#include "cairn/people_tracking/segmentation.hpp"

namespace cairn::people_tracking {

enum class ClassifierKind { kAdaBoost, kSvm };
const char* toString(ClassifierKind k);
ClassifierKind classifierKindFromString(const std::string& s);  // "adaboost" | "svm"; throws InputError

struct LabelledCluster {
  FeatureVector features{};
  bool positive = false;
  ObjectClass object_class = ObjectClass::kClutter;
  int scene = -1;
};

struct ClassifierTrainParams {
  ClassifierKind kind = ClassifierKind::kAdaBoost;
  std::string feature_set = "arras14@1";
  int boost_weak_count = 150;  // number of decision stumps (depth-1 trees), Real AdaBoost
  double svm_c = 10.0;         // RBF SVM on standardised features
  double svm_gamma = 0.1;
  double positive_weight = 1.0;  // SVM class weight of the positive class
};

struct ClassifierMetrics {
  std::size_t tp = 0, fp = 0, tn = 0, fn = 0;
  [[nodiscard]] double precision() const { return tp + fp ? double(tp) / double(tp + fp) : 0.0; }
  [[nodiscard]] double recall() const { return tp + fn ? double(tp) / double(tp + fn) : 0.0; }
  [[nodiscard]] double f1() const {
    const double p = precision(), r = recall();
    return p + r > 0 ? 2 * p * r / (p + r) : 0.0;
  }
};

class LegClassifier {
 public:
  LegClassifier(LegClassifier&&) noexcept;
  LegClassifier& operator=(LegClassifier&&) noexcept;
  ~LegClassifier();

  // Throws InputError when there are no samples of one class or the feature set is unknown.
  static LegClassifier train(const std::vector<LabelledCluster>& samples, const ClassifierTrainParams& params);
  // Throws InputError when the file is missing, corrupt, of another format or names unknown features.
  static LegClassifier load(const std::string& path);
  void save(const std::string& path) const;
  // InputError if `path` cannot be written (checked by save(); tools call it before a long training). Creates the
  // file if it does not exist and leaves an existing one unchanged.
  static void checkWritable(const std::string& path);

  // Person-likeness in [0, 1]; 0.5 is the decision boundary of the trained model.
  [[nodiscard]] double score(const FeatureVector& features) const;
  [[nodiscard]] ClassifierKind kind() const;
  [[nodiscard]] const FeatureSet& featureSet() const;
  [[nodiscard]] ClassifierMetrics evaluate(const std::vector<LabelledCluster>& samples, double threshold = 0.5) const;

 private:
  struct Impl;
  explicit LegClassifier(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

struct TrainingDataParams {
  int scenes = 500;
  std::uint64_t seed = 1;
  LaserModel laser{};
  SegmentationParams segmentation{};
  TrainingSceneParams scene{};
};
// Labelled clusters from random scenes (scene generator, seeded). Scene k uses seed (seed, k), so disjoint seed
// ranges give disjoint train/held-out sets.
std::vector<LabelledCluster> generateLabelledClusters(const TrainingDataParams& params);

// Labelled clusters as CSV (e.g. from `cairn people gen-train`, which labels simulator scans): header
// `label,class,scene,<all registry feature names in registry order>`, label 1 = person leg, class = toString(ObjectClass).
// save throws InputError when the file cannot be written; load throws InputError naming file:line on a missing file,
// a header that does not list the registry's features, or a malformed row.
void saveLabelledClusters(const std::string& path, const std::vector<LabelledCluster>& samples);
std::vector<LabelledCluster> loadLabelledClusters(const std::string& path);

// Default shipped model of a kind: <package>/models/leg_<kind>_<set>.yml (source tree or install share/).
std::string defaultModelPath(ClassifierKind kind, const std::string& feature_set_name);

}  // namespace cairn::people_tracking
