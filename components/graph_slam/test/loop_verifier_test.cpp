// Scan descriptor (Stüde §3.2.1) and AdaBoost loop verifier: invariances, pair features, training on synthetic
// worlds, model files, the shipped model on held-out ACES scans, the pair labelling rule and the ROC helpers.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "cairn/graph_slam/loop_verifier.hpp"
#include "cairn/graph_slam/scan_descriptor.hpp"
#include "cairn/sim/raycast.hpp"
#include "cairn/sim/world.hpp"  // InputError

namespace gs = cairn::graph_slam;
namespace sim = cairn::sim;

namespace {

const std::string kData = std::string(CAIRN_SOURCE_ROOT) + "/test/data/loop_verifier/";
constexpr double kPi = std::numbers::pi;

// A random indoor-like world: a 20 m x 14 m box with axis-aligned and oblique interior walls and pillars.
sim::SegmentGrid randomWorld(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> ux(0.0, 20.0), uy(0.0, 14.0), len(1.0, 6.0), u01(0.0, 1.0);
  std::vector<sim::Segment> s{{{0, 0}, {20, 0}}, {{20, 0}, {20, 14}}, {{20, 14}, {0, 14}}, {{0, 14}, {0, 0}}};
  for (int k = 0; k < 14; ++k) {
    const sim::Vec2 a{ux(rng), uy(rng)};
    const double l = len(rng), r = u01(rng);
    const double ang = r < 0.4 ? 0.0 : r < 0.8 ? kPi / 2 : u01(rng) * kPi;
    s.push_back({a, {a.x + l * std::cos(ang), a.y + l * std::sin(ang)}});
  }
  for (int k = 0; k < 6; ++k) {  // square pillars
    const sim::Vec2 c{ux(rng), uy(rng)};
    const double h = 0.15;
    s.push_back({{c.x - h, c.y - h}, {c.x + h, c.y - h}});
    s.push_back({{c.x + h, c.y - h}, {c.x + h, c.y + h}});
    s.push_back({{c.x + h, c.y + h}, {c.x - h, c.y + h}});
    s.push_back({{c.x - h, c.y + h}, {c.x - h, c.y - h}});
  }
  return sim::SegmentGrid(std::move(s));
}

sim::LaserScan render(const sim::SegmentGrid& world, sim::Pose2 pose, int beams, double fov, double noise,
                      std::mt19937_64* rng) {
  sim::LaserScan scan;
  scan.angle_increment = static_cast<float>(fov / beams);
  scan.angle_min = static_cast<float>(fov >= 2 * kPi - 1e-9 ? -kPi : -fov / 2);
  scan.angle_max = scan.angle_min + static_cast<float>(beams - 1) * scan.angle_increment;
  scan.range_max = 40.0F;
  std::normal_distribution<double> n(0.0, noise);
  for (int i = 0; i < beams; ++i) {
    const double a = pose.theta + scan.angle_min + i * static_cast<double>(scan.angle_increment);
    const sim::RayHit h = world.cast({pose.x, pose.y}, {std::cos(a), std::sin(a)}, 40.0);
    scan.ranges.push_back(h.hit ? static_cast<float>(h.range + (rng && noise > 0 ? n(*rng) : 0.0))
                                : std::numeric_limits<float>::infinity());
  }
  return scan;
}

sim::Pose2 freePose(const sim::SegmentGrid& world, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> ux(0.5, 19.5), uy(0.5, 13.5), ut(-kPi, kPi);
  for (;;) {
    const sim::Pose2 p{ux(rng), uy(rng), ut(rng)};
    if (world.distanceToNearest({p.x, p.y}, 0.4) >= 0.4) return p;
  }
}

void expectScalarsNear(const gs::ScanDescriptor& a, const gs::ScanDescriptor& b, double rel) {
  ASSERT_EQ(a.scalars.size(), gs::kScalarFeatureCount);
  ASSERT_EQ(b.scalars.size(), gs::kScalarFeatureCount);
  for (std::size_t k = 0; k < gs::kScalarFeatureCount; ++k)
    EXPECT_NEAR(a.scalars[k], b.scalars[k], rel * (1.0 + std::abs(a.scalars[k]))) << gs::scalarFeatureNames()[k];
}

// Synthetic labelled pairs: positives are two noisy 360° scans within 0.5 m (any heading) of each other,
// negatives two places more than 3 m apart in the same world or in different worlds.
gs::LabelledPairs syntheticPairs(std::uint64_t seed, int worlds, int per_world) {
  std::mt19937_64 rng(seed);
  std::vector<sim::SegmentGrid> w;
  for (int k = 0; k < worlds; ++k) w.push_back(randomWorld(rng));
  std::uniform_real_distribution<double> off(-0.35, 0.35), ut(-kPi, kPi);
  gs::LabelledPairs out;
  auto add = [&](const sim::LaserScan& a, const sim::LaserScan& b, int label) {
    out.features.push_back(gs::pairFeatures(gs::computeDescriptor(a), gs::computeDescriptor(b)));
    out.labels.push_back(label);
    (label ? out.positives : out.negatives) += 1;
  };
  for (int k = 0; k < worlds; ++k) {
    for (int i = 0; i < per_world; ++i) {
      const sim::Pose2 p = freePose(w[k], rng);
      sim::Pose2 q{p.x + off(rng), p.y + off(rng), ut(rng)};
      if (w[k].distanceToNearest({q.x, q.y}, 0.3) < 0.3) q = {p.x, p.y, q.theta};
      add(render(w[k], p, 360, 2 * kPi, 0.01, &rng), render(w[k], q, 360, 2 * kPi, 0.01, &rng), 1);
      sim::Pose2 r = freePose(w[k], rng);
      while (std::hypot(r.x - p.x, r.y - p.y) < 3.0) r = freePose(w[k], rng);
      const int other = i % 2 == 0 ? k : (k + 1) % worlds;
      if (other != k) r = freePose(w[other], rng);
      add(render(w[k], p, 360, 2 * kPi, 0.01, &rng), render(w[other], r, 360, 2 * kPi, 0.01, &rng), 0);
    }
  }
  return out;
}

std::string tempPath(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("cairn_loop_verifier_test_" + name)).string();
}

