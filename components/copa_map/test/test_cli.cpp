// cairn-copa end to end: train -> predict -> eval, and bad input (one `cairn: <file>:<line>: …` line, exit 2).
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
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

}  // namespace

TEST(CopaCli, TrainPredictEval) {
  const std::string dir = testing::TempDir();
  // Small sub-area of the ATC test split: days 1-3 train, day 4 test.
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
  tr.close();
  te.close();
  pts.close();
  std::ofstream(dir + "/cli_cfg.txt") << "max_iterations = 20\nbatch_size = 300\nperiod_max = 24\n"
                                          "step_decay = invsqrt\ndecay_steps = 10\naverage_iterates = 1\n"
                                          "patience = 2\nelbo_floor = 1\n";
  std::string err;
  ASSERT_EQ(run("train --train " + dir + "/cli_train.csv --config " + dir + "/cli_cfg.txt -o " + dir + "/cli_model.txt", &err), 0) << err;
  ASSERT_EQ(run("predict --model " + dir + "/cli_model.txt --points " + dir + "/cli_pts.csv -o " + dir + "/cli_pred.csv", &err), 0) << err;
  const std::string pred = slurp(dir + "/cli_pred.csv");
  EXPECT_EQ(pred.rfind("x1,x2,t,mean,std\n", 0), 0u);
  EXPECT_GT(std::count(pred.begin(), pred.end(), '\n'), 10);
  ASSERT_EQ(run("eval --model " + dir + "/cli_model.txt --train " + dir + "/cli_train.csv --test " + dir +
                    "/cli_test.csv --json > " + dir + "/cli_eval.json", &err), 0) << err;
  const std::string js = slurp(dir + "/cli_eval.json");
  EXPECT_NE(js.find("\"nrmse\": "), std::string::npos) << js;
  EXPECT_NE(js.find("\"nlpd\": "), std::string::npos) << js;
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
