// Loop-closure verifier: Real AdaBoost with decision stumps (cv::ml::Boost) on the 41 pair features of two scan
// descriptors (Stüde 2024 §3.2.1; Granström et al. 2009). OpenCV lives only in this translation unit.
#include "cairn/graph_slam/loop_verifier.hpp"

#include <dlfcn.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <numbers>
#include <opencv2/core.hpp>
#include <opencv2/ml.hpp>
#include <random>
#include <sstream>
#include <stdexcept>
#include <variant>

#include "cairn/sim/carmen.hpp"

namespace cairn::graph_slam {

namespace {
constexpr const char* kFormat = "cairn_loop_verifier";
constexpr int kFormatVersion = 1;
constexpr const char* kModelFile = "loop_verifier.yml.gz";
// Raw boosted sum Σ αₜ hₜ (not the class vote).
constexpr int kPredictFlags = static_cast<int>(cv::ml::StatModel::RAW_OUTPUT) | static_cast<int>(cv::ml::DTrees::PREDICT_SUM);

std::runtime_error fileError(const std::string& path, const std::string& what) {
  return std::runtime_error(path + ": " + what);
}

// Directory of the binary this code is linked into (shared library or executable): <prefix>/lib or <prefix>/bin.
std::filesystem::path binaryDir() {
  Dl_info info{};
  if (dladdr(reinterpret_cast<const void*>(&binaryDir), &info) == 0 || info.dli_fname == nullptr) return {};
  std::error_code ec;
  const auto p = std::filesystem::weakly_canonical(std::filesystem::path(info.dli_fname), ec);
  return ec ? std::filesystem::path(info.dli_fname).parent_path() : p.parent_path();
}
}  // namespace

struct LoopVerifier::Impl {
  cv::Ptr<cv::ml::Boost> model;
  float sign = 1.0F;  // orientation of OpenCV's raw sum (positive = same place), measured on the training data
  int weak_count = 0;
  DescriptorOptions descriptor;

