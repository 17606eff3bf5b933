// `cairn slam run` (offline SLAM on a CARMEN log) and `cairn slam eval` (Kümmerle et al. 2009 relations metric).
#include <cmath>
#include <exception>
#include <iostream>
#include <string>
#include <vector>

#include "cairn/graph_slam/relations.hpp"
#include "cairn/sim/world.hpp"  // InputError
#include "cli_util.hpp"
#include "verbs.hpp"

namespace gs = cairn::graph_slam;
using cairn::slam_cli::JsonObject;

namespace {

constexpr double kRadToDeg = 180.0 / 3.14159265358979323846;

int fail(const std::string& what) {
  std::cerr << "cairn: slam: " << what << "\n";
  return 2;
}

}  // namespace

int slamEvalVerb(const std::vector<std::string>& args) {
  std::string relations_path, poses_path;
  bool json = false;
  bool allow_missing = false;
  gs::RelationsOptions opt;
  try {
    for (std::size_t i = 0; i < args.size(); ++i) {
      const std::string& a = args[i];
      auto value = [&]() -> const std::string& {
        if (i + 1 >= args.size()) throw std::invalid_argument(a + " needs a value");
        return args[++i];
      };
      if (a == "--relations") relations_path = value();
      else if (a == "--poses") poses_path = value();
      else if (a == "--json") json = true;
      else if (a == "--allow-missing") allow_missing = true;
      else if (a == "--stamp-tolerance") opt.stamp_tolerance = cairn::slam_cli::parseDouble(value(), "--stamp-tolerance");
      else throw std::invalid_argument("eval: unknown option '" + a + "'");
    }
    if (relations_path.empty() || poses_path.empty()) throw std::invalid_argument("eval needs --relations and --poses");
  } catch (const std::exception& e) {
    return fail(e.what());
  }
  try {
    const auto relations = gs::readRelations(relations_path);
    const auto poses = gs::readPoses(poses_path);
    const gs::RelationsResult r = gs::evaluateRelations(relations, poses, opt);
    if (r.missing > 0 && !allow_missing)
      return fail(relations_path + ":" + std::to_string(r.first_missing_line) + ": " + std::to_string(r.missing) +
                  " of " + std::to_string(r.relations) + " relations have a stamp without a pose in " + poses_path +
                  " (--allow-missing skips them)");
    if (r.used == 0) return fail(relations_path + ": no relation could be evaluated");
    if (json) {
      std::cout << JsonObject()
                       .integer("relations", static_cast<long long>(r.relations))
                       .integer("used", static_cast<long long>(r.used))
                       .integer("missing", static_cast<long long>(r.missing))
                       .num("trans_mean_m", r.trans_mean)
                       .num("trans_std_m", r.trans_std)
                       .num("trans_max_m", r.trans_max)
                       .num("rot_mean_deg", r.rot_mean * kRadToDeg)
                       .num("rot_std_deg", r.rot_std * kRadToDeg)
                       .num("rot_max_deg", r.rot_max * kRadToDeg)
                       .text()
                << "\n";
    } else {
      std::printf("relations: %zu used of %zu\n", r.used, r.relations);
      std::printf("translational error: %.4f +- %.4f m (max %.4f)\n", r.trans_mean, r.trans_std, r.trans_max);
      std::printf("rotational error:    %.3f +- %.3f deg (max %.3f)\n", r.rot_mean * kRadToDeg,
                  r.rot_std * kRadToDeg, r.rot_max * kRadToDeg);
    }
    return 0;
  } catch (const cairn::sim::InputError& e) {
    return fail(e.what());
  } catch (const std::exception& e) {
    return fail(e.what());
  }
}

int slamRunVerb(const std::vector<std::string>&) {
  return fail("run: not available yet in this build");
}
