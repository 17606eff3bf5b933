// Throughput of the people tracking pipeline at 30 people (issue 6 target: >= 1000 scans/s on one core).
// Scans are rendered once in the fixture; only detection (segmentation, features, classifier, leg pairing)
// and tracking are timed.
#include <benchmark/benchmark.h>

#include <memory>
#include <random>
#include <vector>

#include "cairn/people_tracking/detector.hpp"
#include "cairn/people_tracking/scene.hpp"
#include "cairn/people_tracking/tracker.hpp"

using namespace cairn::people_tracking;

namespace {
struct Crowd {
  std::vector<LaserScan> scans;
  std::shared_ptr<const LegClassifier> model;
};

const Crowd& crowd() {
  static const Crowd c = [] {
    Crowd out;
    out.model = std::make_shared<const LegClassifier>(LegClassifier::load(defaultModelPath(ClassifierKind::kAdaBoost, "arras14")));
    std::mt19937_64 rng(30);
    std::uniform_real_distribution<double> U(-7.5, 7.5), A(-M_PI, M_PI);
    std::vector<WalkerState> w(30);
    std::vector<Eigen::Vector2d> vel(30);
    for (std::size_t i = 0; i < w.size(); ++i) {
      do w[i].position = {U(rng), U(rng)};
      while (w[i].position.norm() < 1.0);
      const double a = A(rng);
      vel[i] = 1.2 * Eigen::Vector2d(std::cos(a), std::sin(a));
      w[i].heading = a;
    }
    LaserModel laser;
    laser.beams = 1080;
    laser.angle_min = -M_PI;
    laser.angle_increment = 2 * M_PI / 1080;
    for (int k = 0; k < 100; ++k) {
      Scene s;
      s.addBox({0, 0}, 8.5, 8.5, 0.0, ObjectClass::kWall);
      for (std::size_t i = 0; i < w.size(); ++i) {
        w[i].position += 0.1 * vel[i];
        for (int d = 0; d < 2; ++d)
          if (std::abs(w[i].position[d]) > 7.5) vel[i][d] = -vel[i][d];
        w[i].heading = std::atan2(vel[i].y(), vel[i].x());
        advanceGait(w[i], 0.12, 0.1);
        addWalker(s, w[i], static_cast<int>(i));
      }
      out.scans.push_back(renderScan(s, Pose2{}, laser, 0.1 * k, rng).scan);
    }
    return out;
  }();
  return c;
}

// pairing_with_tracks: detectLegs + PeopleTracker::updateLegs with the scan (the component's and the bench's
// path: track-aware leg pairing, occlusion-aware coasting; with `motion`, the detector's motion evidence from the
// last second of scans as well); otherwise the detector's pairing + update().
void runPipeline(benchmark::State& state, Association assoc, bool pairing_with_tracks, bool motion = true,
                 bool joint_pairs = true, const DetectorParams& dp = {}, const MotionEvidenceParams& mp = {}) {
  const Crowd& c = crowd();
  const PersonDetector detector(c.model, dp);
  MotionEvidence history(mp);
  TrackerParams p;
  p.association = assoc;
  if (!joint_pairs) p.joint_pairs_max_nodes = 0;
  PeopleTracker tracker(p);
  std::size_t k = 0;
  double t = 0.0;
  for (auto _ : state) {
    const LaserScan& scan = c.scans[k % c.scans.size()];
    if (k % c.scans.size() == 0) tracker.reset();  // the crowd jumps back to its start
    if (pairing_with_tracks) {
      const std::vector<LegDetection> legs = detector.detectLegs(scan, motion ? &history : nullptr, Pose2{});
      if (motion) history.add(scan, Pose2{});  // clears itself when the crowd's stamps jump back
      tracker.updateLegs(t, legs, Pose2{}, detector.params(), &scan);
    } else {
      tracker.update(t, detector.detect(scan), Pose2{});
    }
    benchmark::DoNotOptimize(tracker.tracks().data());
    t += 0.1;
    ++k;
  }
  state.SetItemsProcessed(state.iterations());  // items/s = scans/s
}

void BM_DetectAndTrack30People_GNN(benchmark::State& state) { runPipeline(state, Association::kGnn, true); }
void BM_DetectAndTrack30People_JPDA(benchmark::State& state) { runPipeline(state, Association::kJpda, true); }
void BM_DetectAndTrack30People_GNN_NoMotionEvidence(benchmark::State& state) {
  runPipeline(state, Association::kGnn, true, false);
}
// The per-leg Hungarian alone, without the joint pair search (TrackerParams::joint_pairs_max_nodes): its cost.
void BM_DetectAndTrack30People_GNN_PerLegPairing(benchmark::State& state) {
  runPipeline(state, Association::kGnn, true, true, false);
}
// The detector before it kept clusters of one and two points (detectorSegmentation): their cost.
void BM_DetectAndTrack30People_GNN_MinPoints3(benchmark::State& state) {
  DetectorParams dp;
  dp.segmentation.min_points = SegmentationParams{}.min_points;
  runPipeline(state, Association::kGnn, true, true, true, dp);
}
// The defaults before moving clusters started tracks at any score (DetectorParams::moving_min_leg_confidence 0.5,
// MotionEvidenceParams::min_free_scans 1): the cost of asking the motion evidence about more clusters.
void BM_DetectAndTrack30People_GNN_PlainBirths(benchmark::State& state) {
  DetectorParams dp;
  dp.moving_min_leg_confidence = dp.min_leg_confidence;
  MotionEvidenceParams mp;
  mp.min_free_scans = 1;
  runPipeline(state, Association::kGnn, true, true, true, dp, mp);
}
// One leg per cluster (before two legs in one cluster were split, DetectorParams::split_min_width): its cost.
void BM_DetectAndTrack30People_GNN_NoSplit(benchmark::State& state) {
  DetectorParams dp;
  dp.split_min_width = dp.max_leg_width + 0.1;
  runPipeline(state, Association::kGnn, true, true, true, dp);
}
// Without the free-space memory (MotionEvidenceParams::memory 0, before it existed): its cost.
void BM_DetectAndTrack30People_GNN_NoMemory(benchmark::State& state) {
  MotionEvidenceParams mp;
  mp.memory = 0.0;
  runPipeline(state, Association::kGnn, true, true, true, DetectorParams{}, mp);
}
void BM_DetectAndTrack30People_GNN_DetectorPairing(benchmark::State& state) {
  runPipeline(state, Association::kGnn, false, false);
}

void BM_Detect30People(benchmark::State& state) {
  const Crowd& c = crowd();
  const PersonDetector detector(c.model);
  std::size_t k = 0;
  for (auto _ : state) benchmark::DoNotOptimize(detector.detect(c.scans[k++ % c.scans.size()]));
  state.SetItemsProcessed(state.iterations());
}

// Leg detection alone, with and without the motion evidence (the history of the last second is kept as in the
// pipeline): what the evidence costs per scan.
void detectLegs30(benchmark::State& state, bool motion) {
  const Crowd& c = crowd();
  const PersonDetector detector(c.model);
  MotionEvidence history;
  std::size_t k = 0;
  for (auto _ : state) {
    const LaserScan& scan = c.scans[k++ % c.scans.size()];
    benchmark::DoNotOptimize(detector.detectLegs(scan, motion ? &history : nullptr, Pose2{}));
    if (motion) history.add(scan, Pose2{});
  }
  state.SetItemsProcessed(state.iterations());
}
void BM_DetectLegs30People(benchmark::State& state) { detectLegs30(state, false); }
void BM_DetectLegs30People_MotionEvidence(benchmark::State& state) { detectLegs30(state, true); }

void BM_Segment30People(benchmark::State& state) {
  const Crowd& c = crowd();
  std::size_t k = 0;
  for (auto _ : state) benchmark::DoNotOptimize(segmentScan(c.scans[k++ % c.scans.size()]));
  state.SetItemsProcessed(state.iterations());
}
}  // namespace

BENCHMARK(BM_Segment30People);
BENCHMARK(BM_Detect30People);
BENCHMARK(BM_DetectLegs30People);
BENCHMARK(BM_DetectLegs30People_MotionEvidence);
BENCHMARK(BM_DetectAndTrack30People_GNN);
BENCHMARK(BM_DetectAndTrack30People_JPDA);
BENCHMARK(BM_DetectAndTrack30People_GNN_NoMotionEvidence);
BENCHMARK(BM_DetectAndTrack30People_GNN_PerLegPairing);
BENCHMARK(BM_DetectAndTrack30People_GNN_MinPoints3);
BENCHMARK(BM_DetectAndTrack30People_GNN_PlainBirths);
BENCHMARK(BM_DetectAndTrack30People_GNN_NoSplit);
BENCHMARK(BM_DetectAndTrack30People_GNN_NoMemory);
BENCHMARK(BM_DetectAndTrack30People_GNN_DetectorPairing);
BENCHMARK_MAIN();