  double raw(const std::vector<double>& f) const {
    if (f.size() != kPairFeatureCount)
      throw std::invalid_argument("LoopVerifier: expected " + std::to_string(kPairFeatureCount) + " pair features, got " +
                                  std::to_string(f.size()));
    cv::Mat row(1, static_cast<int>(f.size()), CV_32F);
    for (std::size_t k = 0; k < f.size(); ++k) row.at<float>(0, static_cast<int>(k)) = static_cast<float>(f[k]);
    const float s = model->predict(row, cv::noArray(), kPredictFlags);
    return static_cast<double>(sign * s);
  }
};

LoopVerifier::LoopVerifier() = default;

int LoopVerifier::weakCount() const { return impl_ ? impl_->weak_count : 0; }

const DescriptorOptions& LoopVerifier::descriptorOptions() const {
  static const DescriptorOptions defaults;
  return impl_ ? impl_->descriptor : defaults;
}

double LoopVerifier::scorePairFeatures(const std::vector<double>& pair_features) const {
  if (!impl_) throw std::logic_error("LoopVerifier: no model (train or load one first)");
  return impl_->raw(pair_features);
}

double LoopVerifier::score(const ScanDescriptor& a, const ScanDescriptor& b) const {
  return scorePairFeatures(pairFeatures(a, b));
}

bool LoopVerifier::accept(const ScanDescriptor& a, const ScanDescriptor& b) const { return score(a, b) >= threshold_; }

double LoopVerifier::probability(double score) { return 1.0 / (1.0 + std::exp(-2.0 * score)); }

LoopVerifier LoopVerifier::train(const std::vector<std::vector<double>>& pair_features, const std::vector<int>& labels,
                                 int weak_count, const DescriptorOptions& descriptor_options) {
  if (pair_features.empty()) throw std::invalid_argument("LoopVerifier::train: no samples");
  if (pair_features.size() != labels.size())
    throw std::invalid_argument("LoopVerifier::train: " + std::to_string(pair_features.size()) + " samples but " +
                                std::to_string(labels.size()) + " labels");
  if (weak_count < 1) throw std::invalid_argument("LoopVerifier::train: weak_count must be >= 1");
  const int n = static_cast<int>(pair_features.size());
  cv::Mat X(n, static_cast<int>(kPairFeatureCount), CV_32F);
  cv::Mat y(n, 1, CV_32S);
  std::size_t npos = 0;
  for (int i = 0; i < n; ++i) {
    const auto& f = pair_features[static_cast<std::size_t>(i)];
    if (f.size() != kPairFeatureCount)
      throw std::invalid_argument("LoopVerifier::train: sample " + std::to_string(i) + " has " + std::to_string(f.size()) +
                                  " features, expected " + std::to_string(kPairFeatureCount));
    for (std::size_t k = 0; k < kPairFeatureCount; ++k) {
      if (!std::isfinite(f[k])) throw std::invalid_argument("LoopVerifier::train: sample " + std::to_string(i) + " is not finite");
      X.at<float>(i, static_cast<int>(k)) = static_cast<float>(f[k]);
    }
    const int l = labels[static_cast<std::size_t>(i)];
    if (l != 0 && l != 1) throw std::invalid_argument("LoopVerifier::train: labels must be 0 or 1");
    y.at<int>(i, 0) = l;
    npos += static_cast<std::size_t>(l);
  }
  if (npos == 0 || npos == pair_features.size())
    throw std::invalid_argument("LoopVerifier::train: needs positive and negative samples");

  auto impl = std::make_shared<Impl>();
  auto boost = cv::ml::Boost::create();
  boost->setBoostType(cv::ml::Boost::REAL);
  boost->setWeakCount(weak_count);  // Stüde §3.2.1: T = 50 training rounds [GS10]
  boost->setMaxDepth(1);            // decision stumps
  boost->setWeightTrimRate(0.0);    // all samples in every round (deterministic, small data)
  boost->setUseSurrogates(false);
  boost->setCVFolds(0);
  boost->train(cv::ml::TrainData::create(X, cv::ml::ROW_SAMPLE, y));
  if (!boost->isTrained()) throw std::runtime_error("LoopVerifier::train: OpenCV training failed");
  impl->model = boost;
  impl->weak_count = weak_count;
  impl->descriptor = descriptor_options;
  // OpenCV's sign convention of the raw sum depends on the class order: orient it on the data.
  double pos = 0.0, neg = 0.0;
  for (int i = 0; i < n; ++i) {
    const double r = impl->raw(pair_features[static_cast<std::size_t>(i)]);
    (y.at<int>(i, 0) == 1 ? pos : neg) += r;
  }
  impl->sign = pos / static_cast<double>(npos) >= neg / static_cast<double>(pair_features.size() - npos) ? 1.0F : -1.0F;
  LoopVerifier v;
  v.impl_ = std::move(impl);
  return v;
}

void LoopVerifier::save(const std::string& path) const {
  if (!impl_) throw fileError(path, "cannot save an untrained loop verifier");
  try {
    cv::FileStorage fs(path, cv::FileStorage::WRITE);
    if (!fs.isOpened()) throw fileError(path, "cannot open for writing");
    const DescriptorOptions& d = impl_->descriptor;
    fs << "format" << kFormat << "format_version" << kFormatVersion;
    fs << "scalar_features" << scalarFeatureNames();
    fs << "max_range" << d.max_range << "min_range" << d.min_range << "angular_resolution" << d.angular_resolution;
    fs << "histogram_bin_sizes" << std::vector<double>(d.histogram_bin_sizes.begin(), d.histogram_bin_sizes.end());
    fs << "gap_distances" << std::vector<double>(d.gap_distances.begin(), d.gap_distances.end());
    fs << "threshold" << threshold_ << "sign" << impl_->sign << "weak_count" << impl_->weak_count;
    fs << "model" << "{";
    impl_->model->write(fs);
    fs << "}";
    fs.release();
  } catch (const cv::Exception& e) {
    throw fileError(path, "cannot write model: " + e.err);
  }
}

LoopVerifier LoopVerifier::load(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw fileError(path, "model file not found");
  auto impl = std::make_shared<Impl>();
  LoopVerifier v;
  try {
    cv::FileStorage fs(path, cv::FileStorage::READ);
    if (!fs.isOpened()) throw fileError(path, "not a readable OpenCV FileStorage file");
    if (static_cast<std::string>(fs["format"]) != kFormat) throw fileError(path, "not a cairn loop verifier model");
    const int version = static_cast<int>(fs["format_version"]);
    if (version != kFormatVersion)
      throw fileError(path, "format_version " + std::to_string(version) + ", this build reads " +
                                std::to_string(kFormatVersion));
    std::vector<std::string> names;
    fs["scalar_features"] >> names;
    if (names != scalarFeatureNames()) throw fileError(path, "scalar feature list differs from this build's descriptor");
    DescriptorOptions& d = impl->descriptor;
    fs["max_range"] >> d.max_range;
    fs["min_range"] >> d.min_range;
    fs["angular_resolution"] >> d.angular_resolution;
    std::vector<double> bins, gaps;
    fs["histogram_bin_sizes"] >> bins;
    fs["gap_distances"] >> gaps;
    if (bins.size() != d.histogram_bin_sizes.size() || gaps.size() != d.gap_distances.size())
      throw fileError(path, "histogram_bin_sizes / gap_distances have the wrong length");
    std::copy(bins.begin(), bins.end(), d.histogram_bin_sizes.begin());
    std::copy(gaps.begin(), gaps.end(), d.gap_distances.begin());
    if (!(d.max_range > 0.0) || !(d.angular_resolution > 0.0)) throw fileError(path, "invalid descriptor options");
    fs["threshold"] >> v.threshold_;
    fs["sign"] >> impl->sign;
    fs["weak_count"] >> impl->weak_count;
    if (!std::isfinite(v.threshold_) || (impl->sign != 1.0F && impl->sign != -1.0F))
      throw fileError(path, "invalid threshold or sign");
    const cv::FileNode node = fs["model"];
    if (node.empty()) throw fileError(path, "no model node");
    impl->model = cv::ml::Boost::create();
    impl->model->read(node);
    if (!impl->model->isTrained() || impl->model->getVarCount() != static_cast<int>(kPairFeatureCount))
      throw fileError(path, "model is not trained or does not take " + std::to_string(kPairFeatureCount) + " features");
  } catch (const cv::Exception& e) {
    throw fileError(path, "corrupt model file: " + e.err);  // e.what() spans lines
  }
  v.impl_ = std::move(impl);
  return v;
}

std::string LoopVerifier::defaultModelPath() {
  namespace fs = std::filesystem;
  const std::string sub = "share/cairn_graph_slam/models";
  std::vector<fs::path> candidates;
  // Mirrors people_tracking's lookup without the runtime: this binary's install prefix, the prefixes in
  // $CMAKE_PREFIX_PATH / $COLCON_PREFIX_PATH, then the source tree's models/ (build tree).
  const fs::path bin = binaryDir();
  if (!bin.empty()) candidates.push_back(bin.parent_path() / sub / kModelFile);
  for (const char* var : {"CMAKE_PREFIX_PATH", "COLCON_PREFIX_PATH"}) {
    const char* v = std::getenv(var);
    if (v == nullptr) continue;
    std::stringstream ss(v);
    std::string prefix;
    while (std::getline(ss, prefix, ':'))
      if (!prefix.empty()) candidates.push_back(fs::path(prefix) / sub / kModelFile);
  }
#ifdef CAIRN_SLAM_MODEL_DIR
  candidates.push_back(fs::path(CAIRN_SLAM_MODEL_DIR) / kModelFile);
#endif
  std::string tried;
  for (const auto& c : candidates) {
    std::error_code ec;
    if (fs::is_regular_file(c, ec)) return c.string();
    tried += (tried.empty() ? "" : ", ") + c.string();
  }
  throw std::runtime_error(std::string(kModelFile) + ": shipped loop verifier model not found (tried " + tried + ")");
}

LoopVerifier LoopVerifier::loadDefault() { return load(defaultModelPath()); }

// ---- training data ----------------------------------------------------------------------------------------

std::vector<VerifierNode> loadVerifierNodes(const std::string& carmen_log, const DescriptorOptions& descriptor,
                                            const NodeSamplingOptions& sampling) {
  sim::CarmenReader reader(carmen_log);
  std::vector<VerifierNode> nodes;
  sim::CarmenRecord rec;
  while (reader.next(rec)) {
    const auto* laser = std::get_if<sim::CarmenLaser>(&rec);
    if (laser == nullptr || !laser->has_pose) continue;
    if (!nodes.empty()) {
      const sim::Pose2& last = nodes.back().pose;
      const double moved = std::hypot(laser->laser_pose.x - last.x, laser->laser_pose.y - last.y);
      const double turned = std::abs(sim::normalizeAngle(laser->laser_pose.theta - last.theta));
      if (moved < sampling.min_distance && turned < sampling.min_rotation) continue;
    }
    VerifierNode node;
    node.stamp = laser->scan.stamp;
    node.pose = laser->laser_pose;
    try {
      node.descriptor = computeDescriptor(laser->scan, descriptor);
    } catch (const std::invalid_argument& e) {
      throw sim::InputError(carmen_log, static_cast<int>(reader.lineNumber()), e.what());
    }
    nodes.push_back(std::move(node));
  }
  return nodes;
}

void LabelledPairs::append(const LabelledPairs& o) {
  features.insert(features.end(), o.features.begin(), o.features.end());
  labels.insert(labels.end(), o.labels.begin(), o.labels.end());
  nodes.insert(nodes.end(), o.nodes.begin(), o.nodes.end());
  positives += o.positives;
  negatives += o.negatives;
  candidate_positives += o.candidate_positives;
  candidate_negatives += o.candidate_negatives;
}

namespace {
// Uniform sample of at most `capacity` items from a stream (Algorithm R), deterministic for a seeded engine.
struct Reservoir {
  std::size_t capacity;
  std::vector<std::pair<std::size_t, std::size_t>> items;
  std::size_t seen = 0;
  void offer(std::pair<std::size_t, std::size_t> item, std::mt19937_64& rng) {
    ++seen;
    if (items.size() < capacity) {
      items.push_back(item);
      return;
    }
    const std::size_t j = static_cast<std::size_t>(rng() % seen);
    if (j < capacity) items[j] = item;
  }
  // The first k items of a seeded shuffle (still a uniform sample), in node order for readability.
  std::vector<std::pair<std::size_t, std::size_t>> take(std::size_t k, std::mt19937_64& rng) {
    for (std::size_t i = items.size(); i > 1; --i) std::swap(items[i - 1], items[static_cast<std::size_t>(rng() % i)]);
    items.resize(std::min(k, items.size()));
    std::sort(items.begin(), items.end());
    return items;
  }
};
}  // namespace

LabelledPairs labelPairs(const std::vector<VerifierNode>& nodes, const PairLabelOptions& o) {
  if (!(o.positive_distance > 0.0) || !(o.negative_distance >= o.positive_distance) ||
      !(o.near_negative_distance >= o.negative_distance) || !(o.near_negative_fraction >= 0.0 && o.near_negative_fraction <= 1.0))
    throw std::invalid_argument("PairLabelOptions: need 0 < positive_distance <= negative_distance <= near_negative_distance "
                                "and near_negative_fraction in [0, 1]");
  std::mt19937_64 rng(o.seed);
  Reservoir pos{o.max_positives, {}, 0}, near{o.max_negatives, {}, 0}, far{o.max_negatives, {}, 0};
  constexpr double kFullFov = 350.0 * std::numbers::pi / 180.0;
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    for (std::size_t j = i + 1; j < nodes.size(); ++j) {
      const VerifierNode &a = nodes[i], &b = nodes[j];
      if (std::abs(a.stamp - b.stamp) < o.min_time_gap) continue;  // consecutive scans: not a revisit
      const double d = std::hypot(a.pose.x - b.pose.x, a.pose.y - b.pose.y);
      if (d < o.positive_distance) {
        // A 180° scanner facing the other way sees a different half of the place: neither label.
        const bool full = a.descriptor.fov >= kFullFov && b.descriptor.fov >= kFullFov;
        if (full || std::abs(sim::normalizeAngle(a.pose.theta - b.pose.theta)) <= o.positive_heading) pos.offer({i, j}, rng);
      } else if (d > o.negative_distance) {
        (d <= o.near_negative_distance ? near : far).offer({i, j}, rng);
      }
    }
  }
  LabelledPairs out;
  out.candidate_positives = pos.seen;
  out.candidate_negatives = near.seen + far.seen;
  const auto positives = pos.take(o.max_positives, rng);
  const std::size_t n_neg = o.balance ? std::min(o.max_negatives, positives.size()) : o.max_negatives;
  std::size_t n_near = static_cast<std::size_t>(std::lround(o.near_negative_fraction * static_cast<double>(n_neg)));
  n_near = std::min(n_near, near.items.size());
  const auto near_s = near.take(n_near, rng);
  const auto far_s = far.take(n_neg - near_s.size(), rng);
  auto add = [&](const std::vector<std::pair<std::size_t, std::size_t>>& list, int label) {
    for (const auto& [i, j] : list) {
      out.features.push_back(pairFeatures(nodes[i].descriptor, nodes[j].descriptor));
      out.labels.push_back(label);
      out.nodes.emplace_back(i, j);
    }
  };
  add(positives, 1);
  add(near_s, 0);
  add(far_s, 0);
  out.positives = positives.size();
  out.negatives = near_s.size() + far_s.size();
  return out;
}