gs::LoopVerifier smallModel() {
  static const gs::LoopVerifier v = [] {
    const gs::LabelledPairs train = syntheticPairs(11, 4, 60);
    return gs::LoopVerifier::train(train.features, train.labels, 50);
  }();
  return v;
}

}  // namespace

TEST(ScanDescriptor, RotatingTheBeamsOfA360ScanLeavesScalarsUnchanged) {
  std::mt19937_64 rng(1);
  const sim::SegmentGrid world = randomWorld(rng);
  const sim::Pose2 p = freePose(world, rng);
  const sim::LaserScan scan = render(world, p, 360, 2 * kPi, 0.0, nullptr);
  const gs::ScanDescriptor d0 = gs::computeDescriptor(scan);
  EXPECT_EQ(d0.points, 360);
  for (int shift : {1, 37, 180, 359}) {
    sim::LaserScan rot = scan;  // cyclic shift of the beams = the robot turned by shift * increment
    for (int i = 0; i < 360; ++i) rot.ranges[static_cast<std::size_t>(i)] = scan.ranges[static_cast<std::size_t>((i + shift) % 360)];
    // Round-off only: the float increment times 360 is not exactly 2π, so the points move by ~1e-7 m.
    expectScalarsNear(d0, gs::computeDescriptor(rot), 1e-6);
    // The robot really turned (ray cast again at the new heading): the same scan up to ray-casting round-off,
    // which can flip a threshold (a gap, a straight triple) but must leave the pair looking like one place.
    const sim::Pose2 turned{p.x, p.y, p.theta + shift * static_cast<double>(scan.angle_increment)};
    const gs::ScanDescriptor d1 = gs::computeDescriptor(render(world, turned, 360, 2 * kPi, 0.0, nullptr));
    for (std::size_t k : {0, 1, 2, 18, 21, 23, 24}) EXPECT_NEAR(d0.scalars[k], d1.scalars[k], 1e-4 * (1 + d0.scalars[k]));
    const std::vector<double> f = gs::pairFeatures(d0, d1);
    for (std::size_t k = gs::kScalarFeatureCount; k < gs::kPairFeatureCount; ++k) EXPECT_GT(f[k], 0.99) << k;
  }
}

