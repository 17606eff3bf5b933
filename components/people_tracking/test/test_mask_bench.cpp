// mask-bench end to end (simulator -> people pipeline -> two GraphSlam instances), one short seeded run.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <vector>

#include "mask_bench.hpp"

using namespace cairn::people_tracking;

namespace {
MaskBenchParams closeGuide(MaskMode mode) {
  MaskBenchParams p;  // apartment, home_tour, robot follows the guide
  p.seed = 1;
  p.fov_deg = 180.0;         // Yuan's front laser
  p.follow_distance = 0.7;   // guide close ahead: the mask covers ~50 beams of the 360
  p.mask = mode;
  return p;
}
}  // namespace

// cairn's default mask (returns inside the guide's circle) must not cost SLAM accuracy even with the guide close
// ahead, where Yuan's tangent mask hides the walls beside the guide (docs/benchmarks.md: 12x the error, median
// of 20 seeds). The guide must actually be tracked and masked, SLAM must beat odometry by far, and the masked
// map must hold no leg imprints.
TEST(MaskBench, InsideMaskKeepsSlamAccuracyWithTheGuideCloseAhead) {
  const MaskBenchResult r = runMaskBench(closeGuide(MaskMode::kReturnsInside));
  EXPECT_GT(r.scans, 300u);
  EXPECT_GT(r.travelled, 12.0);
  EXPECT_GT(r.guide_tracked, 0.8);
  EXPECT_GT(r.masked_beams_per_tracked_scan, 3.0);  // the legs' returns
  EXPECT_GT(r.odometry.rmse, 0.2);
  EXPECT_LT(r.unmasked.rmse, 0.05);
  EXPECT_LT(r.masked.rmse, 1.5 * r.unmasked.rmse + 0.005);
  EXPECT_EQ(r.map_masked.imprints, 0u);
  EXPECT_LE(r.map_masked.spurious, r.map_unmasked.spurious + 5);
}

TEST(MaskBench, TangentMaskHidesMoreBeamsThanTheInsideMask) {
  const MaskBenchResult t = runMaskBench(closeGuide(MaskMode::kTangents));
  const MaskBenchResult i = runMaskBench(closeGuide(MaskMode::kReturnsInside));
  EXPECT_GT(t.masked_beams_per_tracked_scan, 2.0 * i.masked_beams_per_tracked_scan);
}

TEST(MaskBench, BadRouteIsAnInputError) {
  MaskBenchParams p;
  p.route = "no_such_route";
  EXPECT_THROW(runMaskBench(p), InputError);
}

// Yuan's effect where a guide does disturb SLAM: the office corridor (46 m, featureless along its axis) with a
// front laser and the guide walking ahead. Masking (inside mode) lowers the error in 16 of 20 seeds
// (docs/benchmarks.md, median -49 %); here the median of seeds 1-3 must be at least 20 % lower.
TEST(MaskBench, MaskingLowersSlamErrorInACorridorWithAFrontLaser) {
  std::vector<double> ratios;
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    MaskBenchParams p;
    p.world = "office";
    p.route = "corridor_patrol";
    p.keep_spurs = true;    // a -> b -> a: stop before the guide turns round
    p.max_duration = 88.0;
    p.fov_deg = 180.0;
    p.mask = MaskMode::kReturnsInside;
    p.seed = seed;
    const MaskBenchResult r = runMaskBench(p);
    EXPECT_GT(r.guide_tracked, 0.9) << "seed " << seed;
    EXPECT_GT(r.travelled, 40.0) << "seed " << seed;
    ratios.push_back(r.masked.rmse / r.unmasked.rmse);
  }
  std::sort(ratios.begin(), ratios.end());
  EXPECT_LT(ratios[1], 0.8) << ratios[0] << " " << ratios[1] << " " << ratios[2];
}

// The world: the apartment with a short-range front laser (4 m, Hokuyo URG-04LX class). The home tour's
// 6.7 m hallway then has no visible end, the guide walking ahead is the only feature along it, and the unmasked
// SLAM error grows to Yuan's level (0.16 m mean over 20 seeds, with leg imprints in the map); masking the
// guide's returns lowers it in 20 of 20 seeds (docs/benchmarks.md, median -84 %). Here: each of seeds 1-3
// at least 40 % lower, and no leg imprints in the masked map.
TEST(MaskBench, MaskingLowersSlamErrorInTheApartmentWithAShortRangeFrontLaser) {
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    MaskBenchParams p = closeGuide(MaskMode::kReturnsInside);
    p.range_max = 4.0;
    p.seed = seed;
    const MaskBenchResult r = runMaskBench(p);
    EXPECT_GT(r.guide_tracked, 0.8) << "seed " << seed;
    EXPECT_GT(r.travelled, 12.0) << "seed " << seed;
    EXPECT_LT(r.masked.rmse, 0.6 * r.unmasked.rmse) << "seed " << seed << ": " << r.masked.rmse << " vs "
                                                    << r.unmasked.rmse;
    EXPECT_EQ(r.map_masked.imprints, 0u) << "seed " << seed;
  }
}
