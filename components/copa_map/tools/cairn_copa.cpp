// cairn-copa: CoPA-Map command-line tool (`cairn copa <verb> …`).
//   train   --train <csv> [--inducing <csv>] [--config <file>] -o <model>
//   eval    --model <file|copa|ml|fremen|gp-hom> --train <csv> --test <csv> [--config <file>] [--json]
//   predict --model <file> --points <csv with x1,x2,t> -o <csv>
//   render  --model <file> --map <map.yaml> --times t1,t2,… [--bbox x0,y0,x1,y1] -o <prefix>
// Bad input: one line `cairn: <file>:<line>: <what>` on stderr and exit code 2. A diverged training writes the
// last good model and exits with code 3.
#include <algorithm>
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
#include "cairn/strict_number.hpp"
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

// Options of `verb` (names without dashes, "out" for -o); anything else, a repeated option or a missing value
// is a usage error naming the option.
std::map<std::string, std::string> parseArgs(int argc, char** argv, int first,
                                             const std::vector<std::string>& allowed) {
  std::map<std::string, std::string> a;
  for (int i = first; i < argc; ++i) {
    const std::string arg = argv[i];
    std::string k = arg == "-o"               ? std::string("out")
                    : arg.rfind("--", 0) == 0 ? arg.substr(2)
                                              : std::string();
    if (k.empty() || std::find(allowed.begin(), allowed.end(), k) == allowed.end())
      throw UsageError("unknown option '" + arg + "'");
    if (a.count(k)) throw UsageError("option '" + arg + "' given twice");
    if (k == "json") {
      a.emplace(k, "1");
      continue;
    }
    if (i + 1 >= argc) throw UsageError("option '" + arg + "' needs a value");
    a.emplace(k, argv[++i]);
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

// Config file keys: where each value goes and its range ([lo, hi], or (lo, hi] when lo_open). Integer keys
// take whole numbers only, flags 0 or 1.
struct ConfigKey {
  const char* name;
  enum Kind { kReal, kInt, kFlag } kind;
  double lo, hi;
  bool lo_open;
  void (*set)(double v, CopaMapConfig& mc, TrainConfig& tc);
};

constexpr double kIntMax = 2147483647.0;
constexpr double kSeedMax = 9007199254740992.0;  // 2^53: every integer up to here is exact in a double

const ConfigKey kConfigKeys[] = {
    {"batch_size", ConfigKey::kInt, 1, kIntMax, false,
     [](double v, CopaMapConfig&, TrainConfig& t) { t.batch_size = static_cast<int>(v); }},
    {"max_iterations", ConfigKey::kInt, 1, kIntMax, false,
     [](double v, CopaMapConfig&, TrainConfig& t) { t.max_iterations = static_cast<int>(v); }},
    {"max_seconds", ConfigKey::kReal, 0, 1e9, true,
     [](double v, CopaMapConfig&, TrainConfig& t) { t.max_seconds = v; }},
    {"natgrad_gamma", ConfigKey::kReal, 0, 1, true,
     [](double v, CopaMapConfig&, TrainConfig& t) { t.natgrad_gamma_start = t.natgrad_gamma_end = v; }},
    {"natgrad_gamma_start", ConfigKey::kReal, 0, 1, true,
     [](double v, CopaMapConfig&, TrainConfig& t) { t.natgrad_gamma_start = v; }},
    {"natgrad_gamma_end", ConfigKey::kReal, 0, 1, true,
     [](double v, CopaMapConfig&, TrainConfig& t) { t.natgrad_gamma_end = v; }},
    {"adam_lr_start", ConfigKey::kReal, 0, 1, true,
     [](double v, CopaMapConfig&, TrainConfig& t) { t.adam_lr_start = v; }},
    {"adam_lr_end", ConfigKey::kReal, 0, 1, true,
     [](double v, CopaMapConfig&, TrainConfig& t) { t.adam_lr_end = v; }},
    {"decay_steps", ConfigKey::kInt, 1, kIntMax, false,
     [](double v, CopaMapConfig&, TrainConfig& t) { t.decay_steps = static_cast<int>(v); }},
    {"hyper_every", ConfigKey::kInt, 1, kIntMax, false,
     [](double v, CopaMapConfig&, TrainConfig& t) { t.hyper_every = static_cast<int>(v); }},
    {"hyper_warmup", ConfigKey::kInt, 0, kIntMax, false,
     [](double v, CopaMapConfig&, TrainConfig& t) { t.hyper_warmup = static_cast<int>(v); }},
    {"train_hyper", ConfigKey::kFlag, 0, 1, false,
     [](double v, CopaMapConfig&, TrainConfig& t) { t.train_hyper = v != 0; }},
    {"train_inducing", ConfigKey::kFlag, 0, 1, false,
     [](double v, CopaMapConfig&, TrainConfig& t) { t.train_inducing = v != 0; }},
    {"inducing_lr", ConfigKey::kReal, 0, 1e3, true,
     [](double v, CopaMapConfig&, TrainConfig& t) { t.inducing_lr = v; }},
    {"tolerance", ConfigKey::kReal, 0, 1, false,
     [](double v, CopaMapConfig&, TrainConfig& t) { t.tolerance = v; }},
    {"elbo_floor", ConfigKey::kReal, 0, 1e9, false,
     [](double v, CopaMapConfig&, TrainConfig& t) { t.elbo_floor = v; }},
    {"patience", ConfigKey::kInt, 1, 1e6, false,
     [](double v, CopaMapConfig&, TrainConfig& t) { t.patience = static_cast<int>(v); }},
    {"decay_tau", ConfigKey::kReal, 0, 1e12, false,
     [](double v, CopaMapConfig&, TrainConfig& t) { t.decay_tau = v; }},
    {"plateau_factor", ConfigKey::kReal, 0, 1, true,
     [](double v, CopaMapConfig&, TrainConfig& t) { t.plateau_factor = v; }},
    {"average_iterates", ConfigKey::kFlag, 0, 1, false,
     [](double v, CopaMapConfig&, TrainConfig& t) { t.average_iterates = v != 0; }},
    {"mixed_precision", ConfigKey::kFlag, 0, 1, false,
     [](double v, CopaMapConfig&, TrainConfig& t) { t.mixed_precision = v != 0; }},
    {"seed", ConfigKey::kInt, 0, kSeedMax, false,
     [](double v, CopaMapConfig& m, TrainConfig& t) {
       t.seed = m.seed = m.period_init.seed = static_cast<std::uint64_t>(v);
     }},
    {"alpha_ind", ConfigKey::kReal, 0, 1, true,
     [](double v, CopaMapConfig& m, TrainConfig&) { m.alpha_ind = v; }},
    {"g_inducing_ratio", ConfigKey::kReal, 0, 1, true,
     [](double v, CopaMapConfig& m, TrainConfig&) { m.g_inducing_ratio = v; }},
    {"spatial_lengthscale", ConfigKey::kReal, 0, 1e6, true,
     [](double v, CopaMapConfig& m, TrainConfig&) { m.spatial_lengthscale = v; }},
    {"periodic_lengthscale", ConfigKey::kReal, 0, 1e6, true,
     [](double v, CopaMapConfig& m, TrainConfig&) { m.periodic_lengthscale = v; }},
    {"jitter", ConfigKey::kReal, 0, 1, false, [](double v, CopaMapConfig& m, TrainConfig&) { m.jitter = v; }},
    {"gh_order", ConfigKey::kInt, 1, 100, false,
     [](double v, CopaMapConfig& m, TrainConfig&) { m.gh_order = static_cast<int>(v); }},
    {"cell_size", ConfigKey::kReal, 1e-3, 1e6, false,
     [](double v, CopaMapConfig& m, TrainConfig&) { m.cell_size = v; }},
    {"time_bin", ConfigKey::kReal, 1e-6, 1e12, false,
     [](double v, CopaMapConfig& m, TrainConfig&) { m.time_bin = v; }},
    {"init_cell_size", ConfigKey::kReal, 1e-3, 1e6, false,
     [](double v, CopaMapConfig& m, TrainConfig&) { m.period_init.cell_size = v; }},
    {"period_min", ConfigKey::kReal, 0, 1e12, true,
     [](double v, CopaMapConfig& m, TrainConfig&) { m.period_init.period_min = v; }},
    {"period_max", ConfigKey::kReal, 0, 1e12, false,
     [](double v, CopaMapConfig& m, TrainConfig&) { m.period_init.period_max = v; }},
    {"period_step", ConfigKey::kReal, 0, 1e12, true,
     [](double v, CopaMapConfig& m, TrainConfig&) { m.period_init.period_step = v; }},
    {"num_series", ConfigKey::kInt, 1, 1e6, false,
     [](double v, CopaMapConfig& m, TrainConfig&) { m.period_init.num_series = static_cast<int>(v); }},
    {"max_periods", ConfigKey::kInt, 1, 1000, false,
     [](double v, CopaMapConfig& m, TrainConfig&) { m.period_init.max_periods = static_cast<int>(v); }},
    {"max_variance", ConfigKey::kReal, 0, 1, true,
     [](double v, CopaMapConfig& m, TrainConfig&) { m.period_init.max_variance = v; }},
};

std::string rangeText(const ConfigKey& k) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "%s%.16g, %.16g]", k.lo_open ? "(" : "[", k.lo, k.hi);
  return buf;
}

