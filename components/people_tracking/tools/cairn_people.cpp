// cairn-people: command-line front end of the people tracking core (`cairn people <verb> ...`).
//   train      build labelled clusters from generated scenes and train a leg classifier
//   eval       precision/recall of a model on held-out generated scenes
//   bench      replay pedestrian trajectories in a simulated scene and score the tracker (CLEAR MOT)
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <map>
#include <string>
#include <vector>

#include "cairn/people_tracking/classifier.hpp"
#include "tool_bench.hpp"
#include "tool_mask_bench.hpp"


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
  std::fprintf(stderr, "cairn: %s:%d: %s\n", __FILE__, __LINE__, what.c_str());
  std::exit(2);
}

Args parse(int argc, char** argv, int first, const std::vector<std::string>& bool_flags) {
  Args a;
  for (int i = first; i < argc; ++i) {
    std::string s = argv[i];
    if (s.rfind("--", 0) != 0) fail("unexpected argument '" + s + "'");
    s = s.substr(2);
    bool is_flag = false;
    for (const auto& f : bool_flags) is_flag |= (f == s);
    if (is_flag) {
      a.flags.push_back(s);
    } else {
      if (i + 1 >= argc) fail("option --" + s + " needs a value");
      a.kv[s] = argv[++i];
    }
  }
  return a;
}

long toLong(const Args& a, const std::string& k, long def) {
  const std::string v = a.get(k, "");
  if (v.empty()) return def;
  char* end = nullptr;
  const long x = std::strtol(v.c_str(), &end, 10);
  if (*end != '\0') fail("--" + k + " expects an integer, got '" + v + "'");
  return x;
}

double toDouble(const Args& a, const std::string& k, double def) {
  const std::string v = a.get(k, "");
  if (v.empty()) return def;
  char* end = nullptr;
  const double x = std::strtod(v.c_str(), &end);
  if (*end != '\0') fail("--" + k + " expects a number, got '" + v + "'");
  return x;
}

void usage() {
  std::puts(
      "usage: cairn people <verb> [options]\n"
      "  train --kind adaboost|svm [--features arras14@1|stuede5@1] [--scenes 1500] [--seed 1] --out FILE\n"
      "  eval  --model FILE [--scenes 500] [--seed 1000003] [--json]\n"
      "  bench --world auto --trajectories FILE [--robot-path FILE] [--seed N] [--duration S] [--max-people N]\n"
      "        [--association gnn|jpda] [--pairing tracks|detector] [--model FILE] [--rate HZ] [--start S] [--dump DIR] [--json]\n"
      "  mask-bench [--world apartment] [--route home_tour] [--seed N] [--speed 0.5] [--lead 1.2] [--json]");
}

int train(const Args& a) {
  ClassifierTrainParams p;
  p.kind = classifierKindFromString(a.get("kind", "adaboost"));
  p.feature_set = a.get("features", "arras14@1");
  p.boost_weak_count = static_cast<int>(toLong(a, "weak-count", p.boost_weak_count));
  p.svm_c = toDouble(a, "svm-c", p.svm_c);
  p.svm_gamma = toDouble(a, "svm-gamma", p.svm_gamma);
  p.positive_weight = toDouble(a, "pos-weight", p.positive_weight);
  TrainingDataParams d;
  d.scenes = static_cast<int>(toLong(a, "scenes", 1500));
  d.seed = static_cast<std::uint64_t>(toLong(a, "seed", 1));
  const std::string out = a.get("out", "");
  if (out.empty()) fail("train needs --out FILE");
  const auto samples = generateLabelledClusters(d);
  std::size_t pos = 0;
  for (const auto& s : samples) pos += s.positive;
  const LegClassifier c = LegClassifier::train(samples, p);
  c.save(out);
  const ClassifierMetrics m = c.evaluate(samples);
  std::printf("trained %s on %s: %zu clusters (%zu person) from %d scenes, seed %llu; training P=%.3f R=%.3f -> %s\n",
              toString(p.kind), p.feature_set.c_str(), samples.size(), pos, d.scenes,
              static_cast<unsigned long long>(d.seed), m.precision(), m.recall(), out.c_str());
  return 0;
}

int eval(const Args& a) {
  const std::string path = a.get("model", "");
  if (path.empty()) fail("eval needs --model FILE");
  const LegClassifier c = LegClassifier::load(path);
  TrainingDataParams d;
  d.scenes = static_cast<int>(toLong(a, "scenes", 500));
  d.seed = static_cast<std::uint64_t>(toLong(a, "seed", 1000003));
  const auto samples = generateLabelledClusters(d);
  const ClassifierMetrics m = c.evaluate(samples);
  if (a.flag("json")) {
    std::printf(
        "{\"model\": \"%s\", \"kind\": \"%s\", \"feature_set\": \"%s\", \"scenes\": %d, \"seed\": %llu, "
        "\"clusters\": %zu, \"tp\": %zu, \"fp\": %zu, \"tn\": %zu, \"fn\": %zu, \"precision\": %.4f, "
        "\"recall\": %.4f, \"f1\": %.4f}\n",
        path.c_str(), toString(c.kind()), c.featureSet().key().c_str(), d.scenes,
        static_cast<unsigned long long>(d.seed), samples.size(), m.tp, m.fp, m.tn, m.fn, m.precision(), m.recall(),
        m.f1());
  } else {
    std::printf("%s (%s, %s) on %d held-out scenes (seed %llu, %zu clusters): precision %.3f recall %.3f F1 %.3f\n",
                path.c_str(), toString(c.kind()), c.featureSet().key().c_str(), d.scenes,
                static_cast<unsigned long long>(d.seed), samples.size(), m.precision(), m.recall(), m.f1());
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
    if (verb == "train") return train(parse(argc, argv, 2, {}));
    if (verb == "eval") return eval(parse(argc, argv, 2, {"json"}));
    if (verb == "bench") return runBenchVerb(argc, argv);
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
