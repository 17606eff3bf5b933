// cairn-slam: command-line front end of the pose-graph optimizer (`cairn slam <verb> ...`).
//   cairn-slam optimize <in.g2o> [-o out.g2o] [--solver lm|gn|dogleg] [--robust huber:1.0]
//              [--init guess|odometry|chordal] [--max-iters N] [--json]
//              [--fix-information reject|clamp] [--skip-unknown-tags] [--threads N] [--certify]
// --certify: SE-Sync's verification certificate of the result (certificate.hpp); with --json an additional
// "certificate" object after the documented keys.
// Bad input: one line `cairn: <file>:<line>: <what>` on stderr, exit code 2.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <iostream>
#include <string>
#include <string_view>
#include <vector>

#include "cairn/graph_slam/certificate.hpp"
#include "cairn/graph_slam/g2o_io.hpp"
#include "cairn/graph_slam/gnc.hpp"
#include "cairn/graph_slam/initialization.hpp"
#include "cairn/graph_slam/optimizer.hpp"
#include "cli_util.hpp"
#include "verbs.hpp"

namespace gs = cairn::graph_slam;
using cairn::slam_cli::jsonNumber;
using cairn::slam_cli::parseInt;

namespace {

constexpr const char* kUsage =
    "usage: cairn slam optimize <in.g2o> [-o out.g2o] [--solver lm|gn|dogleg] [--robust KERNEL:PARAM]\n"
    "                           [--init guess|odometry|chordal] [--max-iters N] [--json] [--certify]\n"
    "                           [--fix-information reject|clamp] [--skip-unknown-tags] [--threads N]\n"
    "  KERNEL: none, huber, cauchy, gm (Geman-McClure), dcs (dynamic covariance scaling);\n"
    "          gnc[:C2] runs graduated non-convexity over the loop closures instead\n"
    "       cairn slam run --carmen <log> --out <dir> [--config f.yaml] [--set key=value]... [--load state.cslam]\n"
    "                      [--limit N] [--laser-mount auto|zero] [--skip-malformed] [--quiet] [--json]\n"
    "                      offline SLAM: poses.txt, graph.g2o, map.pgm/.yaml/.png, state.cslam, summary.json\n"
    "       cairn slam eval --poses <poses.txt> [--relations <file>] [--odometry-baseline <raw log>]\n"
    "                       [--corrected <corrected log> --carmen <raw log>] [--json] [--allow-missing]\n"
    "                       [--stamp-tolerance S]   Kuemmerle et al. 2009 relative-pose error, corrected-log ATE\n"
    "       cairn slam params [--markdown]          the SLAM parameters (--config keys = component params)\n"
    "       cairn slam train-verifier --logs a.log.gz[,b...] --out model.yml.gz [--weak-count 50] [--seed N]\n"
    "                                 [--target-fpr 0.01] [--max-pairs 5000] [--json]\n"
    "       cairn slam eval-verifier --model model.yml.gz --logs c.log.gz[,d...] [--threshold T] [--seed N]\n"
    "                                [--max-pairs 5000] [--max-negatives 20000] [--json]\n"
    "       cairn slam <verb> --help   this text\n";

int usageError(const std::string& what) {
  std::cerr << "cairn: slam: " << what << "\n" << kUsage;
  return 2;
}

int optimizeVerb(const std::vector<std::string>& args) {
  std::string in, out;
  gs::OptimizerOptions opt;
  gs::RobustKernel kernel;
  bool gnc = false;
  gs::GncOptions gnc_opt;
  gs::Initialization init = gs::Initialization::kGuess;
  gs::G2oReadOptions read_opt;
  bool json = false;
  bool certify = false;
  try {
    for (std::size_t k = 0; k < args.size(); ++k) {
      const std::string& a = args[k];
      auto value = [&]() -> const std::string& {
        if (k + 1 >= args.size()) throw std::invalid_argument(a + " needs a value");
        return args[++k];
      };
      if (a == "-o" || a == "--output") {
        out = value();
      } else if (a == "--solver") {
        opt.algorithm = gs::parseAlgorithm(value());
      } else if (a == "--robust") {
        const std::string& v = value();
        if (v == "gnc" || v.rfind("gnc:", 0) == 0) {
          gnc = true;
          if (v.size() > 4) {
            const auto t = cairn::strict_number::parse_finite(v.substr(4));
            if (!t || !(*t > 0.0))
              throw std::invalid_argument("gnc threshold must be a positive number, got '" + v.substr(4) + "'");
            gnc_opt.inlier_threshold = *t;
          }
        } else {
          kernel = gs::RobustKernel::parse(v);
        }
      } else if (a == "--init") {
        init = gs::parseInitialization(value());
      } else if (a == "--max-iters") {
        opt.max_iterations = parseInt(value(), "--max-iters");
        if (opt.max_iterations < 0) throw std::invalid_argument("--max-iters must be >= 0");
      } else if (a == "--threads") {
        opt.num_threads = parseInt(value(), "--threads");
        if (opt.num_threads < 1) throw std::invalid_argument("--threads must be >= 1");
      } else if (a == "--json") {
        json = true;
      } else if (a == "--certify") {
        certify = true;
      } else if (a == "--fix-information") {
        const std::string& v = value();
        if (v == "clamp") {
          read_opt.information_fix = gs::G2oReadOptions::InformationFix::kClamp;
        } else if (v == "reject") {
          read_opt.information_fix = gs::G2oReadOptions::InformationFix::kReject;
        } else {
          throw std::invalid_argument("--fix-information expects reject or clamp, got '" + v + "'");
        }
      } else if (a == "--skip-unknown-tags") {
        read_opt.skip_unknown_tags = true;
      } else if (a == "-h" || a == "--help") {
        std::cout << kUsage;
        return 0;
      } else if (!a.empty() && a[0] == '-') {
        throw std::invalid_argument("unknown option " + a);
      } else if (in.empty()) {
        in = a;
      } else {
        throw std::invalid_argument("unexpected argument " + a);
      }
    }
  } catch (const std::invalid_argument& e) {
    return usageError(e.what());
  }
  if (in.empty()) return usageError("optimize needs an input file");

  gs::G2oReadReport report;
  gs::PoseGraph graph;
  try {
    graph = gs::readG2o(in, read_opt, &report);
  } catch (const gs::G2oError& e) {
    std::cerr << "cairn: " << e.what() << "\n";
    return 2;
  }
  if (graph.variables().empty()) {
    std::cerr << "cairn: " << in << ":0: no vertices (empty graph)\n";
    return 2;
  }
  for (const std::string& w : report.warnings) std::cerr << "cairn: warning: " << w << "\n";
  if (report.clamped_information > 0) {
    std::cerr << "cairn: warning: " << in << ": projected " << report.clamped_information
              << " information matrices onto the nearest positive semidefinite matrix\n";
  }
  if (kernel.active()) graph.setRobustKernelAll(kernel);

  const auto t0 = std::chrono::steady_clock::now();
  gs::OptimizerSummary sum;
  try {
    gs::initialize(graph, init);
    gs::Optimizer optimizer(opt);
    if (gnc) {
      const double before = graph.chi2();
      const gs::GncSummary g = gs::optimizeGnc(graph, optimizer, gnc_opt);
      sum = g.last;
      sum.initial_chi2 = before;
      sum.iterations = g.inner_iterations;
      if (!json) {
        std::cout << "gnc:          " << g.outer_iterations << " outer iterations, " << g.rejected
                  << " loop closures rejected (weight < 0.5)\n";
      }
    } else {
      sum = optimizer.optimize(graph);
    }
  } catch (const std::exception& e) {
    std::cerr << "cairn: " << in << ":0: " << e.what() << "\n";
    return 2;
  }
  if (!std::isfinite(sum.final_chi2)) {  // e.g. --init produced values whose cost overflows
    std::cerr << "cairn: " << in << ":0: chi2 is not finite after optimization (" << sum.termination << ")\n";
    return 2;
  }
  const double time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const double initial_chi2 = sum.initial_chi2;  // after --init, i.e. at the optimizer's starting point

  if (!out.empty()) {
    try {
      gs::writeG2o(graph, out);
    } catch (const std::exception& e) {
      std::cerr << "cairn: " << out << ":0: " << e.what() << "\n";
      return 2;
    }
  }
  gs::CertificateResult cert;
  if (certify) {
    try {
      cert = gs::certifyGlobalOptimum(graph);
    } catch (const std::exception& e) {
      std::cerr << "cairn: " << in << ":0: --certify: " << e.what() << "\n";
      return 2;
    }
  }
  if (json) {
    std::cout << "{\"vertices\":" << sum.variables << ",\"edges\":" << sum.factors
              << ",\"initial_chi2\":" << jsonNumber(initial_chi2) << ",\"final_chi2\":" << jsonNumber(sum.final_chi2)
              << ",\"iterations\":" << sum.iterations << ",\"time_s\":" << jsonNumber(time_s)
              << ",\"converged\":" << (sum.converged ? "true" : "false");
    if (certify) {
      std::cout << ",\"certificate\":{\"certified\":" << (cert.certified ? "true" : "false")
                << ",\"sesync_objective\":" << jsonNumber(cert.objective_input)
                << ",\"refined_objective\":" << jsonNumber(cert.objective)
                << ",\"dual_bound\":" << jsonNumber(cert.dual_bound) << ",\"lambda_min\":" << jsonNumber(cert.lambda_min)
                << ",\"eta\":" << jsonNumber(cert.eta) << ",\"refine_iterations\":" << cert.refine_iterations
                << ",\"refine_converged\":" << (cert.refine_converged ? "true" : "false")
                << ",\"time_s\":" << jsonNumber(cert.time_s) << "}";
    }
    std::cout << "}\n";
  } else {
    std::cout << "input:        " << in << " (" << sum.variables << " vertices, " << sum.factors << " edges)\n"
              << "solver:       "
              << (opt.algorithm == gs::Algorithm::kLevenbergMarquardt ? "lm"
                  : opt.algorithm == gs::Algorithm::kGaussNewton      ? "gn"
                                                                      : "dogleg")
              << ", robust " << (gnc ? std::string("gnc (Geman-McClure, loop closures)") : kernel.toString()) << "\n"
              << "initial chi2: " << jsonNumber(sum.initial_chi2) << "\n"
              << "final chi2:   " << jsonNumber(sum.final_chi2) << "\n";
    if (kernel.active()) std::cout << "final cost:   " << jsonNumber(sum.final_cost) << " (robust)\n";
    std::cout << "iterations:   " << sum.iterations << " (" << sum.accepted_steps << " accepted)\n"
              << "converged:    " << (sum.converged ? "yes" : "no") << " (" << sum.termination << ")\n"
              << "time:         " << time_s << " s\n";
    if (sum.gauge) std::cout << "gauge:        vertex " << *sum.gauge << " held fixed\n";
    if (!out.empty()) std::cout << "output:       " << out << "\n";
    if (certify) {
      std::cout << "certified:    " << (cert.certified ? "yes" : "no") << " (SE-Sync certificate: f "
                << jsonNumber(cert.objective_input) << " -> " << jsonNumber(cert.objective) << " after "
                << cert.refine_iterations << " LM solves" << (cert.refine_converged ? "" : ", not converged")
                << ", lambda_min " << jsonNumber(cert.lambda_min) << ", eta " << jsonNumber(cert.eta) << ")\n";
    }
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  if (args.empty() || args[0] == "-h" || args[0] == "--help") {
    std::cout << kUsage;
    return args.empty() ? 2 : 0;
  }
  const std::string verb = args[0];
  args.erase(args.begin());
  const bool known = verb == "optimize" || verb == "run" || verb == "eval" || verb == "params" ||
                     verb == "train-verifier" || verb == "eval-verifier";
  if (known && !args.empty() && (args[0] == "-h" || args[0] == "--help")) {
    std::cout << kUsage;
    return 0;
  }
  if (verb == "optimize") return optimizeVerb(args);
  if (verb == "run") return slamRunVerb(args);
  if (verb == "eval") return slamEvalVerb(args);
  if (verb == "params") return slamParamsVerb(args);
  if (verb == "train-verifier") return trainVerifierVerb(args);
  if (verb == "eval-verifier") return evalVerifierVerb(args);
  return usageError("unknown verb '" + verb + "'");
}
