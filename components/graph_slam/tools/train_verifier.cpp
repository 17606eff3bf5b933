// `cairn slam train-verifier` / `cairn slam eval-verifier`: trains the AdaBoost loop-closure verifier on CARMEN
// logs with corrected poses (pairs labelled by the rule of PairLabelOptions, README "Loop-closure verifier") and
// evaluates a model on held-out logs: TPR/FPR/precision at the model's threshold, ROC AUC, and the TPR reachable at
// FPR 0.1 % / 1 % / 5 % (ROC summary).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "cairn/graph_slam/loop_verifier.hpp"
#include "cairn/sim/world.hpp"
#include "cli_util.hpp"
#include "verbs.hpp"

namespace gs = cairn::graph_slam;
namespace cli = cairn::slam_cli;

namespace {

constexpr const char* kTrainUsage =
    "usage: cairn slam train-verifier --logs a.log.gz[,b.log.gz...] --out model.yml.gz [--weak-count 50] [--seed N]\n"
    "                                 [--target-fpr 0.01] [--max-pairs 5000] [--json]\n";
constexpr const char* kEvalUsage =
    "usage: cairn slam eval-verifier --model model.yml.gz --logs c.log.gz[,d.log.gz...] [--threshold T] [--seed N]\n"
    "                                [--max-pairs 5000] [--max-negatives 20000] [--json]\n";

std::vector<std::string> splitList(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ','))
    if (!item.empty()) out.push_back(item);
  return out;
}

int atLeast(int v, int min, const std::string& what) {
  if (v < min) throw std::invalid_argument(what + " must be >= " + std::to_string(min));
  return v;
}

struct Common {
  std::vector<std::string> logs;
  std::string out, model;
  int weak_count = 50;
  double target_fpr = 0.01;
  bool has_threshold = false;
  double threshold = 0.0;
  gs::PairLabelOptions labels;
  bool json = false;
};

// Parses the options shared by both verbs; `allowed` lists the ones this verb takes.
Common parse(const std::vector<std::string>& args, const std::vector<std::string>& allowed, Common c = {}) {
  for (std::size_t k = 0; k < args.size(); ++k) {
    const std::string& a = args[k];
    if (std::find(allowed.begin(), allowed.end(), a) == allowed.end())
      throw std::invalid_argument((a.rfind('-', 0) == 0 ? "unknown option " : "unexpected argument ") + a);
    if (a == "--json") {
      c.json = true;
      continue;
    }
    if (k + 1 >= args.size()) throw std::invalid_argument(a + " needs a value");
    const std::string& v = args[++k];
    if (a == "--logs") {
      c.logs = splitList(v);
    } else if (a == "--out") {
      c.out = v;
    } else if (a == "--model") {
      c.model = v;
    } else if (a == "--weak-count") {
      c.weak_count = atLeast(cli::parseInt(v, a.c_str()), 1, a);
    } else if (a == "--seed") {
      c.labels.seed = static_cast<std::uint64_t>(atLeast(cli::parseInt(v, a.c_str()), 0, a));
    } else if (a == "--max-pairs") {
      c.labels.max_positives = static_cast<std::size_t>(atLeast(cli::parseInt(v, a.c_str()), 1, a));
      if (c.labels.balance) c.labels.max_negatives = c.labels.max_positives;
    } else if (a == "--max-negatives") {
      c.labels.max_negatives = static_cast<std::size_t>(atLeast(cli::parseInt(v, a.c_str()), 1, a));
    } else if (a == "--target-fpr") {
      c.target_fpr = cli::parseDouble(v, a.c_str());
      if (c.target_fpr < 0.0 || c.target_fpr > 1.0) throw std::invalid_argument("--target-fpr must be in [0, 1]");
    } else if (a == "--threshold") {
      c.threshold = cli::parseDouble(v, a.c_str());
      c.has_threshold = true;
    }
  }
  if (c.logs.empty()) throw std::invalid_argument("--logs is required");
  return c;
}

