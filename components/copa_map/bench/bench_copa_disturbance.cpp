// Service disturbance on ATC (Stüde 2024, §4.3.5, eq. 4.22): patrols A→B→C→D, 4 per hour over the 48 test hours
// (4 days x 12 h, 9:00-21:00), Dijkstra on an 8-connected 0.5 m grid of the ATC occupancy map with edge cost
// |edge| (1 + κ m_y / max m_y) from each model, robot at 0.5 m/s, encounters = ground-truth people within 1 m.
// Models: Occupancy (shortest path), ML, FreMEn, CoPA-Map (trained here on the reduced configuration, or --model).
//   bench_copa_disturbance [--data DIR] [--model FILE] [--max-seconds S] [--kappa K]
#include <cmath>
#include <cstdio>
#include <map>
#include <tuple>
#include <string>

#include "../tools/image_io.hpp"
#include "cairn/copa_map/baselines.hpp"
#include "cairn/copa_map/copa_map.hpp"
#include "cairn/copa_map/io.hpp"
#include "cairn/copa_map/service_disturbance.hpp"

using namespace cairn::copa_map;

int main(int argc, char** argv) {
  std::string dir = std::string(CAIRN_SOURCE_ROOT) + "/../shared/data/people/atc_copa_map", model_file;
  double max_seconds = 120, kappa = 10.0;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--data" && i + 1 < argc) dir = argv[++i];
    else if (a == "--model" && i + 1 < argc) model_file = argv[++i];
    else if (a == "--max-seconds" && i + 1 < argc) max_seconds = std::atof(argv[++i]);
    else if (a == "--kappa" && i + 1 < argc) kappa = std::atof(argv[++i]);
    else {
      std::fprintf(stderr, "usage: %s [--data DIR] [--model FILE] [--max-seconds S] [--kappa K]\n", argv[0]);
      return 2;
    }
  }
  try {
    const GridData train = readGridCsv(dir + "/grid_atc_50cm_60min_train_xy.csv");
    const GridData test = readGridCsv(dir + "/grid_atc_50cm_60min_test_xy.csv");
    const tools::MapImage map = tools::loadMapYaml(dir + "/atc_map.yaml");
    const double cell = 0.5, x0 = 3.5, y0 = -20.0, x1 = 28.0, y1 = 2.0;
    const PlanningGrid grid = makePlanningGrid(map.map, cell, x0, y0, x1, y1);
    // Ground truth per (cell, hour) from the test split (people per hour in the 0.5 m cell).
    std::map<std::tuple<int, int, int>, double> gt;
    std::map<std::pair<int, int>, double> total;
    for (Eigen::Index i = 0; i < test.X.rows(); ++i) {
      int ix, iy;
      if (!grid.cellOf(test.X.row(i).head<2>().transpose(), ix, iy)) continue;
      gt[{ix, iy, static_cast<int>(test.X(i, 2))}] = test.y[i];
      total[{ix, iy}] += test.y[i];
    }
    auto truth = [&](double x, double y, double t) {
      int ix, iy;
      if (!grid.cellOf(Eigen::Vector2d(x, y), ix, iy)) return 0.0;
      const auto it = gt.find({ix, iy, static_cast<int>(std::floor(t))});
      return it == gt.end() ? 0.0 : it->second;
    };
    // Largest 4-connected free region of the planning grid (isolated pockets between shelves are unreachable).
    std::vector<int> comp(static_cast<std::size_t>(grid.nx) * grid.ny, -1);
    int best_comp = -1;
    std::size_t best_size = 0;
    for (int start = 0, label = 0; start < grid.nx * grid.ny; ++start) {
      if (comp[static_cast<std::size_t>(start)] >= 0 || !grid.free(start % grid.nx, start / grid.nx)) continue;
      std::vector<int> stack{start};
      comp[static_cast<std::size_t>(start)] = label;
      std::size_t size = 0;
      while (!stack.empty()) {
        const int u = stack.back();
        stack.pop_back();
        ++size;
        const int ux = u % grid.nx, uy = u / grid.nx;
        const int nb[4][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}};
        for (const auto& d : nb) {
          const int vx = ux + d[0], vy = uy + d[1];
          if (!grid.free(vx, vy) || comp[static_cast<std::size_t>(vy * grid.nx + vx)] >= 0) continue;
          comp[static_cast<std::size_t>(vy * grid.nx + vx)] = label;
          stack.push_back(vy * grid.nx + vx);
        }
      }
      if (size > best_size) {
        best_size = size;
        best_comp = label;
      }
      ++label;
    }
    // A-D: cells of that region with people data nearest to the corners of the area, in patrol order.
    const Eigen::Vector2d corners[4] = {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};
    Eigen::Vector2d wp[4];
    for (int c = 0; c < 4; ++c) {
      double best = 1e300;
      for (const auto& [k, tot] : total) {
        if (!grid.free(k.first, k.second) ||
            comp[static_cast<std::size_t>(k.second * grid.nx + k.first)] != best_comp)
          continue;
        const Eigen::Vector2d p = grid.centre(k.first, k.second);
        if ((p - corners[c]).norm() < best) {
          best = (p - corners[c]).norm();
          wp[c] = p;
        }
      }
      std::printf("%c = (%.2f, %.2f)\n", 'A' + c, wp[c].x(), wp[c].y());
    }
    // Predicted rates per model on the planning grid for the 48 test hours.
    Eigen::MatrixXd Q(static_cast<Eigen::Index>(grid.nx) * grid.ny * 48, 3);
    Eigen::Index r = 0;
    for (int t = 0; t < 48; ++t)
      for (int iy = 0; iy < grid.ny; ++iy)
        for (int ix = 0; ix < grid.nx; ++ix) Q.row(r++) << grid.centre(ix, iy).transpose(), t;
    std::vector<std::pair<std::string, Eigen::VectorXd>> models;
    models.emplace_back("Occupancy", Eigen::VectorXd::Zero(Q.rows()));
    MlBaseline ml(cell);
    ml.fit(train.X, train.y);
    models.emplace_back("ML", ml.predict(Q).mean);
    FremenBaseline fr;
    fr.fit(train.X, train.y, Eigen::VectorXd());
    models.emplace_back("FreMEn", fr.predict(Q).mean);
    CopaMap cm;
    if (!model_file.empty()) {
      cm = loadModel(model_file);
    } else {
      Eigen::MatrixXd Z = readInducingCsv(dir + "/grid_atc_50cm_60min_train_z.csv");
      Eigen::MatrixXd Zr(Z.rows() / 4, 3);
      for (Eigen::Index i = 0; i < Zr.rows(); ++i) Zr.row(i) = Z.row(4 * i);
      cm = CopaMap::initialize(train.X, train.y, Eigen::VectorXd(), CopaMapConfig{}, &Zr);
      TrainConfig tc;
      tc.batch_size = 1000;
      tc.hyper_every = 4;
      tc.max_seconds = max_seconds;
      cm.train(train.X, train.y, tc);
    }
    models.emplace_back("CoPA-Map", cm.predict(Q).mean);

    const double rhos[4] = {0.25, 0.5, 0.75, 1.0};
    std::printf("kappa %.1f, %d patrols (4/h x 48 h), speed 0.5 m/s, encounter radius 1 m\n", kappa, 48 * 4);
    std::printf("| model      | E(0.25) | E(0.5) | E(0.75) | E(1.0) | vs occupancy at rho=1 |\n");
    std::printf("|------------|---------|--------|---------|--------|-----------------------|\n");
    double occ_total = 0;
    for (const auto& [name, pred] : models) {
      const double pmax = std::max(pred.maxCoeff(), 1e-12);
      std::vector<double> costs, enc;
      for (int t = 0; t < 48; ++t) {
        const Eigen::Index base = static_cast<Eigen::Index>(t) * grid.nx * grid.ny;
        auto extra = [&](int ix, int iy) {
          return kappa * pred[base + static_cast<Eigen::Index>(iy) * grid.nx + ix] / pmax;
        };
        for (int q = 0; q < 4; ++q) {
          double cost = 0, e = 0, tt = t + q / 4.0;
          for (int leg = 0; leg < 3; ++leg) {
            const PlannedPath p = planPath(grid, wp[leg], wp[leg + 1], extra);
            if (!p.found) throw std::runtime_error("no path between patrol points");
            cost += p.cost;
            e += pathEncounters(p.points, tt, 0.5, 3600.0, 1.0, cell, truth);
            tt += p.length / 0.5 / 3600.0;
          }
          costs.push_back(cost);
          enc.push_back(e);
        }
      }
      const double e1 = serviceDisturbance(costs, enc, 1.0);
      if (name == "Occupancy") occ_total = e1;
      std::printf("| %-10s | %7.1f | %6.1f | %7.1f | %6.1f | %+20.1f%% |\n", name.c_str(),
                  serviceDisturbance(costs, enc, rhos[0]), serviceDisturbance(costs, enc, rhos[1]),
                  serviceDisturbance(costs, enc, rhos[2]), e1, 100.0 * (e1 - occ_total) / occ_total);
      std::fflush(stdout);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "cairn: %s\n", e.what());
    return 2;
  }
  return 0;
}
