#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <unistd.h>

#include "cairn/people_tracking/classifier.hpp"

using namespace cairn::people_tracking;

namespace {
std::vector<LabelledCluster> data(int scenes, std::uint64_t seed) {
  TrainingDataParams p;
  p.scenes = scenes;
  p.seed = seed;
  return generateLabelledClusters(p);
}
std::string tmpPath(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("cairn_pt_" + std::to_string(::getpid()) + "_" + name)).string();
}
std::string modelPath(const std::string& file) {
  return std::string(CAIRN_SOURCE_ROOT) + "/components/people_tracking/models/" + file;
}
}  // namespace

TEST(Classifier, GeneratedDataIsDeterministicAndLabelled) {
  const auto a = data(20, 3), b = data(20, 3);
  ASSERT_EQ(a.size(), b.size());
  std::size_t pos = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].features, b[i].features);
    pos += a[i].positive;
  }
  EXPECT_GT(pos, 5u);
  EXPECT_GT(a.size() - pos, 5 * pos / 2);
}

TEST(Classifier, AdaBoostAndSvmSeparateHeldOutScenes) {
  const auto train = data(150, 11);
  const auto test = data(80, 900001);
  for (ClassifierKind kind : {ClassifierKind::kAdaBoost, ClassifierKind::kSvm}) {
    ClassifierTrainParams p;
    p.kind = kind;
    p.boost_weak_count = 60;
    const LegClassifier c = LegClassifier::train(train, p);
    const ClassifierMetrics m = c.evaluate(test);
    EXPECT_GT(m.precision(), 0.7) << toString(kind);
    EXPECT_GT(m.recall(), 0.7) << toString(kind);
  }
}

TEST(Classifier, SaveLoadRoundTrip) {
  const auto train = data(60, 5);
  ClassifierTrainParams p;
  p.kind = ClassifierKind::kSvm;
  p.feature_set = "stuede5@1";
  const LegClassifier c = LegClassifier::train(train, p);
  const std::string path = tmpPath("svm.yml");
  c.save(path);
  const LegClassifier d = LegClassifier::load(path);
  EXPECT_EQ(d.kind(), ClassifierKind::kSvm);
  EXPECT_EQ(d.featureSet().key(), "stuede5@1");
  for (std::size_t i = 0; i < train.size(); i += 7) EXPECT_NEAR(c.score(train[i].features), d.score(train[i].features), 1e-6);
  std::filesystem::remove(path);
}

TEST(Classifier, ShippedModelsLoadAndReachHeldOutPrecisionRecall) {
  const auto test = data(150, 7777777);
  struct Expect {
    const char* file;
    double precision, recall;
  };
  // Bounds a little below the figures measured on 500 held-out scenes (README table): 0.816/0.854, 0.866/0.848,
  // 0.832/0.711, 0.809/0.750 (simmix: trained on simulator scenes too).
  for (const Expect& e : {Expect{"leg_adaboost_arras14.yml", 0.78, 0.75}, Expect{"leg_svm_arras14.yml", 0.78, 0.75},
                          Expect{"leg_svm_stuede5.yml", 0.72, 0.6}, Expect{"leg_adaboost_arras14_simmix.yml", 0.75, 0.68}}) {
    const LegClassifier c = LegClassifier::load(modelPath(e.file));
    const ClassifierMetrics m = c.evaluate(test);
    EXPECT_GT(m.precision(), e.precision) << e.file;
    EXPECT_GT(m.recall(), e.recall) << e.file;
  }
  EXPECT_EQ(defaultModelPath(ClassifierKind::kSvm, "arras14"), modelPath("leg_svm_arras14.yml"));
}

TEST(Classifier, BadModelFilesGiveClearErrors) {
  EXPECT_THROW(LegClassifier::load(tmpPath("does_not_exist.yml")), InputError);
  const std::string garbage = tmpPath("garbage.yml");
  std::ofstream(garbage) << "%YAML:1.0\n{ this is [ not yaml\n";
  EXPECT_THROW(LegClassifier::load(garbage), InputError);
  const std::string other = tmpPath("other.yml");
  std::ofstream(other) << "%YAML:1.0\n---\nformat: something_else\n";
  EXPECT_THROW(LegClassifier::load(other), InputError);
  // A real model file cut in half.
  std::ifstream in(modelPath("leg_adaboost_arras14.yml"));
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string truncated = tmpPath("truncated.yml");
  std::ofstream(truncated) << text.substr(0, text.size() / 2);
  EXPECT_THROW(LegClassifier::load(truncated), InputError);
  for (const auto& p : {garbage, other, truncated}) std::filesystem::remove(p);
  EXPECT_THROW(classifierKindFromString("forest"), InputError);
}

TEST(Classifier, TrainingNeedsBothClasses) {
  auto samples = data(5, 1);
  for (auto& s : samples) s.positive = false;
  EXPECT_THROW(LegClassifier::train(samples, {}), InputError);
}

TEST(Classifier, LabelledClustersRoundTripThroughCsvAndBadRowsNameTheLine) {
  const auto a = data(5, 4);
  const std::string path = tmpPath("clusters.csv");
  saveLabelledClusters(path, a);
  const auto b = loadLabelledClusters(path);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].positive, b[i].positive);
    EXPECT_EQ(a[i].object_class, b[i].object_class);
    EXPECT_EQ(a[i].scene, b[i].scene);
    for (std::size_t k = 0; k < kNumFeatures; ++k) EXPECT_NEAR(a[i].features[k], b[i].features[k], 1e-6 * (1 + std::abs(a[i].features[k])));
  }
  {
    std::ofstream f(path, std::ios::app);
    f << "1,person_leg,0,1,2\n";
  }
  try {
    (void)loadLabelledClusters(path);
    FAIL() << "short row accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(path + ":" + std::to_string(a.size() + 2)), std::string::npos) << e.what();
  }
  EXPECT_THROW((void)loadLabelledClusters(path + ".missing"), InputError);
  std::filesystem::remove(path);
}