// Labelled pairs of every log (each log sampled with its own seed offset so logs are independent).
gs::LabelledPairs pairsOf(const std::vector<std::string>& logs, const gs::DescriptorOptions& d,
                          const gs::PairLabelOptions& base, std::string& per_log_json,
                          std::vector<gs::LabelledPairs>* per_log = nullptr) {
  gs::LabelledPairs all;
  for (std::size_t i = 0; i < logs.size(); ++i) {
    gs::PairLabelOptions o = base;
    o.seed = base.seed + i;
    const auto nodes = gs::loadVerifierNodes(logs[i], d);
    const gs::LabelledPairs p = gs::labelPairs(nodes, o);
    per_log_json += std::string(per_log_json.empty() ? "" : ",") +
                    cli::JsonObject()
                        .str("log", logs[i])
                        .integer("scans", static_cast<long long>(nodes.size()))
                        .integer("positives", static_cast<long long>(p.positives))
                        .integer("negatives", static_cast<long long>(p.negatives))
                        .integer("candidate_positives", static_cast<long long>(p.candidate_positives))
                        .integer("candidate_negatives", static_cast<long long>(p.candidate_negatives))
                        .text();
    all.append(p);
    if (per_log != nullptr) per_log->push_back(p);
  }
  return all;
}

// TPR/FPR/precision at the threshold, AUC, counts, and the ROC summary (TPR at FPR <= 0.1 %, 1 %, 5 %).
cli::JsonObject& addMetrics(cli::JsonObject& j, const gs::VerifierMetrics& m, const gs::LabelledPairs& p,
                            const gs::LoopVerifier& v) {
  std::vector<double> scores;
  scores.reserve(p.features.size());
  for (const auto& f : p.features) scores.push_back(v.scorePairFeatures(f));
  std::string roc;
  for (double fpr : {0.001, 0.01, 0.05}) {
    gs::LoopVerifier at = v;
    at.setThreshold(gs::thresholdForFpr(scores, p.labels, fpr));
    const gs::VerifierMetrics r = gs::evaluate(at, p);
    roc += std::string(roc.empty() ? "" : ",") +
           cli::JsonObject().num("max_fpr", fpr).num("threshold", r.threshold).num("tpr", r.tpr).num("fpr", r.fpr).text();
  }
  return j.num("threshold", m.threshold)
      .num("tpr", m.tpr)
      .num("fpr", m.fpr)
      .num("precision", m.precision)
      .num("auc", m.auc)
      .integer("positives", static_cast<long long>(p.positives))
      .integer("negatives", static_cast<long long>(p.negatives))
      .integer("tp", static_cast<long long>(m.tp))
      .integer("fp", static_cast<long long>(m.fp))
      .integer("tn", static_cast<long long>(m.tn))
      .integer("fn", static_cast<long long>(m.fn))
      .raw("roc", "[" + roc + "]");
}

void printHuman(const char* title, const gs::VerifierMetrics& m, const gs::LabelledPairs& p) {
  std::printf("%s: %zu positive / %zu negative pairs\n  threshold %.4g: TPR %.3f  FPR %.4f  precision %.4f  AUC %.4f\n",
              title, p.positives, p.negatives, m.threshold, m.tpr, m.fpr, m.precision, m.auc);
}

int usageError(const char* verb, const std::string& what, const char* usage) {
  std::cerr << "cairn: slam " << verb << ": " << what << "\n" << usage;
  return 2;
}

// Runs a verb's work: input errors (they name file:line) and other failures become one line on stderr, exit 2.
template <class Body>
int guarded(const char* verb, Body&& body) {
  try {
    body();
  } catch (const cairn::sim::InputError& e) {
    std::cerr << "cairn: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "cairn: slam " << verb << ": " << e.what() << "\n";
    return 2;
  }
  return 0;
}

}  // namespace

