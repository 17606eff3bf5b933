// cairn_copa::CopaMapNode in a container, queried over DDS from a node in another cairn::Context:
//  * a small CoPA-Map model (trained here on seeded planted data, saved with saveModel) is loaded through
//    model_file; ~/query_rate and ~/expected_count must equal the core's predict()/expectedCount() on the same
//    file (eq. 4.19, §4.2.5), the latched rate map must be the model's mean at rate_map.time, and bad requests
//    get success = false while the component keeps serving;
//  * online: the robot pose from TF (or the odometry fallback) and people tracks over DDS are gridified (§4.2.2), ~/retrain trains in the background and
//    swaps the model in (ModelInfo version 1); the cell where the person stood gets the higher rate;
//  * launch-spec validation of the component's parameters (dry-run construction).
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <optional>
#include <random>
#include <thread>

#include "cairn/test_support.hpp"
#include "cairn/container.hpp"
#include "cairn/copa_map/copa_map.hpp"
#include "cairn/copa_map/io.hpp"
#include "cairn/launch.hpp"
#include "cairn_copa_msgs/msg/ModelInfo.hpp"
#include "cairn_copa_msgs/srv/ExpectedCount.hpp"
#include "cairn_copa_msgs/srv/QueryRate.hpp"
#include "cairn_copa_msgs/srv/Retrain.hpp"
#include "cairn_people_msgs/msg/TrackedPersons.hpp"
#include "nav_msgs/msg/OccupancyGrid.hpp"
#include "nav_msgs/msg/Odometry.hpp"
#include "tf2_msgs/msg/TFMessage.hpp"

using namespace std::chrono_literals;
namespace cm = cairn::copa_map;
namespace cmsg = cairn_copa_msgs::msg;
namespace csrv = cairn_copa_msgs::srv;

namespace {

builtin_interfaces::msg::Time stampOf(double s) {
  builtin_interfaces::msg::Time t;
  t.sec = static_cast<int32_t>(std::floor(s));
  t.nanosec = static_cast<uint32_t>(std::llround((s - std::floor(s)) * 1e9));
  return t;
}

geometry_msgs::msg::TransformStamped transformOf(const std::string& parent, const std::string& child, double s,
                                                double x, double y) {
  geometry_msgs::msg::TransformStamped t;
  t.header.stamp = stampOf(s);
  t.header.frame_id = parent;
  t.child_frame_id = child;
  t.transform.translation.x = x;
  t.transform.translation.y = y;
  t.transform.rotation.w = 1.0;
  return t;
}

constexpr auto waitFor = &cairn::testing::wait_for;  // cairn/test_support.hpp

// A small model on planted moving-robot data (as test_copa_map.cpp): rate bump(x) (1 + 0.8 cos(2π t / 12)) on
// 6 x 4 cells of 1 m over 48 bins, each cell-bin seen with probability 0.5, counts Poisson (seeded).
cm::CopaMap trainSmallModel() {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Eigen::Vector3d> xs;
  std::vector<double> ys, ds;
  for (int t = 0; t < 48; ++t)
    for (int ix = 0; ix < 6; ++ix)
      for (int iy = 0; iy < 4; ++iy) {
        if (u(rng) < 0.5) continue;
        const double x1 = ix + 0.5, x2 = iy + 0.5;
        const double lam = (3.0 * std::exp(-((x1 - 2.5) * (x1 - 2.5) + (x2 - 1.5) * (x2 - 1.5)) / 4.0) + 0.5) *
                           (1.0 + 0.8 * std::cos(2 * M_PI * t / 12.0));
        const double delta = 0.1 + 0.9 * u(rng);
        std::poisson_distribution<int> pois(lam * delta);
        const int c = pois(rng);
        xs.emplace_back(x1, x2, t);
        ys.push_back(c > 0 ? c / delta : 1e-6);
        ds.push_back(delta);
      }
  const auto n = static_cast<Eigen::Index>(xs.size());
  Eigen::MatrixXd X(n, 3);
  Eigen::VectorXd y(n), d(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    X.row(i) = xs[static_cast<std::size_t>(i)].transpose();
    y(i) = ys[static_cast<std::size_t>(i)];
    d(i) = ds[static_cast<std::size_t>(i)];
  }
  cm::CopaMapConfig cfg;
  cfg.cell_size = 1.0;
  cfg.alpha_ind = 0.04;
  cfg.period_init.period_max = 24.0;
  cm::CopaMap model = cm::CopaMap::initialize(X, y, d, cfg);
  cm::TrainConfig tc;
  tc.batch_size = 300;
  tc.max_iterations = 60;
  tc.seed = 3;
  const auto rep = model.train(X, y, tc);
  EXPECT_FALSE(rep.diverged) << rep.message;
  return model;
}

// The test's own node in a separate context: everything it exchanges with the component goes over DDS.
struct Remote {
  std::shared_ptr<cairn::Context> ctx = cairn::Context::create();
  cairn::Executor exec;
  std::unique_ptr<cairn::Node> node;
  std::thread spinner;
  std::mutex mu;
  std::optional<cmsg::ModelInfo> info;
  std::optional<nav_msgs::msg::OccupancyGrid> rate_map;
  std::shared_ptr<cairn::Subscription<cmsg::ModelInfo>> info_sub;
  std::shared_ptr<cairn::Subscription<nav_msgs::msg::OccupancyGrid>> map_sub;
  std::shared_ptr<cairn::Client<csrv::QueryRate_Request, csrv::QueryRate_Response>> query;
  std::shared_ptr<cairn::Client<csrv::ExpectedCount_Request, csrv::ExpectedCount_Response>> count;
  std::shared_ptr<cairn::Client<csrv::Retrain_Request, csrv::Retrain_Response>> retrain;