TEST(ScanDescriptor, ScalarsDoNotDependOnTheScanFramesAngleOffset) {
  std::mt19937_64 rng(2);
  const sim::SegmentGrid world = randomWorld(rng);
  const sim::LaserScan scan = render(world, freePose(world, rng), 180, kPi, 0.0, nullptr);
  sim::LaserScan moved = scan;
  moved.angle_min += 1.0F;
  moved.angle_max += 1.0F;
  const gs::ScanDescriptor a = gs::computeDescriptor(scan), b = gs::computeDescriptor(moved);
  expectScalarsNear(a, b, 1e-12);
  EXPECT_EQ(a.histograms, b.histograms);
}

TEST(ScanDescriptor, IdenticalScansGiveZeroDifferencesAndUnitCorrelation) {
  std::mt19937_64 rng(3);
  const sim::SegmentGrid world = randomWorld(rng);
  const gs::ScanDescriptor d = gs::computeDescriptor(render(world, freePose(world, rng), 180, kPi, 0.01, &rng));
  const std::vector<double> f = gs::pairFeatures(d, d);
  ASSERT_EQ(f.size(), gs::kPairFeatureCount);
  for (std::size_t k = 0; k < gs::kScalarFeatureCount; ++k) EXPECT_EQ(f[k], 0.0) << k;
  for (std::size_t k = gs::kScalarFeatureCount; k < gs::kPairFeatureCount; ++k) EXPECT_NEAR(f[k], 1.0, 1e-12) << k;
  for (const auto& h : d.histograms) {
    double sum = 0.0;
    for (double x : h) sum += x;
    EXPECT_NEAR(sum, 1.0, 1e-9);
  }
}

TEST(ScanDescriptor, PairFeaturesAreSymmetricAndDifferentPlacesDiffer) {
  std::mt19937_64 rng(4);
  const sim::SegmentGrid world = randomWorld(rng);
  const gs::ScanDescriptor a = gs::computeDescriptor(render(world, freePose(world, rng), 360, 2 * kPi, 0.01, &rng));
  const gs::ScanDescriptor b = gs::computeDescriptor(render(world, freePose(world, rng), 360, 2 * kPi, 0.01, &rng));
  const std::vector<double> ab = gs::pairFeatures(a, b), ba = gs::pairFeatures(b, a);
  EXPECT_EQ(ab, ba);
  double sum = 0.0;
  for (std::size_t k = 0; k < gs::kScalarFeatureCount; ++k) sum += ab[k];
  EXPECT_GT(sum, 0.1);
}

TEST(ScanDescriptor, ResamplingMakes180And360BeamScansOverTheSameFovAgree) {
  // Intel/ACES: 180 beams over 180°; FR079: 360 beams over 180°. Resampled to 1°, the descriptors of the same
  // place must be closer to each other than to a different place.
  std::mt19937_64 rng(5);
  const sim::SegmentGrid world = randomWorld(rng);
  const sim::Pose2 p = freePose(world, rng), q = freePose(world, rng);
  const gs::ScanDescriptor a180 = gs::computeDescriptor(render(world, p, 180, kPi, 0.0, nullptr));
  const gs::ScanDescriptor a360 = gs::computeDescriptor(render(world, p, 360, kPi, 0.0, nullptr));
  const gs::ScanDescriptor b180 = gs::computeDescriptor(render(world, q, 180, kPi, 0.0, nullptr));
  EXPECT_EQ(a180.points, 180);
  EXPECT_EQ(a360.points, 180);
  EXPECT_NEAR(a180.fov, a360.fov, 1e-6);
  const std::vector<double> same = gs::pairFeatures(a180, a360), diff = gs::pairFeatures(a180, b180);
  for (std::size_t k = gs::kScalarFeatureCount; k < gs::kPairFeatureCount; ++k) EXPECT_GT(same[k], 0.8) << k;
  EXPECT_NEAR(a180.scalars[0], a360.scalars[0], 0.05 * a180.scalars[0]);  // range_mean
  double s = 0.0, d = 0.0;
  for (std::size_t k = gs::kScalarFeatureCount; k < gs::kPairFeatureCount; ++k) {
    s += same[k];
    d += diff[k];
  }
  EXPECT_GT(s, d);
}