// Config file: `key = value` lines, '#' comments. Unknown keys, values that are not one number, and values
// out of the key's range are errors (with file and line).
void applyConfig(const std::string& path, CopaMapConfig& mc, TrainConfig& tc) {
  std::ifstream in = openInputFile(path, "config file");
  std::string line;
  long ln = 0, period_line = 0;  // last line setting period_min or period_max
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
    const ConfigKey* k = nullptr;
    for (const ConfigKey& c : kConfigKeys)
      if (key == c.name) k = &c;
    if (k == nullptr) throw InputError(path, ln, "unknown key '" + key + "'");
    const auto parsed = cairn::strict_number::parse_finite(val);
    if (!parsed) throw InputError(path, ln, "value of '" + key + "' is not a number: '" + val + "'");
    const double v = *parsed;
    if (k->kind == ConfigKey::kFlag && v != 0 && v != 1)
      throw InputError(path, ln, "value of '" + key + "' must be 0 or 1, got '" + val + "'");
    if (k->kind == ConfigKey::kInt && v != std::floor(v))
      throw InputError(path, ln, "value of '" + key + "' must be an integer, got '" + val + "'");
    if (!(k->lo_open ? v > k->lo : v >= k->lo) || !(v <= k->hi))
      throw InputError(path, ln,
                       "value of '" + key + "' must be in " + rangeText(*k) + ", got '" + val + "'");
    k->set(v, mc, tc);
    if (key == "period_min" || key == "period_max") period_line = ln;
  }
  if (in.bad()) throw InputError(path, ln, "read error");
  const PeriodInitConfig& pi = mc.period_init;
  if (pi.period_max > 0 && pi.period_max < pi.period_min)
    throw InputError(path, period_line, "period_max must be 0 (half the data span) or >= period_min");
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