  Remote() {
    cairn::NodeOptions o("client", &exec);
    o.context = ctx;
    o.start_parameter_services = false;
    node = std::make_unique<cairn::Node>(o);
    info_sub = node->create_subscription<cmsg::ModelInfo>("copa/model_info", cairn::QoS::latched(), [this](const cmsg::ModelInfo& m, const cairn::MessageInfo& mi) {
      EXPECT_FALSE(mi.from_intra_process);
      std::lock_guard l(mu);
      info = m;
    });
    map_sub = node->create_subscription<nav_msgs::msg::OccupancyGrid>("copa/rate_map", cairn::QoS::latched(), [this](const nav_msgs::msg::OccupancyGrid& m) {
      std::lock_guard l(mu);
      rate_map = m;
    });
    query = node->create_client<csrv::QueryRate_Request, csrv::QueryRate_Response>("/copa_map/query_rate");
    count = node->create_client<csrv::ExpectedCount_Request, csrv::ExpectedCount_Response>("/copa_map/expected_count");
    retrain = node->create_client<csrv::Retrain_Request, csrv::Retrain_Response>("/copa_map/retrain");
    spinner = std::thread([this] { exec.spin(); });
  }
  ~Remote() {
    exec.cancel();
    spinner.join();
  }
};

// The component in an in-process container of its own context.
struct Container {
  std::shared_ptr<cairn::Context> ctx = cairn::Context::create();
  cairn::Executor exec;
  cairn::ComponentLoader loader;
  std::unique_ptr<cairn::ComponentManager> mgr;
  std::thread spinner;
  explicit Container(const cairn::LoadRequest& req) {
    mgr = std::make_unique<cairn::ComponentManager>(ctx, exec, "copa_container", loader);
    const auto r = mgr->load(req);
    EXPECT_TRUE(r.ok) << r.error;
    spinner = std::thread([this] { exec.spin(); });
  }
  ~Container() {
    exec.cancel();
    spinner.join();
  }
};

}  // namespace