TEST(ScanDescriptor, InvalidBeamsAreSkippedAndMalformedScansRejected) {
  sim::LaserScan scan;
  scan.angle_min = -1.5F;
  scan.angle_increment = 0.01F;
  scan.ranges = {1.0F, std::nanf(""), 0.0F, -1.0F, std::numeric_limits<float>::infinity(), 100.0F, 2.0F};
  gs::DescriptorOptions o;
  o.angular_resolution = 0.001;  // no resampling: one point per valid beam
  const gs::ScanDescriptor d = gs::computeDescriptor(scan, o);
  EXPECT_EQ(d.points, 4);                               // 1, inf -> r_max, 100 -> r_max, 2
  EXPECT_DOUBLE_EQ(d.scalars[8], 0.5);                  // max_range_fraction
  EXPECT_DOUBLE_EQ(d.scalars[0], (1.0 + 30 + 30 + 2) / 4);  // range_mean with r_max = 30 (Stüde §3.2.1)
  for (double v : d.scalars) EXPECT_TRUE(std::isfinite(v));

  sim::LaserScan none = scan;
  none.ranges = {std::nanf(""), 0.0F};
  const gs::ScanDescriptor z = gs::computeDescriptor(none);
  EXPECT_EQ(z.points, 0);
  for (double v : gs::pairFeatures(z, d)) EXPECT_TRUE(std::isfinite(v));

  sim::LaserScan bad = scan;
  bad.angle_increment = 0.0F;
  EXPECT_THROW(gs::computeDescriptor(bad), std::invalid_argument);
  bad = scan;
  bad.ranges.clear();
  EXPECT_THROW(gs::computeDescriptor(bad), std::invalid_argument);
  gs::ScanDescriptor broken = d;
  broken.histograms.pop_back();
  EXPECT_THROW(gs::pairFeatures(d, broken), std::invalid_argument);
}

TEST(LoopVerifier, TrainedOnSyntheticWorldsSeparatesPairsFromUnseenWorlds) {
  const gs::LoopVerifier v = smallModel();
  EXPECT_EQ(v.weakCount(), 50);
  const gs::LabelledPairs test = syntheticPairs(99, 3, 40);  // other worlds, other places
  const gs::VerifierMetrics m = gs::evaluate(v, test);
  EXPECT_GT(m.auc, 0.85);               // chance: 0.5
  EXPECT_GT(m.tpr - m.fpr, 0.5);        // at the default threshold 0 (Youden's J; chance: 0)
  // A threshold picked for FPR <= 5 % on the training pairs still keeps a clear TPR on unseen worlds.
  const gs::LabelledPairs train = syntheticPairs(11, 4, 60);
  std::vector<double> scores;
  for (const auto& f : train.features) scores.push_back(v.scorePairFeatures(f));
  gs::LoopVerifier strict = v;
  strict.setThreshold(gs::thresholdForFpr(scores, train.labels, 0.05));
  const gs::VerifierMetrics s = gs::evaluate(strict, test);
  EXPECT_GT(s.tpr, 0.4);
  EXPECT_LT(s.fpr, 0.15);
}

