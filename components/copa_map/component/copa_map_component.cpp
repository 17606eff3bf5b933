// cairn_copa::CopaMapNode — the runtime adapter of the CoPA-Map core (Stüde 2024, Ch. 4): the robot pose (TF
// map_frame <- base_frame, or an odometry topic as fallback) and people tracks in; the online gridifier (§4.2.2, eqs. 4.5-4.6) turns them into (x1, x2, t, y, Δ) cells;
// retraining (Algorithm 4.1 + §4.2.5) runs on a background thread and swaps the new model in when it finishes;
// rate queries (eq. 4.19) and expected counts ((1/(r_s² τ)) ∫ m_y, §4.2.5) are served from the current model,
// and a rate map (mean and std) is published as nav_msgs/OccupancyGrid. Thin: conversions, parameters, threads.
//
// Time axis: the model's t is in time bins of τ (the gridifier labels bin k, [t_origin + kτ, t_origin + (k+1)τ),
// with t = k). A ROS time s is mapped to the bin-centre convention t = (s - t_origin)/τ - 0.5.
#include <atomic>
#include <chrono>
#include <cmath>
#include <algorithm>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "../tools/image_io.hpp"
#include "cairn/component.hpp"
#include "cairn/tf.hpp"
#include "cairn/copa_map/copa_map.hpp"
#include "cairn/copa_map/gridifier.hpp"
#include "cairn/copa_map/io.hpp"
#include "cairn/msg_conversions.hpp"
#include "cairn_copa_msgs/msg/ModelInfo.hpp"
#include "cairn_copa_msgs/srv/ExpectedCount.hpp"
#include "cairn_copa_msgs/srv/QueryRate.hpp"
#include "cairn_copa_msgs/srv/Retrain.hpp"
#include "cairn_people_msgs/msg/TrackedPersons.hpp"
#include "nav_msgs/msg/OccupancyGrid.hpp"
#include "nav_msgs/msg/Odometry.hpp"

