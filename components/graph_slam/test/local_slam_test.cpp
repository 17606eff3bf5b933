// LocalSlam: bad input, submap lifecycle, and drift on a simulated run through the office world compared
// with the (deliberately poor) odometry of the same run.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "cairn/graph_slam/local_slam.hpp"
#include "cairn/sim/simulator.hpp"

namespace gs = cairn::graph_slam;
namespace sim = cairn::sim;

namespace {

/// A ring of returns around the sensor (a round room of radius r with some bumps).
gs::RangeData ring(double r, int n = 200) {
  gs::RangeData d;
  for (int i = 0; i < n; ++i) {
    const double a = 2 * 3.14159265358979 * i / n;
    const double rr = r + 0.3 * std::sin(3 * a) + 0.2 * std::cos(7 * a);
    d.returns.emplace_back(rr * std::cos(a), rr * std::sin(a));
  }
  return d;
}

struct SimRun {
  std::vector<sim::LaserScan> scans;
  std::vector<sim::Odometry> odom, truth;
};

/// 40 s of the office world's visit_kitchen route with noisy odometry (scale error and heading drift).
SimRun simulate(double seconds) {
  const sim::World office = sim::loadWorld(sim::resolveWorldPath("office"));
  sim::SimConfig cfg;
  cfg.seed = 3;
  cfg.people = false;
  cfg.crowd = false;
  cfg.odometry.scale_error = 0.03;
  cfg.odometry.heading_drift = 0.02;  // rad/m
  cfg.odometry.sigma_rot = 0.02;
  cfg.laser.resolution = 1.0 * 3.14159265358979 / 180.0;  // 360 beams
  sim::Simulator s(office, cfg);
  s.followRoute(office.routes.at("visit_kitchen"));
  sim::SimOutput out;
  s.advance(seconds, out);
  return {out.scans, out.odometry, out.ground_truth};
}

/// Sample of a stream nearest to stamp t (streams are sorted).
const sim::Odometry& nearest(const std::vector<sim::Odometry>& v, double t) {
  auto it = std::lower_bound(v.begin(), v.end(), t, [](const sim::Odometry& o, double s) { return o.stamp < s; });
  if (it == v.end()) return v.back();
  if (it != v.begin() && std::abs((it - 1)->stamp - t) < std::abs(it->stamp - t)) --it;
  return *it;
}

}  // namespace

TEST(LocalSlam, BadInputIsRejectedWithAReason) {
  gs::LocalSlam slam;
  // Empty scan and a scan of only invalid beams.
  EXPECT_FALSE(slam.addScan(1.0, gs::RangeData{}, std::nullopt));
  EXPECT_NE(slam.lastError().find("valid returns"), std::string::npos) << slam.lastError();
  sim::LaserScan bad;
  bad.angle_increment = 0.01F;
  bad.range_max = 20.0F;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  bad.ranges = {nan, 0.0F, -1.0F, std::numeric_limits<float>::infinity(), nan};
  EXPECT_FALSE(slam.addScan(1.0, gs::toRangeData(bad, gs::Pose2{}, slam.options().filter), std::nullopt));
  // Non-finite points in range data are dropped, not inserted.
  gs::RangeData d = ring(4.0);
  d.returns.emplace_back(nan, 1.0);
  d.returns.emplace_back(std::numeric_limits<double>::infinity(), 0.0);
  auto r = slam.addScan(2.0, d, std::nullopt);
  ASSERT_TRUE(r) << slam.lastError();
  EXPECT_TRUE(r->inserted);
  EXPECT_FALSE(r->matched);
  for (const auto& p : r->range_data.returns) EXPECT_TRUE(p.allFinite());
  // Time going backwards.
  EXPECT_FALSE(slam.addScan(1.5, ring(4.0), std::nullopt));
  EXPECT_NE(slam.lastError().find("backwards"), std::string::npos) << slam.lastError();
  EXPECT_FALSE(slam.addScan(std::numeric_limits<double>::quiet_NaN(), ring(4.0), std::nullopt));
  // Non-finite odometry is treated as missing; the next good scan is matched.
  gs::Pose2 nan_odom;
  nan_odom.theta = nan;
  r = slam.addScan(2.1, ring(4.0), nan_odom);
  ASSERT_TRUE(r) << slam.lastError();
  EXPECT_TRUE(r->matched);
  EXPECT_LT(r->local_pose.t.norm(), 0.02);
  EXPECT_TRUE(slam.lastError().empty());
}