// eval of a model whose training diverged: no scores (they would be of the restored last good state), exit 3 as
// `train`.
int evalDiverged(const std::string& which, const TrainReport& rep) {
  std::fprintf(stderr, "cairn: copa: eval: training of %s diverged: %s\n", which.c_str(), rep.message.c_str());
  return 3;
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
    const TrainReport rep = m.train(tr.X, tr.y, tc);
    if (rep.diverged) return evalDiverged(which, rep);
    t_train = now() - t0;
    t0 = now();
    p = m.predict(te.X);
    logd = m.logPredictiveDensity(te.X, te.y);
  } else {
    CopaMap cm;
    if (which == "copa") {
      cm = CopaMap::initialize(tr.X, tr.y, tr.durations, mc, Z.size() ? &Z : nullptr);
      tc.progress = [&tc](int it, double elbo, double s) { progressBar(it, elbo, s, tc); };
      const TrainReport rep = cm.train(tr.X, tr.y, tc);
      std::fprintf(stderr, "\n");
      if (rep.diverged) return evalDiverged(which, rep);
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

// Comma-separated finite numbers; an empty list or an empty item is an error naming the option.
std::vector<double> parseList(const std::string& s, const std::string& what) {
  if (s.empty()) throw UsageError(what + " needs at least one number");
  std::vector<double> v;
  std::string::size_type pos = 0;
  while (true) {
    const auto comma = s.find(',', pos);
    const std::string tok = trim(s.substr(pos, comma == std::string::npos ? std::string::npos : comma - pos));
    const auto d = cairn::strict_number::parse_finite(tok);
    if (!d) throw UsageError("bad number '" + tok + "' in " + what);
    v.push_back(*d);
    if (comma == std::string::npos) break;
    pos = comma + 1;
  }
  return v;
}

// Largest heat map `render` writes: cells of the model grid and pixels of the PNG (3 bytes each).
constexpr double kMaxRenderCells = 1e7;
constexpr double kMaxRenderPixels = 1e8;

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
  const double fx = std::ceil((x1 - x0) / cs), fy = std::ceil((y1 - y0) / cs);
  const double px = std::max(1.0, std::round(cs / map.map.resolution));  // PNG pixels per cell side
  if (!(fx * fy <= kMaxRenderCells) || !(fx * fy * px * px <= kMaxRenderPixels)) {
    char buf[256];
    std::snprintf(
        buf, sizeof buf,
        "render area is %.4g x %.4g cells of %g m (%.4g PNG pixels); at most %.0e cells and %.0e pixels "
        "(give a smaller --bbox)",
        fx, fy, cs, fx * fy * px * px, kMaxRenderCells, kMaxRenderPixels);
    throw UsageError(buf);
  }
  const int nx = static_cast<int>(fx), ny = static_cast<int>(fy);
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
    if (verb == "train") return cmdTrain(parseArgs(argc, argv, 2, {"train", "inducing", "config", "out"}));
    if (verb == "eval")
      return cmdEval(parseArgs(argc, argv, 2, {"model", "train", "test", "inducing", "config", "json"}));
    if (verb == "predict") return cmdPredict(parseArgs(argc, argv, 2, {"model", "points", "out"}));
    if (verb == "render")
      return cmdRender(parseArgs(argc, argv, 2, {"model", "map", "times", "bbox", "out"}));
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