// ---- evaluation -------------------------------------------------------------------------------------------

double rocAuc(const std::vector<double>& scores, const std::vector<int>& labels) {
  if (scores.size() != labels.size()) throw std::invalid_argument("rocAuc: scores and labels differ in length");
  std::vector<std::size_t> idx(scores.size());
  for (std::size_t k = 0; k < idx.size(); ++k) idx[k] = k;
  std::sort(idx.begin(), idx.end(), [&](std::size_t a, std::size_t b) { return scores[a] < scores[b]; });
  // Mann–Whitney U: sum of the positives' (tie-averaged) ranks.
  double rank_sum = 0.0;
  std::size_t npos = 0;
  for (std::size_t k = 0; k < idx.size();) {
    std::size_t e = k;
    while (e < idx.size() && scores[idx[e]] == scores[idx[k]]) ++e;
    const double avg_rank = 0.5 * static_cast<double>(k + 1 + e);  // ranks k+1 .. e
    for (std::size_t m = k; m < e; ++m)
      if (labels[idx[m]] == 1) {
        rank_sum += avg_rank;
        ++npos;
      }
    k = e;
  }
  const std::size_t nneg = scores.size() - npos;
  if (npos == 0 || nneg == 0) return 0.5;
  const double np = static_cast<double>(npos);
  return (rank_sum - np * (np + 1.0) / 2.0) / (np * static_cast<double>(nneg));
}

