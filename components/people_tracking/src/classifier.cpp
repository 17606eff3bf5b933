// OpenCV lives only in this translation unit.
#include "cairn/people_tracking/classifier.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/ml.hpp>

namespace cairn::people_tracking {

namespace {
constexpr const char* kFormat = "cairn_people_leg_classifier";
constexpr int kFormatVersion = 1;
// All registered features are non-negative and heavy-tailed (walls give 10 m radii and hundreds of points, legs
// a few centimetres); the SVM's RBF kernel needs them on a log scale before standardisation. Stumps are
// invariant to this monotone map. Stored in the model file as "input_transform".
constexpr const char* kTransform = "log(x+1e-4)";
float transformFeature(float x) { return std::log(std::max(0.0f, x) + 1e-4f); }
}  // namespace

const char* toString(ClassifierKind k) { return k == ClassifierKind::kAdaBoost ? "adaboost" : "svm"; }

ClassifierKind classifierKindFromString(const std::string& s) {
  if (s == "adaboost") return ClassifierKind::kAdaBoost;
  if (s == "svm") return ClassifierKind::kSvm;
  throw InputError("unknown classifier kind '" + s + "' (adaboost|svm)");
}

struct LegClassifier::Impl {
  ClassifierKind kind = ClassifierKind::kAdaBoost;
  FeatureSet set;
  std::vector<float> mean, inv_std;  // standardisation per selected feature
  float sign = 1.0f;                 // orientation of the raw output (positive = person)
  float gain = 1.0f;                 // logistic gain applied to the raw output
  cv::Ptr<cv::ml::StatModel> model;