int trainVerifierVerb(const std::vector<std::string>& args) {
  Common c;
  try {
    c = parse(args, {"--logs", "--out", "--weak-count", "--seed", "--target-fpr", "--max-pairs", "--json"});
    if (c.out.empty()) throw std::invalid_argument("--out is required");
  } catch (const std::invalid_argument& e) {
    return usageError("train-verifier", e.what(), kTrainUsage);
  }
  const auto t0 = std::chrono::steady_clock::now();
  std::string threshold_source;
  return guarded("train-verifier", [&] {
    const gs::DescriptorOptions d;
    std::string per_log;
    std::vector<gs::LabelledPairs> per;
    const gs::LabelledPairs pairs = pairsOf(c.logs, d, c.labels, per_log, &per);
    gs::LoopVerifier v = gs::LoopVerifier::train(pairs.features, pairs.labels, c.weak_count, d);
    // Stüde §3.2.1: FPR < 1 % is the target; the threshold is the smallest one meeting it. With several logs it is
    // picked on out-of-log scores (each log scored by a model trained on the others), which transfers to unseen
    // buildings better than the training pairs' own (optimistic) scores; with one log, on the training pairs.
    std::vector<double> scores;
    std::vector<int> labels;
    for (std::size_t i = 0; i < per.size(); ++i) {
      gs::LabelledPairs rest;
      for (std::size_t j = 0; j < per.size(); ++j)
        if (j != i) rest.append(per[j]);
      const gs::LoopVerifier held = per.size() > 1 ? gs::LoopVerifier::train(rest.features, rest.labels, c.weak_count, d) : v;
      for (std::size_t k = 0; k < per[i].features.size(); ++k) {
        scores.push_back(held.scorePairFeatures(per[i].features[k]));
        labels.push_back(per[i].labels[k]);
      }
    }
    v.setThreshold(gs::thresholdForFpr(scores, labels, c.target_fpr));
    threshold_source = per.size() > 1 ? "out-of-log" : "training pairs";
    v.save(c.out);
    const gs::VerifierMetrics m = gs::evaluate(v, pairs);
    const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (c.json) {
      cli::JsonObject train;
      addMetrics(train, m, pairs, v);
      std::cout << cli::JsonObject()
                       .str("out", c.out)
                       .integer("weak_count", c.weak_count)
                       .integer("seed", static_cast<long long>(c.labels.seed))
                       .num("target_fpr", c.target_fpr)
                       .str("threshold_from", threshold_source)
                       .raw("logs", "[" + per_log + "]")
                       .raw("train", train.text())
                       .num("time_s", secs)
                       .text()
                << "\n";
    } else {
      printHuman("training pairs", m, pairs);
      std::printf("threshold from %s scores at FPR <= %g\n", threshold_source.c_str(), c.target_fpr);
      std::printf("model written to %s (%d stumps, %.1f s)\n", c.out.c_str(), c.weak_count, secs);
    }
  });
}

int evalVerifierVerb(const std::vector<std::string>& args) {
  Common c;
  try {
    // Held-out evaluation: every positive (up to 5000) and up to 20000 negatives (not balanced), so the FPR is
    // estimated from many negatives; `precision` is at that sampled ratio.
    c.labels.balance = false;
    c.labels.max_negatives = 20000;
    c = parse(args, {"--model", "--logs", "--threshold", "--seed", "--max-pairs", "--max-negatives", "--json"}, c);
    if (c.model.empty()) throw std::invalid_argument("--model is required");
  } catch (const std::invalid_argument& e) {
    return usageError("eval-verifier", e.what(), kEvalUsage);
  }
  return guarded("eval-verifier", [&] {
    gs::LoopVerifier v = gs::LoopVerifier::load(c.model);
    if (c.has_threshold) v.setThreshold(c.threshold);
    std::string per_log;
    const gs::LabelledPairs pairs = pairsOf(c.logs, v.descriptorOptions(), c.labels, per_log);
    const gs::VerifierMetrics m = gs::evaluate(v, pairs);
    if (c.json) {
      cli::JsonObject j;
      j.str("model", c.model).integer("seed", static_cast<long long>(c.labels.seed)).raw("logs", "[" + per_log + "]");
      std::cout << addMetrics(j, m, pairs, v).text() << "\n";
    } else {
      printHuman("held-out pairs", m, pairs);
    }
  });
}