TEST(LoopVerifier, SaveLoadRoundTripGivesIdenticalScores) {
  gs::LoopVerifier v = smallModel();
  v.setThreshold(0.75);
  const std::string path = tempPath("roundtrip.yml.gz");
  v.save(path);
  const gs::LoopVerifier w = gs::LoopVerifier::load(path);
  EXPECT_EQ(w.threshold(), 0.75);
  EXPECT_EQ(w.weakCount(), 50);
  EXPECT_EQ(w.descriptorOptions().max_range, v.descriptorOptions().max_range);
  const gs::LabelledPairs test = syntheticPairs(7, 2, 10);
  for (const auto& f : test.features) EXPECT_EQ(v.scorePairFeatures(f), w.scorePairFeatures(f));
  std::filesystem::remove(path);
}

TEST(LoopVerifier, BadModelFilesGiveClearErrors) {
  auto message = [](const std::string& path) {
    try {
      gs::LoopVerifier::load(path);
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string missing = tempPath("missing.yml");
  EXPECT_EQ(message(missing).rfind(missing + ": ", 0), 0U) << message(missing);

  // Truncated file: half of a valid model.
  const std::string good = tempPath("good.yml"), cut = tempPath("cut.yml");
  smallModel().save(good);
  std::ifstream in(good);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::ofstream(cut) << text.substr(0, text.size() / 2);
  EXPECT_EQ(message(cut).rfind(cut + ": ", 0), 0U) << message(cut);

  // Another format version.
  std::string other = text;
  const std::size_t at = other.find("format_version: 1");
  ASSERT_NE(at, std::string::npos);
  other.replace(at, 17, "format_version: 7");
  const std::string versioned = tempPath("v7.yml");
  std::ofstream(versioned) << other;
  EXPECT_NE(message(versioned).find("format_version 7"), std::string::npos) << message(versioned);

  // Garbage and a YAML file that is not a verifier.
  const std::string garbage = tempPath("garbage.yml.gz"), yaml = tempPath("other.yml");
  std::ofstream(garbage) << "\x1f\x8b not really gzip";
  std::ofstream(yaml) << "%YAML:1.0\n---\nformat: something_else\n";
  EXPECT_EQ(message(garbage).rfind(garbage + ": ", 0), 0U) << message(garbage);
  EXPECT_NE(message(yaml).find("not a cairn loop verifier"), std::string::npos) << message(yaml);

  EXPECT_THROW(gs::LoopVerifier().scorePairFeatures(std::vector<double>(gs::kPairFeatureCount)), std::logic_error);
  EXPECT_THROW(smallModel().scorePairFeatures({1.0, 2.0}), std::invalid_argument);
  EXPECT_THROW(gs::LoopVerifier::train({{1.0}}, {1}), std::invalid_argument);
  for (const auto& p : {good, cut, versioned, garbage, yaml}) std::filesystem::remove(p);
}

TEST(LoopVerifier, ShippedModelScoresAHeldOutAcesRevisitAboveAFarPair) {
  const gs::LoopVerifier v = gs::LoopVerifier::loadDefault();
  EXPECT_EQ(v.weakCount(), 50);
  EXPECT_GT(v.threshold(), 0.0);
  // Scans 1 and 3: 0.42 m apart, 1031 s apart; scan 2: 42.5 m from scan 1 (test/data/loop_verifier/PROVENANCE.md).
  const std::vector<gs::VerifierNode> n = gs::loadVerifierNodes(kData + "aces_corrected_3scans.log", v.descriptorOptions());
  ASSERT_EQ(n.size(), 3U);
  EXPECT_LT(std::hypot(n[0].pose.x - n[2].pose.x, n[0].pose.y - n[2].pose.y), 1.0);
  EXPECT_GT(std::hypot(n[0].pose.x - n[1].pose.x, n[0].pose.y - n[1].pose.y), 40.0);
  const double positive = v.score(n[0].descriptor, n[2].descriptor);
  const double negative = v.score(n[0].descriptor, n[1].descriptor);
  EXPECT_GT(positive, negative + 1.0);
  EXPECT_FALSE(v.accept(n[0].descriptor, n[1].descriptor));
  EXPECT_GT(gs::LoopVerifier::probability(positive), gs::LoopVerifier::probability(negative));
}

TEST(LoopVerifier, UnreadableLogIsAnInputErrorNamingTheFile) {
  const std::string missing = tempPath("no_such.log");
  try {
    gs::loadVerifierNodes(missing);
    FAIL() << "no error";
  } catch (const sim::InputError& e) {
    EXPECT_EQ(e.file(), missing);
  }
}

TEST(PairLabels, RuleSamplesDeterministicallyAndRespectsDistanceHeadingAndTime) {
  // Nodes on a line with 180° scans (fov < 350°: the heading rule applies).
  sim::LaserScan scan;
  scan.angle_min = static_cast<float>(-kPi / 2);
  scan.angle_increment = static_cast<float>(kPi / 180);
  scan.ranges.assign(180, 3.0F);
  const gs::ScanDescriptor d = gs::computeDescriptor(scan);
  auto node = [&](double t, double x, double th) { return gs::VerifierNode{t, {x, 0.0, th}, d}; };
  std::vector<gs::VerifierNode> nodes{node(0, 0.0, 0.0),   node(5, 0.2, 0.0),    // too close in time
                                      node(100, 0.5, 0.3), node(200, 0.4, 2.0),  // positive / heading too far
                                      node(300, 2.0, 0.0),                        // 1 m < d <= 3 m: neither
                                      node(400, 5.0, 0.0), node(500, 20.0, 0.0)};
  gs::PairLabelOptions o;
  o.balance = false;
  const gs::LabelledPairs p = gs::labelPairs(nodes, o);
  std::vector<std::pair<std::size_t, std::size_t>> pos, neg;
  for (std::size_t k = 0; k < p.labels.size(); ++k) (p.labels[k] ? pos : neg).push_back(p.nodes[k]);
  const std::vector<std::pair<std::size_t, std::size_t>> want_pos{{0, 2}, {1, 2}};  // |Δθ| 0.3 <= 45°
  EXPECT_EQ(pos, want_pos);
  // Negatives: every pair farther than 3 m: node 5 with nodes 0-3 (node 4 is exactly 3 m away), node 6 with all.
  EXPECT_EQ(p.candidate_negatives, 10U);
  EXPECT_EQ(neg.size(), 10U);

  // Sampling: caps, balance and seed.
  o.max_positives = 1;
  o.balance = true;
  const gs::LabelledPairs a = gs::labelPairs(nodes, o), b = gs::labelPairs(nodes, o);
  EXPECT_EQ(a.positives, 1U);
  EXPECT_EQ(a.negatives, 1U);
  EXPECT_EQ(a.nodes, b.nodes);
}

TEST(Roc, AucAndThresholdForFpr) {
  EXPECT_DOUBLE_EQ(gs::rocAuc({0.1, 0.2, 0.8, 0.9}, {0, 0, 1, 1}), 1.0);
  EXPECT_DOUBLE_EQ(gs::rocAuc({0.9, 0.8, 0.2, 0.1}, {0, 0, 1, 1}), 0.0);
  EXPECT_DOUBLE_EQ(gs::rocAuc({0.5, 0.5, 0.5, 0.5}, {0, 1, 0, 1}), 0.5);
  EXPECT_DOUBLE_EQ(gs::rocAuc({0.1, 0.4, 0.35, 0.8}, {0, 0, 1, 1}), 0.75);
  const std::vector<double> s{0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0, 10.0, 11.0};
  const std::vector<int> l{0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1, 1};
  const double t0 = gs::thresholdForFpr(s, l, 0.0);
  EXPECT_GT(t0, 9.0);
  EXPECT_LE(t0, 10.0);
  const double t2 = gs::thresholdForFpr(s, l, 0.2);  // two of ten negatives may pass
  EXPECT_GT(t2, 7.0);
  EXPECT_LE(t2, 8.0);
}