TEST(CopaMapComponent, ServesTheLoadedModelOverDdsLikeTheCore) {
  const std::string path = testing::TempDir() + "/cairn_copa_component_model.txt";
  cm::saveModel(trainSmallModel(), path);
  const cm::CopaMap core = cm::loadModel(path);  // what the component loads

  const double t_origin = 1000.0, tau = 60.0;
  const double map_time = t_origin + (10 + 0.5) * tau;  // centre of bin 10 -> model t = 10
  cairn::LoadRequest req{"cairn_copa::CopaMapNode", "copa_map"};
  req.parameters["model_file"] = path;
  req.parameters["cell_size"] = 1.0;
  req.parameters["time_bin"] = tau;
  req.parameters["t_origin"] = t_origin;
  req.parameters["grid.nx"] = int64_t{6};
  req.parameters["grid.ny"] = int64_t{4};
  req.parameters["rate_map.time"] = map_time;
  req.parameters["retrain_period"] = 0.0;
  Container container(req);
  Remote remote;

  // Rate queries: ROS-time stamps and the model's own time axis.
  csrv::QueryRate_Request rq;
  std::vector<double> tb;
  for (int i = 0; i < 12; ++i) {
    rq.x1.push_back(0.3 + 0.45 * i);
    rq.x2.push_back(0.2 + 0.3 * i);
    tb.push_back(3.0 + 1.7 * i);
    rq.t.push_back(t_origin + (tb.back() + 0.5) * tau);
  }
  Eigen::MatrixXd Q(12, 3);
  for (int i = 0; i < 12; ++i) Q.row(i) << rq.x1[static_cast<std::size_t>(i)], rq.x2[static_cast<std::size_t>(i)], (rq.t[static_cast<std::size_t>(i)] - t_origin) / tau - 0.5;
  const cm::RatePrediction expect = core.predict(Q);
  const auto rs = remote.query->call(rq, 30s);
  ASSERT_TRUE(rs.has_value()) << "query_rate did not answer";
  ASSERT_TRUE(rs->success) << rs->message;
  ASSERT_EQ(rs->mean.size(), 12u);
  ASSERT_EQ(rs->stddev.size(), 12u);
  EXPECT_EQ(rs->model_version, 0u);
  EXPECT_EQ(rs->rate_unit, 3600.0);
  double spread = 0;
  for (int i = 0; i < 12; ++i) {
    EXPECT_DOUBLE_EQ(rs->mean[static_cast<std::size_t>(i)], expect.mean(i)) << i;
    EXPECT_DOUBLE_EQ(rs->stddev[static_cast<std::size_t>(i)], expect.std(i)) << i;
    EXPECT_GT(expect.std(i), 0.0);
    spread = std::max(spread, std::abs(expect.mean(i) - expect.mean(0)));
  }
  EXPECT_GT(spread, 0.1) << "the model predicts a constant: the comparison would not see swapped points";

  csrv::QueryRate_Request rb = rq;
  rb.t = tb;
  rb.time_in_bins = true;
  Eigen::MatrixXd Qb = Q;
  for (int i = 0; i < 12; ++i) Qb(i, 2) = tb[static_cast<std::size_t>(i)];
  const cm::RatePrediction expect_b = core.predict(Qb);
  const auto rsb = remote.query->call(rb, 30s);
  ASSERT_TRUE(rsb && rsb->success);
  for (int i = 0; i < 12; ++i) EXPECT_DOUBLE_EQ(rsb->mean[static_cast<std::size_t>(i)], expect_b.mean(i)) << i;

  // Expected count in a box over [t0, t1] (§4.2.5).
  csrv::ExpectedCount_Request cq;
  cq.x1_min = 1.0, cq.x1_max = 4.0, cq.x2_min = 0.5, cq.x2_max = 3.0;
  cq.t0 = t_origin + 5.0 * tau, cq.t1 = t_origin + 9.0 * tau;
  cq.samples_per_cell = 2;
  const double n_expect = core.expectedCount(1.0, 4.0, 0.5, 3.0, 5.0 - 0.5, 9.0 - 0.5, 2);
  const auto cs = remote.count->call(cq, 30s);
  ASSERT_TRUE(cs.has_value());
  ASSERT_TRUE(cs->success) << cs->message;
  // The core integrates rates (per hour) over bins of τ = 60 s: a count needs τ / rate_unit (it was 60x too high).
  EXPECT_DOUBLE_EQ(cs->expected_count, n_expect * tau / 3600.0);
  EXPECT_GT(n_expect, 0.0);

  // Bad requests: an error reply, and the component keeps serving.
  csrv::QueryRate_Request bad = rq;
  bad.x2.pop_back();
  auto r = remote.query->call(bad, 30s);
  ASSERT_TRUE(r.has_value());
  EXPECT_FALSE(r->success);
  EXPECT_NE(r->message.find("different lengths"), std::string::npos) << r->message;
  bad = rq;
  bad.x1[3] = std::numeric_limits<double>::quiet_NaN();
  r = remote.query->call(bad, 30s);
  ASSERT_TRUE(r.has_value());
  EXPECT_FALSE(r->success);
  csrv::ExpectedCount_Request bad_c = cq;
  std::swap(bad_c.x1_min, bad_c.x1_max);
  auto c = remote.count->call(bad_c, 30s);
  ASSERT_TRUE(c.has_value());
  EXPECT_FALSE(c->success);
  bad_c = cq;
  bad_c.x1_max = 1e6;  // 1e12 prediction points
  c = remote.count->call(bad_c, 30s);
  ASSERT_TRUE(c.has_value());
  EXPECT_FALSE(c->success);
  const auto again = remote.query->call(rq, 30s);
  ASSERT_TRUE(again && again->success);
  EXPECT_DOUBLE_EQ(again->mean[5], expect.mean(5));

  // Latched model info and rate map (mean at the cell centres at rate_map.time, scaled to 0..100).
  ASSERT_TRUE(waitFor([&] {
    std::lock_guard l(remote.mu);
    return remote.info.has_value() && remote.rate_map.has_value();
  }, 30s)) << "no model info / rate map";
  std::lock_guard l(remote.mu);
  EXPECT_TRUE(remote.info->has_model);
  EXPECT_EQ(remote.info->model_version, 0u);
  EXPECT_EQ(remote.info->source, path);
  EXPECT_EQ(remote.info->inducing_points, static_cast<uint32_t>(core.model().latents().front().Z.rows()));
  const auto& g = *remote.rate_map;
  ASSERT_EQ(g.info.width, 6u);
  ASSERT_EQ(g.info.height, 4u);
  ASSERT_EQ(g.data.size(), 24u);
  EXPECT_EQ(g.header.stamp, stampOf(map_time));
  Eigen::MatrixXd G(24, 3);
  for (int iy = 0; iy < 4; ++iy)
    for (int ix = 0; ix < 6; ++ix) G.row(iy * 6 + ix) << ix + 0.5, iy + 0.5, 10.0;
  const Eigen::VectorXd m = core.predict(G).mean;
  for (int i = 0; i < 24; ++i)
    EXPECT_EQ(g.data[static_cast<std::size_t>(i)], static_cast<int8_t>(std::lround(100.0 * m(i) / m.maxCoeff()))) << i;
  std::filesystem::remove(path);
}

