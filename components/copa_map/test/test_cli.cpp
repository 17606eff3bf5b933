// cairn-copa end to end: train -> predict -> eval, and bad input (one `cairn: <file>:<line>: …` line, exit 2).
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

namespace {

const std::string kTool = CAIRN_COPA_TOOL;
const std::string kAtc = std::string(CAIRN_SOURCE_ROOT) + "/test/data/atc_copa_map/grid_atc_50cm_60min_test_xy.csv";

int run(const std::string& args, std::string* err = nullptr) {
  const std::string errf = testing::TempDir() + "/cairn_copa_cli_err.txt";
  const int rc = std::system((kTool + " " + args + " 2> " + errf).c_str());
  if (err) {
    std::ifstream in(errf);
    std::stringstream ss;
    ss << in.rdbuf();
    *err = ss.str();
  }
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

std::string slurp(const std::string& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// Small sub-area of the ATC test split: days 1-3 train (cli_train.csv), day 4 test (cli_test.csv), points at
// t = 40 (cli_pts.csv).
void writeSubArea(const std::string& dir) {
  std::ifstream in(kAtc);
  std::ofstream tr(dir + "/cli_train.csv"), te(dir + "/cli_test.csv"), pts(dir + "/cli_pts.csv");
  std::string line;
  std::getline(in, line);
  tr << line << "\n";
  te << line << "\n";
  pts << "x1,x2,t\n";
  while (std::getline(in, line)) {
    double x1, x2, t;
    if (std::sscanf(line.c_str(), "%lf,%lf,%lf", &x1, &x2, &t) != 3) continue;
    if (x1 < 14 || x1 > 19 || x2 < -12 || x2 > -7) continue;
    (t < 36 ? tr : te) << line << "\n";
    if (t == 40) pts << line.substr(0, line.rfind(',')) << "\n";
  }
}

}  // namespace

TEST(CopaCli, TrainPredictEval) {
  const std::string dir = testing::TempDir();
  writeSubArea(dir);
  std::ofstream(dir + "/cli_cfg.txt") << "max_iterations = 20\nbatch_size = 300\nperiod_max = 24\n"
                                          "step_decay = invsqrt\ndecay_steps = 10\naverage_iterates = 1\n"
                                          "patience = 2\nelbo_floor = 1\n";
  std::string err;
  ASSERT_EQ(run("train --train " + dir + "/cli_train.csv --config " + dir + "/cli_cfg.txt -o " + dir + "/cli_model.txt", &err), 0) << err;
  ASSERT_EQ(run("predict --model " + dir + "/cli_model.txt --points " + dir + "/cli_pts.csv -o " + dir + "/cli_pred.csv", &err), 0) << err;
  const std::string pred = slurp(dir + "/cli_pred.csv");
  EXPECT_EQ(pred.rfind("x1,x2,t,mean,std\n", 0), 0u);
  EXPECT_GT(std::count(pred.begin(), pred.end(), '\n'), 10);
  {  // every row: the point it was asked for (t = 40), a non-negative rate and a positive std
    std::istringstream rows(pred);
    std::string row;
    std::getline(rows, row);
    int n = 0;
    while (std::getline(rows, row)) {
      double x1, x2, t, mean, sd;
      ASSERT_EQ(std::sscanf(row.c_str(), "%lf,%lf,%lf,%lf,%lf", &x1, &x2, &t, &mean, &sd), 5) << row;
      EXPECT_EQ(t, 40.0) << row;
      EXPECT_TRUE(std::isfinite(mean) && mean >= 0 && std::isfinite(sd) && sd > 0) << row;
      ++n;
    }
    EXPECT_GT(n, 10);
  }
  ASSERT_EQ(run("eval --model " + dir + "/cli_model.txt --train " + dir + "/cli_train.csv --test " + dir +
                    "/cli_test.csv --json > " + dir + "/cli_eval.json", &err), 0) << err;
  // Every documented key, each a finite number (the model file has a variance: NLPD and coverage too).
  const std::string js = slurp(dir + "/cli_eval.json");
  for (const char* key : {"n_train", "n_test", "nrmse", "chi2", "nlpd", "coverage95", "train_seconds", "predict_seconds"}) {
    std::string needle = "\"";
    needle.append(key).append("\": ");
    const std::size_t at = js.find(needle);
    ASSERT_NE(at, std::string::npos) << key << " in " << js;
    const double v = std::strtod(js.c_str() + at + needle.size(), nullptr);
    EXPECT_TRUE(std::isfinite(v) && v >= 0) << key << " in " << js;
  }
  const double nrmse_file = std::strtod(js.c_str() + js.find("\"nrmse\": ") + 9, nullptr);
  EXPECT_GT(nrmse_file, 0.0);
  ASSERT_EQ(run("eval --model ml --train " + dir + "/cli_train.csv --test " + dir + "/cli_test.csv --json > " + dir +
                    "/cli_ml.json", &err), 0) << err;
  EXPECT_NE(slurp(dir + "/cli_ml.json").find("\"nlpd\": null"), std::string::npos);
}

TEST(CopaCli, BadInputIsOneLineAndExitCode2) {
  const std::string dir = testing::TempDir();
  std::ofstream(dir + "/cli_bad.csv") << "x1,x2,t,y\n1,2,3,4\n1,2,oops,4\n";
  std::string err;
  EXPECT_EQ(run("train --train " + dir + "/cli_bad.csv -o " + dir + "/x.txt", &err), 2);
  EXPECT_EQ(err, "cairn: " + dir + "/cli_bad.csv:3: non-numeric value 'oops' in column t\n");
  std::ofstream(dir + "/cli_model_bad.txt") << "cairn-copa-model 7\n";
  EXPECT_EQ(run("predict --model " + dir + "/cli_model_bad.txt --points " + dir + "/cli_bad.csv -o " + dir + "/y.csv", &err), 2);
  EXPECT_NE(err.find("version 7 is not supported"), std::string::npos) << err;
  EXPECT_EQ(run("frobnicate", &err), 2);
  std::ofstream(dir + "/cli_cfg_bad.txt") << "batch_size = 300\nstep_decay = cosine\n";
  EXPECT_EQ(run("train --train " + dir + "/cli_bad.csv --config " + dir + "/cli_cfg_bad.txt -o " + dir + "/x.txt", &err), 2);
  EXPECT_EQ(err, "cairn: " + dir + "/cli_cfg_bad.txt:2: step decay 'cosine': expected constant, invsqrt or plateau\n");
}

namespace {

// Writes a config file whose line 2 is `line` (line 1 is a comment) and runs `train` with it.
int trainWithConfigLine(const std::string& line, std::string* err) {
  const std::string dir = testing::TempDir();
  std::ofstream(dir + "/cli_range.txt") << "# range check\n" << line << "\n";
  return run(
      "train --train " + dir + "/cli_never_read.csv --config " + dir + "/cli_range.txt -o " + dir + "/x.txt",
      err);
}

}  // namespace

TEST(CopaCli, ZeroPeriodStepIsAnErrorNotAHang) {
  const std::string dir = testing::TempDir();
  std::string err;
  EXPECT_EQ(trainWithConfigLine("period_step = 0", &err), 2);
  EXPECT_EQ(err, "cairn: " + dir +
                     "/cli_range.txt:2: value of 'period_step' must be in (0, 1000000000000], got '0'\n");
}

TEST(CopaCli, EveryConfigValueIsRangeCheckedWithFileAndLine) {
  const std::string dir = testing::TempDir();
  for (const std::string line :
       {"max_iterations = -5", "batch_size = 0", "batch_size = -1", "batch_size = 2.5", "max_seconds = -1",
        "patience = -1", "seed = -1", "hyper_every = 0", "decay_steps = 0", "cell_size = 0", "time_bin = -1",
        "alpha_ind = 2", "train_hyper = 2", "natgrad_gamma = 0"}) {
    std::string err;
    EXPECT_EQ(trainWithConfigLine(line, &err), 2) << line;
    const std::string key = line.substr(0, line.find(' '));
    EXPECT_EQ(err.rfind("cairn: " + dir + "/cli_range.txt:2: value of '" + key + "' must be ", 0), 0u)
        << line << ": " << err;
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  }
  std::string err;
  EXPECT_EQ(trainWithConfigLine("max_iterations = 5 6", &err), 2);
  EXPECT_EQ(err, "cairn: " + dir + "/cli_range.txt:2: value of 'max_iterations' is not a number: '5 6'\n");
  EXPECT_EQ(trainWithConfigLine("period_max = 1.5", &err), 2);  // below the default period_min 2
  EXPECT_EQ(err, "cairn: " + dir +
                     "/cli_range.txt:2: period_max must be 0 (half the data span) or >= period_min\n");
  EXPECT_EQ(trainWithConfigLine("cell_size = 1e-300", &err),
            2);  // cell indices floor(x / r_s) would overflow
  EXPECT_EQ(err, "cairn: " + dir +
                     "/cli_range.txt:2: value of 'cell_size' must be in [0.001, 1000000], got '1e-300'\n");
  EXPECT_EQ(trainWithConfigLine("gh_order = 1000000", &err), 2);
  EXPECT_EQ(err,
            "cairn: " + dir + "/cli_range.txt:2: value of 'gh_order' must be in [1, 100], got '1000000'\n");
}

TEST(CopaCli, UnknownOptionsAndDirectoriesAreErrors) {
  const std::string dir = testing::TempDir();
  std::string err;
  EXPECT_EQ(run("train --train a.csv -o m.txt --bogus 1", &err), 2);
  EXPECT_EQ(err.rfind("cairn: copa: unknown option '--bogus'\n", 0), 0u) << err;
  EXPECT_EQ(run("predict --model m.txt --points p.csv -o out.csv --bogus 1", &err), 2);
  EXPECT_EQ(err.rfind("cairn: copa: unknown option '--bogus'\n", 0), 0u) << err;
  EXPECT_EQ(run("predict --model m.txt --json --points p.csv -o out.csv", &err), 2);  // --json is eval's
  EXPECT_EQ(err.rfind("cairn: copa: unknown option '--json'\n", 0), 0u) << err;
  EXPECT_EQ(run("train --train a.csv --train b.csv -o m.txt", &err), 2);
  EXPECT_EQ(err.rfind("cairn: copa: option '--train' given twice\n", 0), 0u) << err;
  EXPECT_EQ(run("train --train a.csv -o m.txt --config " + dir, &err), 2);
  EXPECT_EQ(err, "cairn: " + dir + ":0: cannot open config file: is a directory\n");
  EXPECT_EQ(run("train --train " + dir + " -o m.txt", &err), 2);
  EXPECT_EQ(err, "cairn: " + dir + ":0: cannot open file: is a directory\n");
}

TEST(CopaCli, NegativeRateInAGridCsvIsAnError) {
  const std::string dir = testing::TempDir();
  std::ofstream(dir + "/cli_neg.csv") << "x1,x2,t,y\n1,2,3,4\n\n1,2,4,-0.5\n";
  std::string err;
  EXPECT_EQ(run("train --train " + dir + "/cli_neg.csv -o " + dir + "/x.txt", &err), 2);
  EXPECT_EQ(err, "cairn: " + dir + "/cli_neg.csv:4: negative rate y\n");
}

TEST(CopaCli, RenderChecksMapYamlTimesAndArea) {
  const std::string dir = testing::TempDir();
  writeSubArea(dir);
  std::ofstream(dir + "/cli_render_cfg.txt") << "max_iterations = 1\nbatch_size = 300\nperiod_max = 24\n";
  std::string err;
  const std::string model = dir + "/cli_render_model.txt";
  ASSERT_EQ(run("train --train " + dir + "/cli_train.csv --config " + dir + "/cli_render_cfg.txt -o " + model,
                &err),
            0)
      << err;
  const std::string png = std::string(CAIRN_SOURCE_ROOT) + "/test/data/people/atc_map.png";
  auto render = [&](const std::string& yaml, const std::string& extra) {
    std::ofstream(dir + "/cli_map.yaml") << yaml;
    return run("render --model " + model + " --map " + dir + "/cli_map.yaml -o " + dir + "/cli_r " + extra,
               &err);
  };
  const std::string small = "--times 40 --bbox 14,-12,16,-10";
  // The flow form is valid YAML.
  EXPECT_EQ(render("{image: " + png + ", resolution: 0.05, origin: [-60, -40, 0]}\n", small), 0) << err;
  for (const char* f : {"/cli_r_t40_mean.png", "/cli_r_t40_std.png"}) {  // PNG signature
    const std::string img = slurp(dir + f);
    EXPECT_EQ(img.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8)) << f;
  }
  EXPECT_EQ(render("image: " + png + "\nresolution: 0.05\norigin: [-60, -40, 0\nnegate: 0\n", small), 2);
  EXPECT_EQ(err.rfind("cairn: " + dir + "/cli_map.yaml:", 0), 0u) << err;
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  EXPECT_EQ(render("image: " + png + "\nresolution: 0.05\norigin: [-60, -40, 0]\n  negate: 0\n", small), 2);
  EXPECT_EQ(err.rfind("cairn: " + dir + "/cli_map.yaml:", 0), 0u) << err;
  EXPECT_EQ(render("image: " + png + "\nresolution: 0.05\norigin: [-60, -40, 0]\nnegatee: 0\n", small), 2);
  EXPECT_EQ(err.rfind("cairn: " + dir + "/cli_map.yaml:4: unknown key 'negatee'", 0), 0u) << err;
  EXPECT_EQ(render("image: " + png + "\nresolution: 0.05\norigin: [-60, -40, 0]\nresolution: 0.1\n", small), 2);
  EXPECT_EQ(err.rfind("cairn: " + dir + "/cli_map.yaml:4: duplicate key 'resolution'", 0), 0u) << err;
  const std::string good = "image: " + png + "\nresolution: 0.05\norigin: [-60, -40, 0]\n";
  EXPECT_EQ(render(good, "--times '' --bbox 14,-12,16,-10"), 2);
  EXPECT_EQ(err.rfind("cairn: copa: --times needs at least one number\n", 0), 0u) << err;
  EXPECT_EQ(render(good, "--times 40, --bbox 14,-12,16,-10"), 2);
  EXPECT_EQ(err.rfind("cairn: copa: bad number '' in --times\n", 0), 0u) << err;
  EXPECT_EQ(render(good, "--times 40 --bbox -1e9,-1e9,1e9,1e9"), 2);
  EXPECT_EQ(err.rfind("cairn: copa: render area is 4e+09 x 4e+09 cells", 0), 0u) << err;
}
