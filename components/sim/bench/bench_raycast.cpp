// google-benchmark: one 720-beam scan in the shipped office world, grid ray casting vs the naive
// all-segments baseline (the same comparison `cairn-sim bench` prints as JSON).
#include <benchmark/benchmark.h>

#include "cairn/sim/laser.hpp"
#include "cairn/sim/world.hpp"

using namespace cairn::sim;

namespace {
struct Office {
  World world = loadWorld(resolveWorldPath("office"));
  SegmentGrid grid{world.walls};
  std::vector<Segment> dyn;
  std::vector<Circle> circles;
  Office() { world.dynamicGeometry(0.0, dyn, circles); }
};
const Office& office() {
  static const Office o;
  return o;
}
const Pose2 kPoses[4] = {{2.0, 12.55, 0.0}, {20.4, 9.0, 1.2}, {25.0, 20.0, -2.0}, {40.0, 12.55, 3.0}};
}  // namespace

static void BM_ScanGrid(benchmark::State& state) {
  const Office& o = office();
  const LaserSimulator laser(LaserConfig{}, o.grid);
  std::vector<RayHit> hits;
  std::size_t k = 0;
  for (auto _ : state) {
    laser.castIdeal(kPoses[k++ % 4], o.dyn, o.circles, hits);
    benchmark::DoNotOptimize(hits.data());
  }
}
BENCHMARK(BM_ScanGrid);

static void BM_ScanNaive(benchmark::State& state) {
  const Office& o = office();
  std::vector<Segment> all = o.world.walls;
  all.insert(all.end(), o.dyn.begin(), o.dyn.end());
  const LaserConfig cfg;
  std::size_t k = 0;
  for (auto _ : state) {
    const Pose2& p = kPoses[k++ % 4];
    double acc = 0;
    for (int i = 0; i < cfg.beams(); ++i) {
      const double a = p.theta + cfg.angleMin() + i * cfg.resolution;
      const Vec2 d{std::cos(a), std::sin(a)};
      RayHit h = castNaive(all, {p.x, p.y}, d, cfg.range_max);
      for (const auto& c : o.circles) {
        const double t = rayCircle({p.x, p.y}, d, c.center, c.radius);
        if (t >= 0 && t < h.range) h.range = t;
      }
      acc += h.range;
    }
    benchmark::DoNotOptimize(acc);
  }
}
BENCHMARK(BM_ScanNaive);

BENCHMARK_MAIN();