namespace {
// Robot pose from TF (map <- odom static, odom <- base_link per step) or from the `odom` topic (fallback); the
// robot is at (2, 2) in the model frame either way.
void gridifyAndRetrain(bool pose_from_tf) {
  cairn::LoadRequest req{"cairn_copa::CopaMapNode", "copa_map"};
  req.parameters["pose_source"] = std::string(pose_from_tf ? "tf" : "odom");
  req.parameters["cell_size"] = 0.5;
  req.parameters["time_bin"] = 20.0;  // τ
  req.parameters["min_duration"] = 1.0;
  req.parameters["fov_radius"] = 10.0;
  req.parameters["max_pose_gap"] = 1.5;
  req.parameters["grid.nx"] = int64_t{8};
  req.parameters["grid.ny"] = int64_t{8};
  req.parameters["detection_period"] = 0.9;
  req.parameters["retrain_period"] = 0.0;
  req.parameters["min_training_points"] = int64_t{100};
  req.parameters["train.max_iterations"] = int64_t{40};
  req.parameters["train.batch_size"] = int64_t{500};
  Container container(req);
  Remote remote;
  auto odom_pub = remote.node->create_publisher<nav_msgs::msg::Odometry>("odom", cairn::QoS{}.keep_last(1000));
  auto tf_pub = remote.node->create_publisher<tf2_msgs::msg::TFMessage>("/tf", cairn::QoS{}.keep_last(1000));
  auto tf_static_pub = remote.node->create_publisher<tf2_msgs::msg::TFMessage>("/tf_static", cairn::QoS::latched());
  auto tracks_pub = remote.node->create_publisher<cairn_people_msgs::msg::TrackedPersons>("people/tracks", cairn::QoS{}.keep_last(1000));
  if (pose_from_tf) {
    tf2_msgs::msg::TFMessage st;
    st.transforms.push_back(transformOf("map", "odom", 0.0, 0.5, -0.5));
    tf_static_pub->publish(st);
  }
  ASSERT_TRUE(waitFor([&] {
    const bool pose = pose_from_tf ? tf_pub->inter_process_subscription_count() > 0 &&
                                         tf_static_pub->inter_process_subscription_count() > 0
                                   : odom_pub->inter_process_subscription_count() > 0;
    return pose && tracks_pub->inter_process_subscription_count() > 0;
  }, 20s));
  // The fallback topic is not subscribed with TF poses and vice versa.
  EXPECT_EQ(odom_pub->inter_process_subscription_count() > 0, !pose_from_tf);

  // No model yet: queries are refused.
  csrv::QueryRate_Request rq;
  rq.x1 = {1.25, 3.25};
  rq.x2 = {1.25, 3.25};
  rq.t = {5.0, 5.0};
  rq.time_in_bins = true;
  auto r = remote.query->call(rq, 30s);
  ASSERT_TRUE(r.has_value());
  EXPECT_FALSE(r->success);
  EXPECT_NE(r->message.find("no model"), std::string::npos) << r->message;

  // A robot standing at (2, 2) sees all 64 cells; one person stands in cell (2, 2) (centre (1.25, 1.25)) for
  // 24 bins of 20 s. Tracks at 1 Hz; a few bad messages on the way (ignored with a warning).
  for (int k = 0; k <= 480; ++k) {
    nav_msgs::msg::Odometry o;
    o.header.stamp = stampOf(k);
    o.header.frame_id = "odom";
    o.pose.pose.position.x = 2.0;
    o.pose.pose.position.y = 2.0;
    if (k == 100) o.pose.pose.position.x = std::numeric_limits<double>::quiet_NaN();
    if (pose_from_tf) {
      tf2_msgs::msg::TFMessage tf;
      tf.transforms.push_back(transformOf("odom", "base_link", k, 1.5, 2.5));
      if (k == 100) tf.transforms.back().transform.translation.x = std::numeric_limits<double>::quiet_NaN();
      tf_pub->publish(tf);
      o.header.frame_id = "map";
    } else {
      odom_pub->publish(o);
    }
    cairn_people_msgs::msg::TrackedPersons tp;
    tp.header = o.header;
    cairn_people_msgs::msg::TrackedPerson p;
    p.position.x = 1.2;
    p.position.y = 1.3;
    tp.tracks.push_back(p);
    if (k == 200) tp.tracks.back().position.y = std::numeric_limits<double>::infinity();
    tracks_pub->publish(tp);
    if (k == 300) {  // time going backwards: ignored
      o.header.stamp = stampOf(10);
      if (pose_from_tf) {
        tf2_msgs::msg::TFMessage tf;
        tf.transforms.push_back(transformOf("odom", "base_link", 10, -3.0, -3.0));
        tf_pub->publish(tf);
      } else {
        odom_pub->publish(o);
      }
    }
    std::this_thread::sleep_for(1ms);  // pacing only; lost messages would not change the assertions
  }
  // Retrain once everything sent has been gridified: with flush, all bins are closed first.
  std::optional<csrv::Retrain_Response> rr;
  ASSERT_TRUE(waitFor([&] {
    csrv::Retrain_Request rt;
    rt.flush = true;
    rr = remote.retrain->call(rt, 30s);
    return rr.has_value() && rr->accepted;
  }, 30s)) << (rr ? rr->message : "no reply");
  // All 64 cells seen in each of the 24 closed 20 s bins: exactly 64 × 24 points. The NaN pose, the infinite
  // track position and the pose from the past must neither add a cell/bin nor close or drop one. (A lost stream
  // message leaves a gap under max_pose_gap 1.5 s and min_duration 1 s per bin: no change.)
  EXPECT_EQ(rr->training_points, 64u * 24u);

  ASSERT_TRUE(waitFor([&] {
    std::lock_guard l(remote.mu);
    return remote.info && remote.info->model_version == 1;
  }, 60s)) << "the retrained model was not swapped in";
  {
    std::lock_guard l(remote.mu);
    EXPECT_TRUE(remote.info->has_model);
    EXPECT_EQ(remote.info->source, "trained");
    EXPECT_EQ(remote.info->training_points, rr->training_points);
    EXPECT_GT(remote.info->inducing_points, 0u);
  }
  r = remote.query->call(rq, 30s);
  ASSERT_TRUE(r.has_value());
  ASSERT_TRUE(r->success) << r->message;
  EXPECT_EQ(r->model_version, 1u);
  // 20 samples per 20 s bin = 3600 per hour in the person's cell, ~0 elsewhere (eq. 4.6).
  EXPECT_GT(r->mean[0], 10.0 * r->mean[1] + 100.0) << r->mean[0] << " vs " << r->mean[1];
}
}  // namespace