namespace cairn_copa {

namespace cm = cairn::copa_map;
namespace cmsg = cairn_copa_msgs::msg;
namespace csrv = cairn_copa_msgs::srv;

namespace {

using cairn::time_from_seconds;
using cairn::to_seconds;

struct StopTraining {};  // thrown from the training progress callback when the node is destroyed

}  // namespace

class CopaMapNode : public cairn::Node {
 public:
  explicit CopaMapNode(const cairn::NodeOptions& o) : cairn::Node(o) {
    using D = cairn::ParameterDescriptor;
    const std::string model_file = declare_parameter<std::string>(
        "model_file", "", D{"CoPA-Map model (cairn copa train) served from the start; empty: none until the first retraining", {}, {}, true});
    const std::string map_file = declare_parameter<std::string>(
        "map_file", "", D{"map_server YAML: occupancy for the FOV ray casting (§4.2.2) and the default grid extent; empty: the first message on `map`", {}, {}, true});
    frame_id_ = declare_parameter<std::string>("frame_id", "", D{"frame of model, odometry and tracks; messages in another frame are ignored; empty: map_frame with pose_source tf, not checked with odom", {}, {}, true});
    // Robot pose (§4.2.2 needs where the robot was to know what it observed): from TF map_frame <- base_frame
    // (default), or from an odometry topic as a fallback (e.g. a localized pose republished as Odometry).
    pose_source_ = declare_parameter<std::string>("pose_source", "tf", D{"robot pose from 'tf' (map_frame <- base_frame) or 'odom' (topic `odom`, its frame is the model frame)", {}, {}, true});
    if (pose_source_ != "tf" && pose_source_ != "odom")
      throw std::invalid_argument("pose_source: '" + pose_source_ + "' is neither 'tf' nor 'odom'");
    map_frame_ = declare_parameter<std::string>("map_frame", "map", D{"model frame when pose_source is tf (target of the TF lookup)", {}, {}, true});
    base_frame_ = declare_parameter<std::string>("base_frame", "base_link", D{"robot frame whose origin is the FOV centre (pose_source tf)", {}, {}, true});
    pose_period_ = declare_parameter<double>("pose_period", 0.1, D{"s (steady) between polls of the latest map_frame <- base_frame TF; poses are also looked up at every track stamp", 0.001, 60.0, true});
    if (pose_source_ == "tf" && frame_id_.empty()) frame_id_ = map_frame_;
    // Gridifier (gridifier.hpp; Stüde §4.2.2 / §4.3).
    gc_.cell_size = declare_parameter<double>("cell_size", gc_.cell_size, D{"r_s, m (§4.3 ATC: 0.5 m)", 0.05, 50.0, true});
    gc_.time_bin = declare_parameter<double>("time_bin", gc_.time_bin, D{"τ, s (§4.3 ATC: 60 min)", 1.0, 7.0 * 86400.0, true});
    gc_.t_origin = declare_parameter<double>("t_origin", 0.0, D{"s, ROS time of the start of time bin 0 (model t = 0)", {}, {}, true});
    gc_.fov_radius = declare_parameter<double>("fov_radius", gc_.fov_radius, D{"r_fov, m (copa-map util/fov.py; the thesis does not state it)", 0.0, 100.0, true});
    gc_.max_pose_gap = declare_parameter<double>("max_pose_gap", gc_.max_pose_gap, D{"s a pose is held; longer gaps are unobserved", 0.0, 3600.0, true});
    gc_.min_duration = declare_parameter<double>("min_duration", gc_.min_duration, D{"s, cells observed less per bin are dropped (copa-map Gridifier)", 0.0, 7.0 * 86400.0, true});
    gc_.rate_unit = declare_parameter<double>("rate_unit", gc_.rate_unit, D{"s, rates are detections per rate_unit (eq. 4.6)", 1e-3, 1e7, true});
    gc_.origin_x = declare_parameter<double>("grid.origin_x", 0.0, D{"m, lower-left corner of the grid (used when grid.nx > 0)", {}, {}, true});
    gc_.origin_y = declare_parameter<double>("grid.origin_y", 0.0, D{"m", {}, {}, true});
    gc_.nx = static_cast<int>(declare_parameter<int64_t>("grid.nx", 0, D{"cells along x1; 0: cover the map", 0.0, 100000.0, true}));
    gc_.ny = static_cast<int>(declare_parameter<int64_t>("grid.ny", 0, D{"cells along x2; 0: cover the map", 0.0, 100000.0, true}));
    if ((gc_.nx > 0) != (gc_.ny > 0)) throw std::invalid_argument("parameters 'grid.nx' and 'grid.ny' must both be 0 or both positive");
    detection_period_ = declare_parameter<double>("detection_period", 1.0, D{"s, people tracks are sampled at most once per period (c_i counts samples)", 0.0, 3600.0, true});
    flush_period_ = declare_parameter<double>("flush_period", 10.0, D{"s (steady clock), finished time bins are moved to the training set", 0.05, 3600.0, true});
    // Training (copa_map.hpp, svgp.hpp; §4.2.4-4.2.5, §4.3).
    retrain_period_ = declare_parameter<double>("retrain_period", 86400.0, D{"s of ROS time between scheduled retrainings; 0: only on ~/retrain", 0.0, 1e8, true});
    min_points_ = static_cast<std::size_t>(declare_parameter<int64_t>("min_training_points", 200, D{"cells needed before a retraining starts", 2.0, 1e9, true}));
    max_points_ = static_cast<std::size_t>(declare_parameter<int64_t>("max_training_points", 200000, D{"newest cells kept for training (older ones are dropped)", 2.0, 1e9, true}));
    mc_.alpha_ind = declare_parameter<double>("alpha_ind", mc_.alpha_ind, D{"α_ind, inducing points m = floor(α_ind n) (§4.3: 0.02)", 1e-4, 1.0, true});
    mc_.cell_size = gc_.cell_size;
    mc_.time_bin = 1.0;  // the model's time axis is in bins
    tc_.max_iterations = static_cast<int>(declare_parameter<int64_t>("train.max_iterations", tc_.max_iterations, D{"mini-batch steps (copa-map 2,500)", 1.0, 1e7, true}));
    tc_.max_seconds = declare_parameter<double>("train.max_seconds", tc_.max_seconds, D{"s per retraining", 0.1, 1e6, true});
    tc_.batch_size = static_cast<int>(declare_parameter<int64_t>("train.batch_size", tc_.batch_size, D{"mini-batch size (copa-map 1,100)", 1.0, 1e7, true}));
    tc_.tolerance = declare_parameter<double>("train.tolerance", tc_.tolerance, D{"relative epoch-ELBO change that stops training (copa-map 1e-3)", 0.0, 1.0, true});
    tc_.seed = static_cast<std::uint64_t>(declare_parameter<int64_t>("train.seed", 1, D{"mini-batch and k-means seed", 0.0, {}, true}));
    mc_.seed = mc_.period_init.seed = tc_.seed;  // as the CLI's `seed`: also Alg. 4.1's period sampling
    // Rate map output.
    rate_map_time_ = declare_parameter<double>("rate_map.time", 0.0, D{"s, ROS time the published rate map is for; 0: the time of publication", {}, {}, false});
    rate_map_max_ = declare_parameter<double>("rate_map.max_rate", 0.0, D{"rate shown as 100 in the grid; 0: the map's maximum", 0.0, 1e12, false});
    on_parameter_change([this](const std::string& name, const cairn::ParameterValue& v) -> std::optional<std::string> {
      if (name == "rate_map.time") rate_map_time_ = cairn::parameter_as<double>(v, name);
      else if (name == "rate_map.max_rate") rate_map_max_ = cairn::parameter_as<double>(v, name);
      else return std::nullopt;
      publish_pending_ = true;
      return std::nullopt;
    });

    // Files are read in a dry run too, so `cairn launch --check` reports a missing or corrupt model or map.
    if (!model_file.empty()) {
      try {
        model_ = std::make_shared<const cm::CopaMap>(cm::loadModel(model_file));
      } catch (const std::exception& e) {
        throw std::invalid_argument(std::string("model_file: ") + e.what());
      }
      if (std::abs(model_->cellSize() - gc_.cell_size) > 1e-9 * gc_.cell_size)
        CAIRN_WARN(logger(), "model_file: the model's cell size " << model_->cellSize() << " m differs from cell_size "
                                                                 << gc_.cell_size << " m (expected counts use the model's)");
      model_source_ = model_file;
    }
    if (!map_file.empty()) {
      try {
        map_ = std::make_shared<const cm::OccupancyMap>(cm::tools::loadMapYaml(map_file).map);
      } catch (const std::exception& e) {
        throw std::invalid_argument(std::string("map_file: ") + e.what());
      }
      makeGridifier();
    } else if (gc_.nx > 0) {
      makeGridifier();
    }

    const auto stream = cairn::QoS{}.keep_last(100);
    info_pub_ = create_publisher<cmsg::ModelInfo>("copa/model_info", cairn::QoS::latched());
    mean_pub_ = create_publisher<nav_msgs::msg::OccupancyGrid>("copa/rate_map", cairn::QoS::latched());
    std_pub_ = create_publisher<nav_msgs::msg::OccupancyGrid>("copa/rate_map_std", cairn::QoS::latched());
    if (pose_source_ == "odom") {
      odom_sub_ = create_subscription<nav_msgs::msg::Odometry>("odom", stream, [this](const nav_msgs::msg::Odometry& m) { onOdom(m); });
    } else {
      tf_buffer_ = std::make_shared<cairn::TransformBuffer>(30.0);
      tf_listener_ = std::make_unique<cairn::TransformListener>(*this, tf_buffer_);
    }
    tracks_sub_ = create_subscription<cairn_people_msgs::msg::TrackedPersons>(
        "people/tracks", stream, [this](const cairn_people_msgs::msg::TrackedPersons& m) { onTracks(m); });
    map_sub_ = create_subscription<nav_msgs::msg::OccupancyGrid>("map", cairn::QoS::latched(), [this](const nav_msgs::msg::OccupancyGrid& m) { onMap(m); });
    query_srv_ = create_service<csrv::QueryRate_Request, csrv::QueryRate_Response>(
        "~/query_rate", [this](const csrv::QueryRate_Request& rq, csrv::QueryRate_Response& rs) { onQueryRate(rq, rs); });
    count_srv_ = create_service<csrv::ExpectedCount_Request, csrv::ExpectedCount_Response>(
        "~/expected_count", [this](const csrv::ExpectedCount_Request& rq, csrv::ExpectedCount_Response& rs) { onExpectedCount(rq, rs); });
    retrain_srv_ = create_service<csrv::Retrain_Request, csrv::Retrain_Response>(
        "~/retrain", [this](const csrv::Retrain_Request& rq, csrv::Retrain_Response& rs) { onRetrain(rq, rs); });
    if (dry_run()) return;  // no timers, no prediction work in `cairn launch --check`

    flush_timer_ = create_wall_timer(std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::duration<double>(flush_period_)),
                                     [this] { flushGrid(false); });
    if (tf_buffer_)
      pose_timer_ = create_wall_timer(std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::duration<double>(pose_period_)),
                                      [this] { poseFromTf(cairn::Time{0}, false); });
    // Publishes model info and rate maps after a model swap or a parameter change (set by other threads).
    publish_pending_ = true;
    poll_timer_ = create_wall_timer(std::chrono::milliseconds(100), [this] {
      if (publish_pending_.exchange(false)) publishModel();
    });
    if (retrain_period_ > 0)
      retrain_timer_ = create_timer(std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::duration<double>(retrain_period_)), [this] {
        flushGrid(false);
        std::string why;
        if (!startTraining(why)) CAIRN_INFO(logger(), "scheduled retraining skipped: " << why);
      });
    CAIRN_INFO(logger(), (model_ ? "model " + model_source_ : std::string("no model yet")) << ", grid "
                         << (grid_ ? std::to_string(gc_.nx) + "x" + std::to_string(gc_.ny) : std::string("waiting for `map`"))
                         << ", r_s " << gc_.cell_size << " m, τ " << gc_.time_bin << " s");
  }

  ~CopaMapNode() override {
    stop_ = true;
    if (train_thread_.joinable()) train_thread_.join();
  }

 private:
  // At most one warning per key and second.
  void warn(const std::string& key, const std::string& what) {
    auto& last = warned_[key];
    const auto now = std::chrono::steady_clock::now();
    if (last.time_since_epoch().count() != 0 && now - last < std::chrono::seconds(1)) return;
    last = now;
    CAIRN_WARN(logger(), what);
  }

  std::shared_ptr<const cm::CopaMap> currentModel(std::uint32_t* version = nullptr) const {
    std::lock_guard l(model_mu_);
    if (version) *version = model_version_;
    return model_;
  }

  double toModelTime(double s) const { return (s - gc_.t_origin) / gc_.time_bin - 0.5; }

  void makeGridifier() {
    cm::GridConfig g = gc_;
    if (g.nx <= 0 && map_) {
      g.origin_x = map_->origin_x;
      g.origin_y = map_->origin_y;
      g.nx = std::max(1, static_cast<int>(std::ceil(map_->width * map_->resolution / g.cell_size)));
      g.ny = std::max(1, static_cast<int>(std::ceil(map_->height * map_->resolution / g.cell_size)));
    }
    gc_ = g;
    grid_ = std::make_unique<cm::Gridifier>(g, map_);
  }

  bool frameOk(const std::string& frame, const char* what) {
    if (frame_id_.empty() || frame == frame_id_) return true;
    warn(std::string("frame_") + what, std::string(what) + ": frame '" + frame + "' is not frame_id '" + frame_id_ + "', ignored");
    return false;
  }

  void onMap(const nav_msgs::msg::OccupancyGrid& m) {
    if (grid_) return;  // map_file, grid.nx/ny or an earlier map fixed the grid
    if (!frameOk(m.header.frame_id, "map")) return;
    const auto& info = m.info;
    if (info.width == 0 || info.height == 0 || !(info.resolution > 0) ||
        m.data.size() != static_cast<std::size_t>(info.width) * info.height) {
      warn("map_bad", "map: empty or inconsistent OccupancyGrid (" + std::to_string(m.data.size()) + " cells for " +
                          std::to_string(info.width) + "x" + std::to_string(info.height) + "), ignored");
      return;
    }
    auto om = std::make_shared<cm::OccupancyMap>();
    om->width = static_cast<int>(info.width);
    om->height = static_cast<int>(info.height);
    om->resolution = info.resolution;
    om->origin_x = info.origin.position.x;
    om->origin_y = info.origin.position.y;
    om->occupied.resize(m.data.size());
    // map_server: 100 occupied, 0 free, -1 unknown; unknown does not block the view (copa-map treats it as free).
    for (std::size_t i = 0; i < m.data.size(); ++i) om->occupied[i] = m.data[i] >= 65 ? 1 : 0;
    map_ = om;
    makeGridifier();
    CAIRN_INFO(logger(), "map received: grid " << gc_.nx << "x" << gc_.ny << " cells of " << gc_.cell_size << " m");
    publish_pending_ = true;
  }

  void onOdom(const nav_msgs::msg::Odometry& m) {
    if (!grid_) {
      warn("no_grid", "odom: no grid yet (set map_file or grid.nx/ny, or publish `map`), ignored");
      return;
    }
    if (!frameOk(m.header.frame_id, "odom")) return;
    const double t = to_seconds(m.header.stamp);
    try {
      grid_->addPose(t, m.pose.pose.position.x, m.pose.pose.position.y);
      last_pose_t_ = t;
    } catch (const std::invalid_argument& e) {
      warn("odom_bad", std::string("odom: ") + e.what() + " (t = " + std::to_string(t) + "), ignored");
    }
  }

  // Robot pose from TF at `stamp` (Time{0}: the latest available) into the gridifier. Poses older than the last
  // one are skipped (the gridifier needs non-decreasing times); a missing transform is logged (rate-limited)
  // unless `quiet` (lookups at track stamps may run ahead of the TF stream; the poll fills in).
  void poseFromTf(cairn::Time stamp, bool quiet) {
    if (!grid_ || !tf_buffer_) return;
    geometry_msgs::msg::TransformStamped tf;
    try {
      tf = tf_buffer_->lookup_msg(map_frame_, base_frame_, stamp);
    } catch (const cairn::TransformError& e) {
      if (!quiet) warn("tf_missing", "no TF " + map_frame_ + " <- " + base_frame_ + ": " + e.what());
      return;
    }
    const double t = to_seconds(tf.header.stamp);
    if (!(t > last_pose_t_)) return;
    try {
      grid_->addPose(t, tf.transform.translation.x, tf.transform.translation.y);
      last_pose_t_ = t;
    } catch (const std::invalid_argument& e) {
      warn("tf_bad", std::string("tf pose: ") + e.what() + " (t = " + std::to_string(t) + "), ignored");
    }
  }

  void onTracks(const cairn_people_msgs::msg::TrackedPersons& m) {
    if (!grid_ || !frameOk(m.header.frame_id, "people/tracks")) return;
    const double t = to_seconds(m.header.stamp);
    if (!std::isfinite(t)) return;
    if (tf_buffer_) poseFromTf(cairn::stamp_of(m.header.stamp), true);  // where the robot was when it saw them
    if (last_sample_t_ && t >= *last_sample_t_ && t - *last_sample_t_ < detection_period_) return;
    last_sample_t_ = t;
    for (const auto& p : m.tracks) {
      try {
        grid_->addDetection(t, p.position.x, p.position.y);
      } catch (const std::invalid_argument& e) {
        warn("track_bad", std::string("people/tracks: ") + e.what() + ", track ignored");
      }
    }
  }

  void flushGrid(bool all) {
    if (!grid_) return;
    const std::vector<cm::GridCell> cells = all ? grid_->finish() : grid_->flush(last_pose_t_);
    if (all) grid_ = std::make_unique<cm::Gridifier>(gc_, map_);  // finish() closes the gridifier; start a new one
    for (const auto& c : cells) data_.push_back(c);
    while (data_.size() > max_points_) data_.pop_front();
    gridded_cells_ += cells.size();
  }

  bool startTraining(std::string& why) {
    if (training_) {
      why = "a retraining is running";
      return false;
    }
    if (data_.size() < min_points_) {
      why = std::to_string(data_.size()) + " gridded cells, min_training_points is " + std::to_string(min_points_);
      return false;
    }
    if (train_thread_.joinable()) train_thread_.join();
    const auto n = static_cast<Eigen::Index>(data_.size());
    Eigen::MatrixXd X(n, 3);
    Eigen::VectorXd y(n), d(n);
    for (Eigen::Index i = 0; i < n; ++i) {
      const auto& c = data_[static_cast<std::size_t>(i)];
      X.row(i) << c.x1, c.x2, c.t;
      y(i) = c.rate;
      d(i) = c.duration;
    }
    training_ = true;
    train_thread_ = std::thread([this, X = std::move(X), y = std::move(y), d = std::move(d)] { train(X, y, d); });
    why = std::to_string(n) + " cells";
    return true;
  }

  // Background thread: a fresh model (Algorithm 4.1 + Δ-weighted k-means, §4.2.4) trained on a copy of the data
  // (§4.2.5); swapped in unless the training diverged (then the previous model stays).
  void train(const Eigen::MatrixXd& X, const Eigen::VectorXd& y, const Eigen::VectorXd& d) {
    std::string message;
    try {
      auto m = std::make_shared<cm::CopaMap>(cm::CopaMap::initialize(X, y, d, mc_));
      cm::TrainConfig tc = tc_;
      tc.progress = [this](int, double, double) {
        if (stop_) throw StopTraining{};
      };
      const cm::TrainReport rep = m->train(X, y, tc);
      if (rep.diverged) {
        message = "retraining diverged, previous model kept: " + rep.message;
      } else {
        std::lock_guard l(model_mu_);
        model_ = m;
        ++model_version_;
        model_source_ = "trained";
        training_points_ = static_cast<std::uint32_t>(X.rows());
        train_seconds_ = rep.seconds;
        final_elbo_ = rep.final_elbo;
        message = "trained on " + std::to_string(X.rows()) + " cells: " + std::to_string(rep.iterations) +
                  " iterations, " + std::to_string(rep.seconds) + " s" + (rep.converged ? ", converged" : "");
      }
    } catch (const StopTraining&) {
      training_ = false;
      return;
    } catch (const std::exception& e) {
      message = std::string("retraining failed, previous model kept: ") + e.what();
    }
    {
      std::lock_guard l(model_mu_);
      train_message_ = message;
    }
    training_ = false;
    publish_pending_ = true;
  }

  void onRetrain(const csrv::Retrain_Request& rq, csrv::Retrain_Response& rs) {
    flushGrid(rq.flush);
    std::string why;
    rs.accepted = startTraining(why);
    rs.message = why;
    rs.training_points = static_cast<std::uint32_t>(data_.size());
    CAIRN_INFO(logger(), "retrain: " << (rs.accepted ? "started on " : "refused: ") << why);
  }

  void onQueryRate(const csrv::QueryRate_Request& rq, csrv::QueryRate_Response& rs) {
    rs.rate_unit = gc_.rate_unit;
    const auto model = currentModel(&rs.model_version);
    if (!model) {
      rs.message = "no model yet (model_file empty and no retraining finished)";
      return;
    }
    if (rq.x1.size() != rq.x2.size() || rq.x1.size() != rq.t.size()) {
      rs.message = "x1, x2, t have different lengths (" + std::to_string(rq.x1.size()) + ", " +
                   std::to_string(rq.x2.size()) + ", " + std::to_string(rq.t.size()) + ")";
      warn("query_bad", "query_rate: " + rs.message);
      return;
    }
    Eigen::MatrixXd Q(static_cast<Eigen::Index>(rq.x1.size()), 3);
    for (std::size_t i = 0; i < rq.x1.size(); ++i) {
      const double t = rq.time_in_bins ? rq.t[i] : toModelTime(rq.t[i]);
      if (!std::isfinite(rq.x1[i]) || !std::isfinite(rq.x2[i]) || !std::isfinite(t)) {
        rs.message = "point " + std::to_string(i) + " is not finite";
        warn("query_bad", "query_rate: " + rs.message);
        return;
      }
      Q.row(static_cast<Eigen::Index>(i)) << rq.x1[i], rq.x2[i], t;
    }
    const cm::RatePrediction p = model->predict(Q);
    rs.mean.assign(p.mean.data(), p.mean.data() + p.mean.size());
    rs.stddev.assign(p.std.data(), p.std.data() + p.std.size());
    rs.success = true;
  }

  void onExpectedCount(const csrv::ExpectedCount_Request& rq, csrv::ExpectedCount_Response& rs) {
    const auto model = currentModel(&rs.model_version);
    if (!model) {
      rs.message = "no model yet (model_file empty and no retraining finished)";
      return;
    }
    const double t0 = rq.time_in_bins ? rq.t0 : toModelTime(rq.t0), t1 = rq.time_in_bins ? rq.t1 : toModelTime(rq.t1);
    const int spc = rq.samples_per_cell == 0 ? 1 : rq.samples_per_cell;
    // Bounded work per request: at most 1e6 prediction points.
    const double points = (rq.x1_max - rq.x1_min) / model->cellSize() * spc * (rq.x2_max - rq.x2_min) / model->cellSize() * spc *
                          (t1 - t0) / model->timeBin() * spc;
    if (!(points <= 1e6) || spc < 1 || spc > 100) {
      rs.message = "region too large or samples_per_cell out of 1..100 (" + std::to_string(points) + " points)";
      warn("count_bad", "expected_count: " + rs.message);
      return;
    }
    try {
      // The model's rates are per rate_unit seconds and its time axis is in bins of τ: the core integrates rate ×
      // bins, so τ / rate_unit makes it a count (§4.2.5 writes m_y per τ; equal when τ = rate_unit, as with ATC).
      rs.expected_count = model->expectedCount(rq.x1_min, rq.x1_max, rq.x2_min, rq.x2_max, t0, t1, spc) *
                          gc_.time_bin / gc_.rate_unit;
      rs.success = true;
    } catch (const std::invalid_argument& e) {
      rs.message = e.what();
      warn("count_bad", std::string("expected_count: ") + e.what());
    }
  }

  void publishModel() {
    std::uint32_t version = 0;
    const auto model = currentModel(&version);
    const double now_s = now().seconds();
    auto info = std::make_unique<cmsg::ModelInfo>();
    info->header.stamp = time_from_seconds(now_s);
    info->header.frame_id = frame_id_;
    info->has_model = model != nullptr;
    info->model_version = version;
    info->cell_size = model ? model->cellSize() : gc_.cell_size;
    info->time_bin = gc_.time_bin;
    info->t_origin = gc_.t_origin;
    info->rate_unit = gc_.rate_unit;
    {
      std::lock_guard l(model_mu_);
      info->source = model_source_;
      info->training_points = training_points_;
      info->train_seconds = train_seconds_;
      info->final_elbo = final_elbo_;
      info->message = train_message_;
    }
    if (model && !model->model().latents().empty())
      info->inducing_points = static_cast<std::uint32_t>(model->model().latents().front().Z.rows());
    info->gridded_cells = gridded_cells_;
    info_pub_->publish(std::move(info));
    if (!model || !grid_) return;

    // Rate map over the grid at rate_map.time (eq. 4.19 at the cell centres).
    const double s = rate_map_time_.load() != 0.0 ? rate_map_time_.load() : now_s;
    const Eigen::Index n = static_cast<Eigen::Index>(gc_.nx) * gc_.ny;
    Eigen::MatrixXd Q(n, 3);
    for (int iy = 0; iy < gc_.ny; ++iy)
      for (int ix = 0; ix < gc_.nx; ++ix)
        Q.row(static_cast<Eigen::Index>(iy) * gc_.nx + ix) << gc_.origin_x + (ix + 0.5) * gc_.cell_size,
            gc_.origin_y + (iy + 0.5) * gc_.cell_size, toModelTime(s);
    const cm::RatePrediction p = model->predict(Q);
    auto grid = [&](const Eigen::VectorXd& v) {
      auto g = std::make_unique<nav_msgs::msg::OccupancyGrid>();
      g->header.stamp = time_from_seconds(s);
      g->header.frame_id = frame_id_.empty() ? "map" : frame_id_;
      g->info.map_load_time = time_from_seconds(now_s);
      g->info.resolution = static_cast<float>(gc_.cell_size);
      g->info.width = static_cast<std::uint32_t>(gc_.nx);
      g->info.height = static_cast<std::uint32_t>(gc_.ny);
      g->info.origin.position.x = gc_.origin_x;
      g->info.origin.position.y = gc_.origin_y;
      const double vmax = rate_map_max_.load() > 0 ? rate_map_max_.load() : (v.size() ? v.maxCoeff() : 0.0);
      g->data.resize(static_cast<std::size_t>(v.size()));
      for (Eigen::Index i = 0; i < v.size(); ++i)
        g->data[static_cast<std::size_t>(i)] =
            vmax > 0 ? static_cast<int8_t>(std::lround(std::clamp(100.0 * v(i) / vmax, 0.0, 100.0))) : int8_t{0};
      return g;
    };
    mean_pub_->publish(grid(p.mean));
    if (p.std.size() == n) std_pub_->publish(grid(p.std));
  }

  // Parameters and configuration.
  std::string frame_id_, pose_source_, map_frame_, base_frame_;
  double pose_period_ = 0.1;
  cm::GridConfig gc_;
  cm::CopaMapConfig mc_;
  cm::TrainConfig tc_;
  double detection_period_ = 1.0, flush_period_ = 10.0, retrain_period_ = 0.0;
  std::size_t min_points_ = 200, max_points_ = 200000;
  std::atomic<double> rate_map_time_{0.0}, rate_map_max_{0.0};  // set by the parameter service

  // Executor-thread state (the node's callbacks share the default, mutually exclusive group).
  std::shared_ptr<const cm::OccupancyMap> map_;
  std::unique_ptr<cm::Gridifier> grid_;
  double last_pose_t_ = -1e300;
  std::optional<double> last_sample_t_;
  std::deque<cm::GridCell> data_;
  std::uint64_t gridded_cells_ = 0;
  std::map<std::string, std::chrono::steady_clock::time_point> warned_;

  // Shared with the training thread.
  mutable std::mutex model_mu_;
  std::shared_ptr<const cm::CopaMap> model_;
  std::uint32_t model_version_ = 0;
  std::string model_source_, train_message_;
  std::uint32_t training_points_ = 0;
  double train_seconds_ = 0, final_elbo_ = 0;
  std::atomic<bool> training_{false}, stop_{false}, publish_pending_{false};
  std::thread train_thread_;

  std::shared_ptr<cairn::Publisher<cmsg::ModelInfo>> info_pub_;
  std::shared_ptr<cairn::Publisher<nav_msgs::msg::OccupancyGrid>> mean_pub_, std_pub_;
  std::shared_ptr<cairn::Subscription<nav_msgs::msg::Odometry>> odom_sub_;
  std::shared_ptr<cairn::Subscription<cairn_people_msgs::msg::TrackedPersons>> tracks_sub_;
  std::shared_ptr<cairn::Subscription<nav_msgs::msg::OccupancyGrid>> map_sub_;
  std::shared_ptr<cairn::Service<csrv::QueryRate_Request, csrv::QueryRate_Response>> query_srv_;
  std::shared_ptr<cairn::Service<csrv::ExpectedCount_Request, csrv::ExpectedCount_Response>> count_srv_;
  std::shared_ptr<cairn::Service<csrv::Retrain_Request, csrv::Retrain_Response>> retrain_srv_;
  std::shared_ptr<cairn::TimerBase> flush_timer_, poll_timer_, retrain_timer_, pose_timer_;
  std::shared_ptr<cairn::TransformBuffer> tf_buffer_;
  std::unique_ptr<cairn::TransformListener> tf_listener_;
};

}  // namespace cairn_copa

CAIRN_REGISTER_COMPONENT(cairn_copa::CopaMapNode)