double thresholdForFpr(const std::vector<double>& scores, const std::vector<int>& labels, double target_fpr) {
  if (scores.size() != labels.size()) throw std::invalid_argument("thresholdForFpr: scores and labels differ in length");
  if (!(target_fpr >= 0.0 && target_fpr <= 1.0)) throw std::invalid_argument("thresholdForFpr: target_fpr must be in [0, 1]");
  std::vector<double> neg;
  for (std::size_t k = 0; k < scores.size(); ++k)
    if (labels[k] == 0) neg.push_back(scores[k]);
  if (neg.empty()) return scores.empty() ? 0.0 : *std::min_element(scores.begin(), scores.end());
  std::sort(neg.begin(), neg.end(), std::greater<>());
  const auto allowed = static_cast<std::size_t>(std::floor(target_fpr * static_cast<double>(neg.size()) + 1e-9));
  if (allowed >= neg.size()) return *std::min_element(scores.begin(), scores.end());
  // Just above the (allowed+1)-th highest negative: at most `allowed` negatives score >= t.
  return std::nextafter(neg[allowed], std::numeric_limits<double>::infinity());
}

VerifierMetrics evaluate(const LoopVerifier& verifier, const LabelledPairs& pairs) {
  VerifierMetrics m;
  m.threshold = verifier.threshold();
  std::vector<double> scores;
  scores.reserve(pairs.features.size());
  for (std::size_t k = 0; k < pairs.features.size(); ++k) {
    const double s = verifier.scorePairFeatures(pairs.features[k]);
    scores.push_back(s);
    const bool p = s >= m.threshold, pos = pairs.labels[k] == 1;
    (p ? (pos ? m.tp : m.fp) : (pos ? m.fn : m.tn)) += 1;
  }
  const auto ratio = [](std::size_t a, std::size_t b) { return b == 0 ? 0.0 : static_cast<double>(a) / static_cast<double>(b); };
  m.tpr = ratio(m.tp, m.tp + m.fn);
  m.fpr = ratio(m.fp, m.fp + m.tn);
  m.precision = ratio(m.tp, m.tp + m.fp);
  m.auc = rocAuc(scores, pairs.labels);
  return m;
}

}  // namespace cairn::graph_slam