TEST(CopaMapComponent, GridifiesTfPoseAndTracksAndRetrainsInTheBackground) { gridifyAndRetrain(true); }

TEST(CopaMapComponent, OdometryTopicFallbackGridifiesAndRetrains) { gridifyAndRetrain(false); }

namespace {
std::string launchError(const std::string& params) {
  return cairn::launch_spec_error(
        "containers:\n  - name: c\n    components:\n      - class: cairn_copa::CopaMapNode\n"
        "        params: " + params + "\n",
      "copa.yaml");
}
}  // namespace

TEST(CopaMapComponent, LaunchSpecValidatesItsParameters) {
  EXPECT_EQ(launchError("{cell_size: 0.5, time_bin: 3600, fov_radius: 3.5, retrain_period: 86400, grid.nx: 10, grid.ny: 8}"), "");
  EXPECT_EQ(launchError("{cell_size: fine}"),
            "copa.yaml:5: params: /copa_map_node: parameter 'cell_size' expects double, got string (\"fine\")");
  auto e = launchError("{cell_size: -1.0}");
  EXPECT_NE(e.find("cell_size"), std::string::npos) << e;
  EXPECT_EQ(e.rfind("copa.yaml:5:", 0), 0u) << e;
  e = launchError("{model_file: /no/such/model.txt}");
  EXPECT_NE(e.find("model_file: "), std::string::npos) << e;
  EXPECT_NE(e.find("/no/such/model.txt"), std::string::npos) << e;
  e = launchError("{grid.nx: 10}");
  EXPECT_NE(e.find("'grid.nx' and 'grid.ny' must both be 0 or both positive"), std::string::npos) << e;
  e = launchError("{map_file: /no/such/map.yaml}");
  EXPECT_NE(e.find("map_file: "), std::string::npos) << e;
  // A map YAML with a malformed value names the file, line and key (atof used to read it as 0 / all occupied).
  const std::string bad_map = testing::TempDir() + "/cairn_copa_component_bad_map.yaml";
  { std::ofstream(bad_map) << "image: map.pgm\nresolution: 0.05\norigin: [0, 0, 0]\noccupied_thresh: high\n"; }
  e = launchError("{map_file: " + bad_map + "}");
  EXPECT_NE(e.find("map_file: " + bad_map + ":4: 'occupied_thresh' expects a number, got 'high'"), std::string::npos) << e;
  { std::ofstream(bad_map) << "image: map.pgm\nresolution: 0.05\norigin: [0, zero, 0]\n"; }
  e = launchError("{map_file: " + bad_map + "}");
  EXPECT_NE(e.find(bad_map + ":3: 'origin' expects a number, got 'zero'"), std::string::npos) << e;
  { std::ofstream(bad_map) << "image: map.pgm\nnegate: yes\n"; }
  e = launchError("{map_file: " + bad_map + "}");
  EXPECT_NE(e.find(bad_map + ":2: 'negate' expects 0 or 1, got 'yes'"), std::string::npos) << e;
  std::filesystem::remove(bad_map);
  e = launchError("{pose_source: gps}");
  EXPECT_NE(e.find("pose_source: 'gps' is neither 'tf' nor 'odom'"), std::string::npos) << e;
  e = launchError("{train.no_such_param: 1}");
  EXPECT_NE(e.find("train.no_such_param"), std::string::npos) << e;

  // A corrupt model file (wrong version line) is reported too.
  const std::string bad = testing::TempDir() + "/cairn_copa_component_bad_model.txt";
  { std::ofstream(bad) << "cairn-copa-model 99\n"; }
  e = launchError("{model_file: " + bad + "}");
  EXPECT_NE(e.find("model_file: " + bad + ":1:"), std::string::npos) << e;
  std::filesystem::remove(bad);
}