TEST(LocalSlam, MotionFilterAndSubmapLifecycle) {
  gs::LocalSlamOptions o;
  o.scans_per_submap = 3;
  gs::LocalSlam slam(o);
  const gs::RangeData d = ring(5.0);
  // Standing still: only the first scan and then one every motion_max_time are inserted.
  int inserted = 0;
  for (int i = 0; i < 20; ++i) {
    gs::Pose2 odom;
    auto r = slam.addScan(0.5 * i, d, odom);
    ASSERT_TRUE(r);
    inserted += r->inserted;
    EXPECT_LT(r->local_pose.t.norm(), 0.02);
  }
  EXPECT_EQ(inserted, 2);  // t = 0 and t = 5.5 (the first stamp more than 5 s later)
  // Moving (odometry says 0.3 m per scan, the scene moves with it): every scan inserted.
  gs::LocalSlam moving(o);
  std::size_t last_finished = 0;
  for (int i = 0; i < 12; ++i) {
    gs::Pose2 odom;
    odom.t = {0.3 * i, 0.0};
    gs::RangeData di = ring(5.0);
    for (auto& p : di.returns) p.x() -= 0.3 * i;  // a static world seen from the moving base
    auto r = moving.addScan(0.1 * i, di, odom);
    ASSERT_TRUE(r) << moving.lastError();
    EXPECT_TRUE(r->inserted) << i;
    EXPECT_NEAR(r->local_pose.t.x(), 0.3 * i, 0.03) << i;
    EXPECT_LE(moving.activeSubmaps().size(), 2U);
    EXPECT_GE(r->insertion_submaps.size(), 1U);
    const auto fresh = moving.takeNewlyFinished();
    last_finished += fresh.size();
    for (const auto& s : fresh) {
      EXPECT_TRUE(s->finished);
      EXPECT_EQ(s->num_scans, 2 * o.scans_per_submap);
    }
  }
  // 12 inserted scans, submaps started every 3 and finished after 6: 0..5, 3..8, 6..11 finished.
  EXPECT_EQ(moving.finishedSubmaps().size(), 3U);
  EXPECT_EQ(last_finished, 3U);
  EXPECT_TRUE(moving.takeNewlyFinished().empty());
  EXPECT_EQ(moving.finishedSubmaps()[1]->index, 1);
  // Released: LocalSlam keeps only its active submaps; the next finished one is reported as new.
  const std::shared_ptr<const gs::Submap> kept = moving.finishedSubmaps()[0];
  moving.releaseFinished();
  EXPECT_TRUE(moving.finishedSubmaps().empty());
  EXPECT_TRUE(moving.takeNewlyFinished().empty());
  EXPECT_EQ(kept->index, 0);  // a taken submap stays valid for whoever holds it
}

TEST(LocalSlam, DriftsMuchLessThanOdometryOnASimulatedRun) {
  const SimRun run = simulate(45.0);
  ASSERT_GT(run.scans.size(), 300U);
  gs::LocalSlam slam;
  const gs::Pose2 mount = gs::toPose2(sim::LaserConfig{}.mount);
  std::optional<gs::Pose2> first_truth, first_local, first_odom;
  double max_err_slam = 0, max_err_odom = 0, final_err_slam = 0, final_err_odom = 0;
  for (const auto& scan : run.scans) {
    const gs::Pose2 odom = gs::toPose2(nearest(run.odom, scan.stamp).pose);
    const gs::Pose2 truth = gs::toPose2(nearest(run.truth, scan.stamp).pose);
    auto r = slam.addScan(scan.stamp, gs::toRangeData(scan, mount, slam.options().filter), odom);
    ASSERT_TRUE(r) << slam.lastError();
    if (!first_truth) {
      first_truth = truth;
      first_local = r->local_pose;
      first_odom = odom;
    }
    // Everything relative to the first pose (the local frame's origin is arbitrary).
    const gs::Pose2 t = gs::compose(gs::inverse(*first_truth), truth);
    const gs::Pose2 l = gs::compose(gs::inverse(*first_local), r->local_pose);
    const gs::Pose2 o = gs::compose(gs::inverse(*first_odom), odom);
    final_err_slam = (l.t - t.t).norm();
    final_err_odom = (o.t - t.t).norm();
    max_err_slam = std::max(max_err_slam, final_err_slam);
    max_err_odom = std::max(max_err_odom, final_err_odom);
  }
  RecordProperty("max_err_slam", std::to_string(max_err_slam));
  RecordProperty("max_err_odom", std::to_string(max_err_odom));
  std::printf("local SLAM max error %.3f m (final %.3f), odometry max error %.3f m (final %.3f), %zu scans, %zu inserted, %zu submaps finished\n",
              max_err_slam, final_err_slam, max_err_odom, final_err_odom, slam.scansAdded(), slam.scansInserted(),
              slam.finishedSubmaps().size());
  EXPECT_GT(max_err_odom, 0.5);  // the odometry is poor enough for the comparison to mean something
  EXPECT_LT(max_err_slam, 0.2);
  EXPECT_LT(max_err_slam, 0.25 * max_err_odom);
}