  cv::Mat row(const FeatureVector& f) const {
    const std::vector<float> v = set.select(f);
    cv::Mat m(1, static_cast<int>(v.size()), CV_32F);
    for (std::size_t i = 0; i < v.size(); ++i)
      m.at<float>(0, static_cast<int>(i)) = (transformFeature(v[i]) - mean[i]) * inv_std[i];
    return m;
  }
  int flags() const {
    return cv::ml::StatModel::RAW_OUTPUT | (kind == ClassifierKind::kAdaBoost ? cv::ml::DTrees::PREDICT_SUM : 0);
  }
  float raw(const cv::Mat& r) const { return model->predict(r, cv::noArray(), flags()); }
};

LegClassifier::LegClassifier(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
LegClassifier::LegClassifier(LegClassifier&&) noexcept = default;
LegClassifier& LegClassifier::operator=(LegClassifier&&) noexcept = default;
LegClassifier::~LegClassifier() = default;

LegClassifier LegClassifier::train(const std::vector<LabelledCluster>& samples, const ClassifierTrainParams& params) {
  auto impl = std::make_unique<Impl>();
  impl->kind = params.kind;
  impl->set = people_tracking::featureSet(params.feature_set);
  const std::size_t d = impl->set.features.size();
  std::size_t npos = 0;
  for (const auto& s : samples) npos += s.positive ? 1 : 0;
  if (npos == 0 || npos == samples.size()) throw InputError("training needs positive and negative samples");

  const int n = static_cast<int>(samples.size());
  cv::Mat X(n, static_cast<int>(d), CV_32F);
  cv::Mat y(n, 1, CV_32S);
  std::vector<double> sum(d, 0.0), sq(d, 0.0);
  for (int i = 0; i < n; ++i) {
    auto v = impl->set.select(samples[static_cast<std::size_t>(i)].features);
    for (std::size_t j = 0; j < d; ++j) {
      v[j] = transformFeature(v[j]);
      X.at<float>(i, static_cast<int>(j)) = v[j];
      sum[j] += v[j];
      sq[j] += double(v[j]) * v[j];
    }
    y.at<int>(i, 0) = samples[static_cast<std::size_t>(i)].positive ? 1 : 0;
  }
  impl->mean.resize(d);
  impl->inv_std.resize(d);
  for (std::size_t j = 0; j < d; ++j) {
    const double m = sum[j] / n;
    const double var = std::max(0.0, sq[j] / n - m * m);
    impl->mean[j] = static_cast<float>(m);
    impl->inv_std[j] = static_cast<float>(var > 1e-18 ? 1.0 / std::sqrt(var) : 1.0);
  }
  for (int i = 0; i < n; ++i)
    for (std::size_t j = 0; j < d; ++j) {
      float& x = X.at<float>(i, static_cast<int>(j));
      x = (x - impl->mean[j]) * impl->inv_std[j];
    }

  if (params.kind == ClassifierKind::kAdaBoost) {
    auto boost = cv::ml::Boost::create();
    boost->setBoostType(cv::ml::Boost::REAL);
    boost->setWeakCount(params.boost_weak_count);
    boost->setMaxDepth(1);  // decision stumps
    boost->setWeightTrimRate(0.0);
    boost->setUseSurrogates(false);
    boost->train(cv::ml::TrainData::create(X, cv::ml::ROW_SAMPLE, y));
    impl->model = boost;
    impl->gain = 2.0f;  // Real AdaBoost sums approximate half the log-odds
  } else {
    auto svm = cv::ml::SVM::create();
    svm->setType(cv::ml::SVM::C_SVC);
    svm->setKernel(cv::ml::SVM::RBF);
    svm->setC(params.svm_c);
    svm->setGamma(params.svm_gamma);
    cv::Mat weights = (cv::Mat_<double>(2, 1) << 1.0, params.positive_weight);
    svm->setClassWeights(weights);
    svm->setTermCriteria(cv::TermCriteria(cv::TermCriteria::MAX_ITER + cv::TermCriteria::EPS, 1000000, 1e-3));
    svm->train(cv::ml::TrainData::create(X, cv::ml::ROW_SAMPLE, y));
    impl->model = svm;
    impl->gain = 2.0f;
  }
  if (!impl->model->isTrained()) throw InputError("classifier training failed");
  // Orient the raw output: OpenCV's sign convention differs between models, so measure it on the data.
  double pos = 0.0, neg = 0.0;
  for (int i = 0; i < n; ++i) {
    const float r = impl->raw(X.row(i));
    (y.at<int>(i, 0) == 1 ? pos : neg) += r;
  }
  impl->sign = (pos / double(npos)) >= (neg / double(samples.size() - npos)) ? 1.0f : -1.0f;
  return LegClassifier(std::move(impl));
}

double LegClassifier::score(const FeatureVector& features) const {
  const float r = impl_->sign * impl_->raw(impl_->row(features));
  return 1.0 / (1.0 + std::exp(-static_cast<double>(impl_->gain * r)));
}

ClassifierKind LegClassifier::kind() const { return impl_->kind; }
const FeatureSet& LegClassifier::featureSet() const { return impl_->set; }

ClassifierMetrics LegClassifier::evaluate(const std::vector<LabelledCluster>& samples, double threshold) const {
  ClassifierMetrics m;
  for (const auto& s : samples) {
    const bool p = score(s.features) >= threshold;
    if (p && s.positive) ++m.tp;
    else if (p && !s.positive) ++m.fp;
    else if (!p && s.positive) ++m.fn;
    else ++m.tn;
  }
  return m;
}

void LegClassifier::checkWritable(const std::string& path) {
  // Probed with the standard library first: OpenCV would log its own multi-line error for an unwritable path.
  if (std::filesystem::is_directory(path) || !std::ofstream(path, std::ios::app))
    throw InputError("cannot write model file " + path);
}

void LegClassifier::save(const std::string& path) const {
  checkWritable(path);
  try {
    cv::FileStorage fs(path, cv::FileStorage::WRITE);
    if (!fs.isOpened()) throw InputError("cannot write model file " + path);
    fs << "format" << kFormat << "format_version" << kFormatVersion;
    fs << "kind" << toString(impl_->kind);
    fs << "feature_set" << impl_->set.key();
    fs << "feature_registry_version" << kFeatureRegistryVersion;
    fs << "feature_names" << impl_->set.featureNames();
    fs << "input_transform" << kTransform;
    fs << "mean" << impl_->mean << "inv_std" << impl_->inv_std;
    fs << "sign" << impl_->sign << "gain" << impl_->gain;
    fs << "model" << "{";
    impl_->model->write(fs);
    fs << "}";
  } catch (const cv::Exception& e) {
    throw InputError("cannot write model file " + path + ": " + e.err);  // err: the message without OpenCV's file/line
  }
}

LegClassifier LegClassifier::load(const std::string& path) {
  if (!std::filesystem::is_regular_file(path)) throw InputError("model file not found: " + path);
  auto impl = std::make_unique<Impl>();
  try {
    cv::FileStorage fs(path, cv::FileStorage::READ);
    if (!fs.isOpened()) throw InputError("cannot open model file " + path);
    if (static_cast<std::string>(fs["format"]) != kFormat)
      throw InputError("model file " + path + " is not a cairn leg classifier");
    if (static_cast<int>(fs["format_version"]) != kFormatVersion)
      throw InputError("model file " + path + " has an unsupported format_version");
    impl->kind = classifierKindFromString(static_cast<std::string>(fs["kind"]));
    impl->set = people_tracking::featureSet(static_cast<std::string>(fs["feature_set"]));
    std::vector<std::string> names;
    fs["feature_names"] >> names;
    if (names != impl->set.featureNames())
      throw InputError("model file " + path + ": feature names do not match feature set " + impl->set.key());
    if (static_cast<std::string>(fs["input_transform"]) != kTransform)
      throw InputError("model file " + path + " uses an unknown input_transform");
    fs["mean"] >> impl->mean;
    fs["inv_std"] >> impl->inv_std;
    fs["sign"] >> impl->sign;
    fs["gain"] >> impl->gain;
    const std::size_t d = impl->set.features.size();
    if (impl->mean.size() != d || impl->inv_std.size() != d)
      throw InputError("model file " + path + ": standardisation does not match the feature set");
    const cv::FileNode node = fs["model"];
    if (node.empty()) throw InputError("model file " + path + " has no model");
    if (impl->kind == ClassifierKind::kAdaBoost) {
      auto m = cv::ml::Boost::create();
      m->read(node);
      impl->model = m;
    } else {
      auto m = cv::ml::SVM::create();
      m->read(node);
      impl->model = m;
    }
    if (!impl->model->isTrained() || impl->model->getVarCount() != static_cast<int>(d))
      throw InputError("model file " + path + ": model is not trained or has the wrong input size");
  } catch (const cv::Exception& e) {
    throw InputError("corrupt model file " + path + ": " + e.err);
  }
  return LegClassifier(std::move(impl));
}

std::vector<LabelledCluster> generateLabelledClusters(const TrainingDataParams& params) {
  std::vector<LabelledCluster> out;
  for (int k = 0; k < params.scenes; ++k) {
    std::seed_seq seq{static_cast<std::uint32_t>(params.seed), static_cast<std::uint32_t>(params.seed >> 32),
                      static_cast<std::uint32_t>(k)};
    std::mt19937_64 rng(seq);
    const Scene scene = randomTrainingScene(rng, params.scene);
    const SimScan sim = renderScan(scene, Pose2{}, params.laser, 0.0, rng);
    for (const Cluster& c : segmentScan(sim.scan, params.segmentation)) {
      const ClusterLabel label = labelCluster(c, sim, scene);
      out.push_back({computeFeatures(c), label.is_person, label.object_class, k});
    }
  }
  return out;
}

std::string defaultModelPath(ClassifierKind kind, const std::string& feature_set_name) {
  const std::string file = std::string("leg_") + toString(kind) + "_" + feature_set_name + ".yml";
  return std::string(CAIRN_PEOPLE_MODEL_DIR) + "/" + file;
}

}  // namespace cairn::people_tracking
