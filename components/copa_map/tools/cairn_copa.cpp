// cairn-copa: CoPA-Map command-line tool (`cairn copa <verb> …`).
//   train   --train <csv> [--inducing <csv>] [--config <file>] -o <model>
//   eval    --model <file|copa|ml|fremen|gp-hom> --train <csv> --test <csv> [--config <file>] [--json]
//   predict --model <file> --points <csv with x1,x2,t> -o <csv>
//   render  --model <file> --map <map.yaml> --times t1,t2,… [--bbox x0,y0,x1,y1] -o <prefix>
// Bad input: one line `cairn: <file>:<line>: <what>` on stderr and exit code 2. A diverged training writes the
// last good model and exits with code 3.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "cairn/copa_map/baselines.hpp"
#include "cairn/copa_map/copa_map.hpp"
#include "cairn/copa_map/io.hpp"
#include "cairn/copa_map/metrics.hpp"
#include "image_io.hpp"

using namespace cairn::copa_map;

namespace {

struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

const char* kUsage =
    "usage: cairn copa <verb> [options]\n"
    "  train   --train <csv> [--inducing <csv>] [--config <file>] -o <model>\n"
    "  eval    --model <file|copa|ml|fremen|gp-hom> --train <csv> --test <csv> [--inducing <csv>] [--config <file>] "
    "[--json]\n"
    "  predict --model <file> --points <csv with x1,x2,t> -o <csv>\n"
    "  render  --model <file> --map <map.yaml> --times t1,t2,... [--bbox x0,y0,x1,y1] -o <prefix>\n";

std::map<std::string, std::string> parseArgs(int argc, char** argv, int first) {
  std::map<std::string, std::string> a;
  for (int i = first; i < argc; ++i) {
    std::string k = argv[i];
    if (k == "--json") {
      a.insert_or_assign(std::string("json"), std::string("1"));
      continue;
    }
    if (k.rfind("-", 0) != 0 || i + 1 >= argc) {
      std::string msg = "bad or incomplete option '";
      msg.append(k).append("'");
      throw UsageError(msg);
    }
    if (k == "-o") {
      k = std::string("out");
    } else {
      k.erase(0, k.find_first_not_of('-'));
    }
    a[k] = argv[++i];
  }
  return a;
}

std::string need(const std::map<std::string, std::string>& a, const std::string& k) {
  const auto it = a.find(k);
  if (it == a.end()) {
    std::string msg = "missing option ";
    msg.append(k == "out" ? "-o" : "--");
    if (k != "out") msg.append(k);
    throw UsageError(msg);
  }
  return it->second;
}

double now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

// Config file: `key = value` lines, '#' comments. Unknown keys are errors (with file and line).
void applyConfig(const std::string& path, CopaMapConfig& mc, TrainConfig& tc) {
  std::ifstream in(path);
  if (!in) throw InputError(path, 0, "cannot open config file");
  std::string line;
  long ln = 0;
  while (std::getline(in, line)) {
    ++ln;
    const auto hash = line.find('#');
    if (hash != std::string::npos) line = line.substr(0, hash);
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    const auto eq = line.find('=');
    if (eq == std::string::npos) throw InputError(path, ln, "expected 'key = value'");
    const std::string key = trim(line.substr(0, eq)), val = trim(line.substr(eq + 1));
    if (key == "step_decay") {  // the only key with a word value
      try {
        tc.step_decay = stepDecayFromName(val);
      } catch (const std::invalid_argument& e) {
        throw InputError(path, ln, e.what());
      }
      continue;
    }
    char* end = nullptr;
    const double v = std::strtod(val.c_str(), &end);
    if (end == val.c_str() || !std::isfinite(v)) throw InputError(path, ln, "value of '" + key + "' is not a number");
    if (key == "batch_size") tc.batch_size = static_cast<int>(v);
    else if (key == "max_iterations") tc.max_iterations = static_cast<int>(v);
    else if (key == "max_seconds") tc.max_seconds = v;
    else if (key == "natgrad_gamma") tc.natgrad_gamma_start = tc.natgrad_gamma_end = v;
    else if (key == "natgrad_gamma_start") tc.natgrad_gamma_start = v;
    else if (key == "natgrad_gamma_end") tc.natgrad_gamma_end = v;
    else if (key == "adam_lr_start") tc.adam_lr_start = v;
    else if (key == "adam_lr_end") tc.adam_lr_end = v;
    else if (key == "decay_steps") tc.decay_steps = static_cast<int>(v);
    else if (key == "hyper_every") tc.hyper_every = static_cast<int>(v);
    else if (key == "hyper_warmup") tc.hyper_warmup = static_cast<int>(v);
    else if (key == "train_hyper") tc.train_hyper = v != 0;
    else if (key == "train_inducing") tc.train_inducing = v != 0;
    else if (key == "inducing_lr") tc.inducing_lr = v;
    else if (key == "tolerance") tc.tolerance = v;
    else if (key == "elbo_floor") tc.elbo_floor = v;
    else if (key == "patience") tc.patience = static_cast<int>(v);
    else if (key == "decay_tau") tc.decay_tau = v;
    else if (key == "plateau_factor") tc.plateau_factor = v;
    else if (key == "average_iterates") tc.average_iterates = v != 0;
    else if (key == "mixed_precision") tc.mixed_precision = v != 0;
    else if (key == "seed") tc.seed = mc.seed = mc.period_init.seed = static_cast<std::uint64_t>(v);
    else if (key == "alpha_ind") mc.alpha_ind = v;
    else if (key == "g_inducing_ratio") mc.g_inducing_ratio = v;
    else if (key == "spatial_lengthscale") mc.spatial_lengthscale = v;
    else if (key == "periodic_lengthscale") mc.periodic_lengthscale = v;
    else if (key == "jitter") mc.jitter = v;
    else if (key == "gh_order") mc.gh_order = static_cast<int>(v);
    else if (key == "cell_size") mc.cell_size = v;
    else if (key == "time_bin") mc.time_bin = v;
    else if (key == "init_cell_size") mc.period_init.cell_size = v;
    else if (key == "period_min") mc.period_init.period_min = v;
    else if (key == "period_max") mc.period_init.period_max = v;
    else if (key == "period_step") mc.period_init.period_step = v;
    else if (key == "num_series") mc.period_init.num_series = static_cast<int>(v);
    else if (key == "max_periods") mc.period_init.max_periods = static_cast<int>(v);
    else if (key == "max_variance") mc.period_init.max_variance = v;
    else throw InputError(path, ln, "unknown key '" + key + "'");
  }
}

void progressBar(int it, double elbo, double secs, const TrainConfig& tc) {
  static double last = -1.0;
  if (secs - last < 0.5 && it + 1 < tc.max_iterations) return;  // at most two updates per second
  last = secs;
  const double frac_it = static_cast<double>(it + 1) / tc.max_iterations;
  const double frac_t = secs / tc.max_seconds;
  const double frac = std::min(1.0, std::max(frac_it, frac_t));
  const double eta = frac > 0 ? secs / frac - secs : 0;
  const int w = 30, filled = static_cast<int>(frac * w);
  std::fprintf(stderr, "\r[%s%s] it %d  ELBO/n %.4f  %.0f s  ETA <= %.0f s   ", std::string(filled, '#').c_str(),
               std::string(w - filled, '.').c_str(), it + 1, elbo, secs, eta);
}

int cmdTrain(const std::map<std::string, std::string>& a) {
  CopaMapConfig mc;
  TrainConfig tc;
  if (a.count("config")) applyConfig(a.at("config"), mc, tc);
  const std::string out = need(a, "out");
  const GridData d = readGridCsv(need(a, "train"));
  Eigen::MatrixXd Z;
  if (a.count("inducing")) Z = readInducingCsv(a.at("inducing"));
  PeriodInitResult init;
  CopaMap cm = CopaMap::initialize(d.X, d.y, d.durations, mc, Z.size() ? &Z : nullptr, &init);
  std::fprintf(stderr, "cairn copa: %ld points, m_f=%ld, m_g=%ld, periods:", static_cast<long>(d.X.rows()),
               static_cast<long>(cm.model().latents()[0].Z.rows()), static_cast<long>(cm.model().latents()[1].Z.rows()));
  for (std::size_t i = 0; i < init.periods.size(); ++i)
    std::fprintf(stderr, " %.2f (σ² %.2f)", init.periods[i], init.variances[i]);
  std::fprintf(stderr, "\n");
  tc.progress = [&tc](int it, double elbo, double s) { progressBar(it, elbo, s, tc); };
  const TrainReport rep = cm.train(d.X, d.y, tc);
  std::fprintf(stderr, "\ncairn copa: %s after %d iterations (%.1f s)\n", rep.message.c_str(), rep.iterations,
               rep.seconds);
  saveModel(cm, out);
  if (rep.diverged) {
    std::fprintf(stderr, "cairn: %s: training diverged: %s\n", out.c_str(), rep.message.c_str());
    return 3;
  }
  return 0;
}

int cmdPredict(const std::map<std::string, std::string>& a) {
  const CopaMap cm = loadModel(need(a, "model"));
  const GridData pts = readGridCsv(need(a, "points"), false);
  const std::string out = need(a, "out");
  const RatePrediction p = cm.predict(pts.X);
  std::ofstream f(out);
  if (!f) throw InputError(out, 0, "cannot write output");
  f << "x1,x2,t,mean,std\n";
  char buf[160];
  for (Eigen::Index i = 0; i < pts.X.rows(); ++i) {
    std::snprintf(buf, sizeof buf, "%.10g,%.10g,%.10g,%.10g,%.10g\n", pts.X(i, 0), pts.X(i, 1), pts.X(i, 2),
                  p.mean[i], p.std[i]);
    f << buf;
  }
  return 0;
}

int cmdEval(const std::map<std::string, std::string>& a) {
  const std::string which = need(a, "model");
  CopaMapConfig mc;
  TrainConfig tc;
  if (a.count("config")) applyConfig(a.at("config"), mc, tc);
  const GridData tr = readGridCsv(need(a, "train"));
  const GridData te = readGridCsv(need(a, "test"));
  Eigen::MatrixXd Z;
  if (a.count("inducing")) Z = readInducingCsv(a.at("inducing"));
  RatePrediction p;
  Eigen::VectorXd logd;
  double t_train = 0, t_pred = 0;
  double t0 = now();
  std::string name = which;
  if (which == "ml") {
    MlBaseline m(mc.cell_size);
    m.fit(tr.X, tr.y);
    t_train = now() - t0;
    t0 = now();
    p = m.predict(te.X);
  } else if (which == "fremen") {
    FremenBaseline m(FremenConfig{mc.cell_size});
    m.fit(tr.X, tr.y, tr.durations);
    t_train = now() - t0;
    t0 = now();
    p = m.predict(te.X);
  } else if (which == "gp-hom") {
    GpHomBaseline m;
    m.initialize(tr.X, tr.y, tr.durations, mc, Z.size() ? &Z : nullptr);
    m.train(tr.X, tr.y, tc);
    t_train = now() - t0;
    t0 = now();
    p = m.predict(te.X);
    logd = m.logPredictiveDensity(te.X, te.y);
  } else {
    CopaMap cm;
    if (which == "copa") {
      cm = CopaMap::initialize(tr.X, tr.y, tr.durations, mc, Z.size() ? &Z : nullptr);
      tc.progress = [&tc](int it, double elbo, double s) { progressBar(it, elbo, s, tc); };
      cm.train(tr.X, tr.y, tc);
      std::fprintf(stderr, "\n");
    } else {
      cm = loadModel(which);  // a trained model file: no training time
      name = "copa-map-file";
    }
    t_train = now() - t0;
    t0 = now();
    p = cm.predict(te.X);
    logd = cm.logPredictiveDensity(te.X, te.y);
  }
  t_pred = now() - t0;
  const double e = nrmse(p.mean, te.y), c2 = chiSquareDistance(p.mean, te.y);
  const bool has_var = logd.size() > 0;
  if (a.count("json")) {
    std::printf("{\"model\": \"%s\", \"n_train\": %ld, \"n_test\": %ld, \"nrmse\": %.6g, \"chi2\": %.6g, ", name.c_str(),
                static_cast<long>(tr.X.rows()), static_cast<long>(te.X.rows()), e, c2);
    if (has_var)
      std::printf("\"nlpd\": %.6g, \"coverage95\": %.6g, ", nlpd(logd), coverage95(p.mean, p.std, te.y));
    else
      std::printf("\"nlpd\": null, \"coverage95\": null, ");
    std::printf("\"train_seconds\": %.3f, \"predict_seconds\": %.3f}\n", t_train, t_pred);
  } else {
    std::printf("model %s: NRMSE %.4f  chi2 %.1f", name.c_str(), e, c2);
    if (has_var) std::printf("  NLPD %.4f  cov95 %.3f", nlpd(logd), coverage95(p.mean, p.std, te.y));
    std::printf("  train %.2f s  predict %.2f s\n", t_train, t_pred);
  }
  return 0;
}

std::vector<double> parseList(const std::string& s, const std::string& what) {
  std::vector<double> v;
  std::stringstream ss(s);
  std::string tok;
  while (std::getline(ss, tok, ',')) {
    char* end = nullptr;
    const double d = std::strtod(tok.c_str(), &end);
    if (end == tok.c_str() || *end != '\0' || !std::isfinite(d)) throw UsageError("bad number '" + tok + "' in " + what);
    v.push_back(d);
  }
  return v;
}

int cmdRender(const std::map<std::string, std::string>& a) {
  const CopaMap cm = loadModel(need(a, "model"));
  const tools::MapImage map = tools::loadMapYaml(need(a, "map"));
  const std::vector<double> times = parseList(need(a, "times"), "--times");
  const std::string prefix = need(a, "out");
  double x0, y0, x1, y1;
  if (a.count("bbox")) {
    const auto b = parseList(a.at("bbox"), "--bbox");
    if (b.size() != 4 || !(b[2] > b[0]) || !(b[3] > b[1])) throw UsageError("--bbox needs x0,y0,x1,y1 with x1>x0, y1>y0");
    x0 = b[0], y0 = b[1], x1 = b[2], y1 = b[3];
  } else {  // extent of the inducing points plus a margin
    const Eigen::MatrixXd& Z = cm.model().latents()[0].Z;
    x0 = Z.col(0).minCoeff() - 2;
    x1 = Z.col(0).maxCoeff() + 2;
    y0 = Z.col(1).minCoeff() - 2;
    y1 = Z.col(1).maxCoeff() + 2;
  }
  const double cs = cm.cellSize();
  const int nx = static_cast<int>(std::ceil((x1 - x0) / cs)), ny = static_cast<int>(std::ceil((y1 - y0) / cs));
  for (double t : times) {
    Eigen::MatrixXd Q(static_cast<Eigen::Index>(nx) * ny, 3);
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) Q.row(static_cast<Eigen::Index>(j) * nx + i) << x0 + (i + 0.5) * cs, y0 + (j + 0.5) * cs, t;
    const RatePrediction p = cm.predict(Q);
    Eigen::MatrixXd M(ny, nx), S(ny, nx);
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        M(j, i) = p.mean[static_cast<Eigen::Index>(j) * nx + i];
        S(j, i) = p.std[static_cast<Eigen::Index>(j) * nx + i];
      }
    char tag[64];
    std::snprintf(tag, sizeof tag, "_t%g", t);
    tools::writeHeatmapPng(prefix + tag + "_mean.png", map, M, x0, y0, cs, M.maxCoeff());
    tools::writeHeatmapPng(prefix + tag + "_std.png", map, S, x0, y0, cs, S.maxCoeff());
    std::printf("%s%s_mean.png %s%s_std.png (max mean %.3g, max std %.3g)\n", prefix.c_str(), tag, prefix.c_str(), tag,
                M.maxCoeff(), S.maxCoeff());
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || std::string(argv[1]) == "--help" || std::string(argv[1]) == "-h") {
    std::fputs(kUsage, argc < 2 ? stderr : stdout);
    return argc < 2 ? 2 : 0;
  }
  const std::string verb = argv[1];
  try {
    const auto a = parseArgs(argc, argv, 2);
    if (verb == "train") return cmdTrain(a);
    if (verb == "eval") return cmdEval(a);
    if (verb == "predict") return cmdPredict(a);
    if (verb == "render") return cmdRender(a);
    throw UsageError("unknown verb '" + verb + "'");
  } catch (const UsageError& e) {
    std::fprintf(stderr, "cairn: copa: %s\n%s", e.what(), kUsage);
    return 2;
  } catch (const InputError& e) {
    std::fprintf(stderr, "cairn: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "cairn: copa %s: %s\n", verb.c_str(), e.what());
    return 2;
  }
}