// An isolated scan that does not fit the submap is held back and goes in with the next good scan (nothing
// is lost); lost_scans such scans in a row report lost and are discarded.
TEST(LocalSlam, UnmatchedScansAreHeldBackThenFlushedOrReportedLost) {
  gs::LocalSlamOptions o;
  o.motion_min_distance = 0.0;  // every scan passes the motion filter
  o.motion_min_angle = 0.0;
  gs::LocalSlam slam(o);
  const gs::Pose2 still;
  double t = 0.0;
  for (int i = 0; i < 15; ++i) ASSERT_TRUE(slam.addScan(t += 0.1, ring(4.0), still));
  // A different room (a much smaller ring of another shape) at the same odometry pose.
  gs::RangeData other;
  for (int i = 0; i < 200; ++i) {
    const double a = 2 * 3.14159265358979 * i / 200;
    other.returns.emplace_back(1.2 * std::cos(a) + 0.4, 0.8 * std::sin(a) - 0.3);
  }
  auto odd = slam.addScan(t += 0.1, other, still);
  ASSERT_TRUE(odd);
  EXPECT_TRUE(odd->unmatched) << odd->match_score;
  EXPECT_TRUE(odd->held);
  EXPECT_FALSE(odd->inserted);
  EXPECT_FALSE(odd->lost);
  const std::size_t inserted_before = slam.scansInserted();
  auto good = slam.addScan(t += 0.1, ring(4.0), still);
  ASSERT_TRUE(good);
  EXPECT_FALSE(good->unmatched);
  ASSERT_EQ(good->flushed.size(), 1u);
  EXPECT_TRUE(good->flushed[0].inserted);
  EXPECT_DOUBLE_EQ(good->flushed[0].stamp, odd->stamp);
  EXPECT_EQ(slam.scansInserted(), inserted_before + 2);  // the held-back scan and this one
  // A third place (a square room; `other` is in the submap now): held back scan after scan, then lost.
  gs::RangeData square;
  for (int i = 0; i < 200; ++i) {
    const double u = -2.5 + 5.0 * (i % 50) / 50.0;
    const int side = i / 50;
    square.returns.emplace_back(side == 0 ? u : side == 1 ? 2.5 : side == 2 ? -u : -2.5,
                                side == 0 ? -2.5 : side == 1 ? u : side == 2 ? 2.5 : -u);
  }
  for (int i = 1; i <= o.lost_scans; ++i) {
    auto r = slam.addScan(t += 0.1, square, still);
    ASSERT_TRUE(r);
    EXPECT_TRUE(r->unmatched);
    EXPECT_EQ(r->lost, i == o.lost_scans) << i;
  }
  EXPECT_EQ(slam.scansInserted(), inserted_before + 2);  // the lost run was never inserted
  o.lost_scans = 0;  // disabled: unmatched scans are inserted as they come
  gs::LocalSlam plain(o);
  for (int i = 0; i < 15; ++i) ASSERT_TRUE(plain.addScan(i * 0.1, ring(4.0), still));
  auto r = plain.addScan(2.0, other, still);
  ASSERT_TRUE(r);
  EXPECT_TRUE(r->unmatched);
  EXPECT_FALSE(r->held);
  EXPECT_TRUE(r->inserted);
}
