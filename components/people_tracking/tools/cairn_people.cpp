// cairn-people: command-line front end of the people tracking core (`cairn people <verb> ...`).
//   train      build labelled clusters from generated scenes and train a leg classifier
//   eval       precision/recall of a model on held-out generated scenes
//   gen-train  labelled clusters from components/sim scans (CSV for train/eval --data)
//   bench      replay pedestrian trajectories in a simulated scene and score the tracker (CLEAR MOT)
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <map>
#include <string>
#include <vector>

#include "cairn/people_tracking/classifier.hpp"
#include "cli_parse.hpp"
#include "tool_bench.hpp"
#include "mask_bench.hpp"
#ifdef CAIRN_PEOPLE_SIM
#include "sim_training.hpp"
#endif


using namespace cairn::people_tracking;

namespace {

struct Args {
  std::map<std::string, std::string> kv;
  std::vector<std::string> flags;
  [[nodiscard]] bool has(const std::string& k) const { return kv.count(k) || flag(k); }
  [[nodiscard]] bool flag(const std::string& k) const {
    for (const auto& f : flags)
      if (f == k) return true;
    return false;
  }
  [[nodiscard]] std::string get(const std::string& k, const std::string& def) const {
    auto it = kv.find(k);
    return it == kv.end() ? def : it->second;
  }
};

[[noreturn]] void fail(const std::string& what) {
  std::fprintf(stderr, "cairn people: %s\n", what.c_str());  // the place (file:line, option) is in `what`
  std::exit(2);
}

// The verb's options: `values` take a value, `bool_flags` do not; anything else is an error (a typo such as
// --scene for --scenes would otherwise run with the default).
Args parse(int argc, char** argv, int first, const std::string& verb, const std::vector<std::string>& values,
           const std::vector<std::string>& bool_flags) {
  Args a;
  auto known = [](const std::vector<std::string>& list, const std::string& s) {
    return std::find(list.begin(), list.end(), s) != list.end();
  };
  for (int i = first; i < argc; ++i) {
    std::string s = argv[i];
    if (s.rfind("--", 0) != 0) fail("unexpected argument '" + s + "'");
    s = s.substr(2);
    if (known(bool_flags, s)) {
      a.flags.push_back(s);
    } else if (known(values, s)) {
      if (i + 1 >= argc) fail("option --" + s + " needs a value");
      a.kv[s] = argv[++i];
    } else {
      fail(verb + ": unknown option --" + s + " (cairn people --help)");
    }
  }
  return a;
}

// An option given with an empty value ("--scenes ''") is an error, not the default.
long long toInteger(const Args& a, const std::string& k, long long def, long long lo, long long hi) {
  return a.kv.count(k) ? parseInteger("--" + k, a.kv.at(k), lo, hi) : def;
}

double toDouble(const Args& a, const std::string& k, double def) {
  return a.kv.count(k) ? parseNumber("--" + k, a.kv.at(k)) : def;
}

// A number option that must be > 0.
double toPositive(const Args& a, const std::string& k, double def) {
  const double x = toDouble(a, k, def);
  if (!(x > 0.0)) fail("option --" + k + " expects a number > 0, got '" + a.get(k, "") + "'");
  return x;
}

void usage() {
  std::puts(
      "usage: cairn people <verb> [options]\n"
      "  train --kind adaboost|svm [--features arras14@1|stuede5@1] [--scenes 1500] [--seed 1] [--groups P] [--data CSV[,CSV]]\n"
      "        [--weak-count N] [--svm-c C] [--svm-gamma G] [--pos-weight W] [--min-points N] --out FILE\n"
      "  eval  --model FILE [--scenes 500] [--seed 1000003] [--groups P] [--data CSV] [--json]\n"
      "  gen-train [--worlds apartment,office,warehouse,open] [--episodes 200] [--seed 1] [--scans-per-episode 6] [--walker-area 5]\n"
      "            [--max-walkers N] [--scene-generator N] -o FILE\n"
      "  bench --world auto|office|apartment|warehouse|WORLD.yaml --trajectories FILE [--robot-path FILE|circle:R|route:NAME[:SPEED]]\n"
      "        [--trajectory-offset X,Y[,THETA]] [--static-map [--static-map-margin M] [--track-leg-confidence-with-map C]] [--seed N] [--duration S]\n"
      "        [--association gnn|jpda] [--pairing tracks|detector] [--model FILE] [--rate HZ] [--start S]\n"
      "        [--reid-window S] [--reid-max-distance M] [--publish-coast S] [--split-scans K] [--joint-pairs NODES] [--confirm-hits N] [--confirm-score L] [--single-leg-stride M]\n"
      "        [--min-leg-confidence C] [--single-leg-min-confidence C] [--track-leg-confidence C] [--beams N] [--smooth S] [--fix-id-swaps] [--dump DIR] [--json]\n"
      "        tracker tuning (README): [--process-noise Q] [--delete-timeout S] [--max-position-sigma M] [--leg-spread M]\n"
      "        [--leg-spread-lateral M] [--leg-gate CHI2] [--confidence-cost C] [--confidence-gain G] [--occluded-coast S] [--occluded-delete-timeout S]\n"
      "        [--free-space-delete N] [--visibility-radius M] [--min-init-distance M] [--initial-velocity-sigma V]\n"
      "        [--standing-time S] [--standing-speed V] [--standing-noise Q]   (standing people; time 0 = off)\n"
      "        [--pair-distance M] [--sigma-pair M] [--sigma-single M] [--min-points N] [--small-cluster-min-range M]\n"
      "        two legs in one cluster: [--split-min-width M] (> 0.45 = off) [--split-gap-ratio R] [--split-min-gap-beams B]\n"
      "        [--maneuver-noise Q] [--maneuver-rate R] [--maneuver-end-rate R]   (IMM; 0 = one walking mode)\n"
      "        [--maneuver-gate M] [--maneuver-gate-time S]   (maneuver gate; 0 = off)\n"
      "        [--adaptive-nis T] (0 = off) [--adaptive-gain G] [--adaptive-smoothing W]   (adaptive process noise)\n"
      "        motion evidence: [--motion-window S] (0 = off) [--motion-min-age S] [--motion-margin M] [--motion-slope-factor K] [--motion-min-free-scans N] [--moving-fraction F]\n"
      "        [--moving-track-leg-confidence C] [--moving-min-leg-confidence C]\n"
      "        free-space memory: [--motion-memory S] (0 = off) [--crossed-track-leg-confidence C]\n"
      "        second source: [--camera FOV_DEG] [--camera-range M] [--camera-bearing-sigma DEG] [--camera-range-sigma R]\n"
      "        [--camera-pd P] [--camera-false N] [--fusion-distance M] [--fusion-gate CHI2]\n"
      "        diagnostic: [--oracle-detections] [--oracle-sigma M]   (true positions instead of the detector)\n"
      "        scores cairn and a baseline: CLEAR MOT (MOTA, MOTP, ID switches, FP, FN), HOTA (DetA, AssA, LocA), IDF1,\n"
      "        OSPA, scans/s (JSON fields: README); tools/score_dump.py rescores a --dump directory independently\n"
      "  mask-bench [--world apartment] [--route home_tour] [--seed N] [--speed 0.5] [--lead 1.2] [--robot follow|route]\n"
      "             [--keep-spurs] [--follow-distance M] [--fov-deg 360] [--range-max 20] [--mask tangents|inside] [--model FILE]\n"
      "             [--min-points N] [--heading-drift R] [--scale-error E] [--max-duration S] [--json]");
}

// --data: comma-separated list of labelled-cluster CSV files (absent: none; given empty: an error).
std::vector<LabelledCluster> loadData(const Args& a) {
  std::vector<LabelledCluster> out;
  if (!a.kv.count("data")) return out;
  const std::string& list = a.kv.at("data");
  if (list.empty()) fail("option --data needs at least one file, got ''");
  std::size_t begin = 0;
  while (begin < list.size()) {
    const std::size_t end = std::min(list.find(',', begin), list.size());
    const std::vector<LabelledCluster> part = loadLabelledClusters(list.substr(begin, end - begin));
    out.insert(out.end(), part.begin(), part.end());
    begin = end + 1;
  }
  return out;
}

#ifdef CAIRN_PEOPLE_SIM
int genTrain(const Args& a) {
  SimTrainingParams p;
  if (a.kv.count("worlds")) {
    if (a.kv.at("worlds").empty()) fail("option --worlds needs at least one world, got ''");
    p.worlds = splitCommas(a.kv.at("worlds"));
  }
  p.episodes = static_cast<int>(toInteger(a, "episodes", p.episodes, 1, 10000000));
  p.seed = static_cast<std::uint64_t>(toInteger(a, "seed", 1, 0, kMaxSeed));
  p.scans_per_episode = static_cast<int>(toInteger(a, "scans-per-episode", p.scans_per_episode, 1, 100000));
  p.max_walkers = static_cast<int>(toInteger(a, "max-walkers", p.max_walkers, 1, 1000));
  p.walker_area = toDouble(a, "walker-area", p.walker_area);
  if (!(p.walker_area >= 1.0 && p.walker_area <= 50.0)) fail("gen-train: --walker-area must be in [1, 50] m");
  if (p.episodes < 1 || p.scans_per_episode < 1) fail("gen-train: --episodes and --scans-per-episode must be >= 1");
  if (p.max_walkers < p.min_walkers) fail("gen-train: --max-walkers must be >= 1");
  const std::string out = a.get("o", a.get("out", ""));
  if (out.empty()) fail("gen-train needs -o FILE");
  if (a.has("scene-generator")) {  // the package's own scene generator instead of the simulator (for comparisons)
    TrainingDataParams d;
    d.scenes = static_cast<int>(toInteger(a, "scene-generator", 500, 1, 10000000));
    d.seed = p.seed;
    const auto samples = generateLabelledClusters(d);
    saveLabelledClusters(out, samples);
    std::printf("gen-train: %zu clusters from %d generated scenes (seed %llu) -> %s\n", samples.size(), d.scenes,
                static_cast<unsigned long long>(d.seed), out.c_str());
    return 0;
  }
  SimLabelStats st;
  const std::vector<SimLabelledCluster> clusters = simLabelledClusters(p, &st);
  std::vector<LabelledCluster> samples;
  std::map<std::string, std::size_t> by_class;
  for (const SimLabelledCluster& c : clusters) {
    samples.push_back(c.sample);
    ++by_class[toString(c.sample.object_class)];
  }
  saveLabelledClusters(out, samples);
  std::printf("gen-train: %d episodes (seed %llu), %zu scans, %zu clusters: %zu person legs, %zu other, %zu ambiguous "
              "(skipped), %zu beyond range ->",
              p.episodes, static_cast<unsigned long long>(p.seed), st.scans, samples.size(), st.positives, st.negatives,
              st.ambiguous, st.far);
  for (const auto& [cls, n] : by_class) std::printf(" %s %zu", cls.c_str(), n);
  std::printf(" -> %s\n", out.c_str());
  return 0;
}
#endif

// --groups P: probability in [0, 1] that a generated person walks with a companion beside them.
double groupProbability(const Args& a) {
  const double p = toDouble(a, "groups", 0.0);
  if (!(p >= 0.0 && p <= 1.0)) fail("option --groups expects a probability in [0, 1], got '" + a.get("groups", "") + "'");
  return p;
}

int train(const Args& a) {
  ClassifierTrainParams p;
  p.kind = classifierKindFromString(a.get("kind", "adaboost"));
  p.feature_set = a.get("features", "arras14@1");
  p.boost_weak_count = static_cast<int>(toInteger(a, "weak-count", p.boost_weak_count, 1, 100000));
  p.svm_c = toPositive(a, "svm-c", p.svm_c);
  p.svm_gamma = toPositive(a, "svm-gamma", p.svm_gamma);
  p.positive_weight = toPositive(a, "pos-weight", p.positive_weight);
  TrainingDataParams d;
  // --data only: the CSV files; --data and --scenes: both (a mix); neither: generated scenes.
  d.scenes = static_cast<int>(toInteger(a, "scenes", a.has("data") ? 0 : 1500, 0, 10000000));
  d.seed = static_cast<std::uint64_t>(toInteger(a, "seed", 1, 0, kMaxSeed));
  d.segmentation.min_points = static_cast<int>(toInteger(a, "min-points", d.segmentation.min_points, 1, 1000));
  d.scene.group_probability = groupProbability(a);
  const std::string out = a.get("out", "");
  if (out.empty()) fail("train needs --out FILE");
  LegClassifier::checkWritable(out);  // before the training, not after it
  const std::vector<LabelledCluster> data = loadData(a);  // a bad file before the scenes are generated
  auto samples = generateLabelledClusters(d);
  samples.insert(samples.end(), data.begin(), data.end());
  std::size_t pos = 0;
  for (const auto& s : samples) pos += s.positive;
  const LegClassifier c = LegClassifier::train(samples, p);
  c.save(out);
  const ClassifierMetrics m = c.evaluate(samples);
  std::printf("trained %s on %s: %zu clusters (%zu person) from %d generated scenes (seed %llu) + %zu from --data; "
              "training P=%.3f R=%.3f -> %s\n",
              toString(p.kind), p.feature_set.c_str(), samples.size(), pos, d.scenes,
              static_cast<unsigned long long>(d.seed), data.size(), m.precision(), m.recall(), out.c_str());
  return 0;
}

int eval(const Args& a) {
  const std::string path = a.get("model", "");
  if (path.empty()) fail("eval needs --model FILE");
  TrainingDataParams d;
  d.scenes = static_cast<int>(toInteger(a, "scenes", a.has("data") ? 0 : 500, 0, 10000000));
  d.seed = static_cast<std::uint64_t>(toInteger(a, "seed", 1000003, 0, kMaxSeed));
  d.scene.group_probability = groupProbability(a);
  const std::vector<LabelledCluster> data = loadData(a);
  const LegClassifier c = LegClassifier::load(path);
  auto samples = generateLabelledClusters(d);
  samples.insert(samples.end(), data.begin(), data.end());
  if (samples.empty()) fail("eval: no samples (--scenes 0 and no --data)");
  const ClassifierMetrics m = c.evaluate(samples);
  if (a.flag("json")) {
    std::printf(
        "{\"model\": \"%s\", \"kind\": \"%s\", \"feature_set\": \"%s\", \"scenes\": %d, \"seed\": %llu, \"data\": \"%s\", "
        "\"clusters\": %zu, \"tp\": %zu, \"fp\": %zu, \"tn\": %zu, \"fn\": %zu, \"precision\": %.4f, "
        "\"recall\": %.4f, \"f1\": %.4f}\n",
        path.c_str(), toString(c.kind()), c.featureSet().key().c_str(), d.scenes,
        static_cast<unsigned long long>(d.seed), a.get("data", "").c_str(), samples.size(), m.tp, m.fp, m.tn, m.fn, m.precision(), m.recall(),
        m.f1());
  } else {
    std::printf("%s (%s, %s) on %d held-out scenes (seed %llu) + data '%s' (%zu clusters): precision %.3f recall %.3f "
                "F1 %.3f\n",
                path.c_str(), toString(c.kind()), c.featureSet().key().c_str(), d.scenes,
                static_cast<unsigned long long>(d.seed), a.get("data", "").c_str(), samples.size(), m.precision(), m.recall(), m.f1());
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || std::string(argv[1]) == "--help" || std::string(argv[1]) == "-h") {
    usage();
    return argc < 2 ? 2 : 0;
  }
  const std::string verb = argv[1];
  try {
    if (verb == "train")
      return train(parse(argc, argv, 2, verb,
                         {"kind", "features", "weak-count", "svm-c", "svm-gamma", "pos-weight", "scenes", "seed",
                          "min-points", "groups", "data", "out"},
                         {}));
    if (verb == "eval") return eval(parse(argc, argv, 2, verb, {"model", "scenes", "seed", "groups", "data"}, {"json"}));
    if (verb == "bench") return runBenchVerb(argc, argv);
#ifdef CAIRN_PEOPLE_SIM
    if (verb == "gen-train") {
      // -o is the one single-dash option (as the issue writes it); map it to --o.
      std::vector<std::string> args(argv, argv + argc);
      std::vector<char*> ptrs;
      for (std::string& x : args) {
        if (x == "-o") x = "--o";
        ptrs.push_back(x.data());
      }
      return genTrain(parse(argc, ptrs.data(), 2, verb,
                            {"worlds", "episodes", "seed", "scans-per-episode", "walker-area", "max-walkers",
                             "scene-generator", "o", "out"},
                            {}));
    }
#else
    if (verb == "gen-train") fail("gen-train was not built (needs the sim component)");
#endif
#ifdef CAIRN_PEOPLE_MASK_BENCH
    if (verb == "mask-bench") return runMaskBenchVerb(argc, argv);
#else
    if (verb == "mask-bench") fail("mask-bench was not built (needs the graph_slam and sim components)");
#endif

  } catch (const std::exception& e) {
    fail(e.what());
  }
  usage();
  fail("unknown verb '" + verb + "'");
}
