// Stochastic BT analysis (Stüde §5.2.2, eqs. 5.1-5.2) against closed forms and Monte-Carlo execution.
#include <gtest/gtest.h>

#include <cmath>

#include "cairn/bt_executive/sbt.hpp"

using namespace cairn::bt::sbt;

namespace {

TEST(Sbt, SingleActionMatchesClosedForm) {
  Analysis a(action("a", 0.7, 0.5, 2.0));
  for (double t : {0.0, 0.5, 1.0, 3.0, 10.0}) {
    auto [ps, pf] = a.probabilities(t);
    EXPECT_NEAR(ps, 0.7 * (1 - std::exp(-0.5 * t)), 1e-9);
    EXPECT_NEAR(pf, 0.3 * (1 - std::exp(-2.0 * t)), 1e-9);
  }
  EXPECT_NEAR(a.successProbability(), 0.7, 1e-12);
  EXPECT_NEAR(a.successRate(), 0.5, 1e-9);
  EXPECT_NEAR(a.failureRate(), 2.0, 1e-9);
}

TEST(Sbt, SequenceOfTwoCertainActionsIsHypoexponential) {
  const double l1 = 1.0, l2 = 3.0;
  Analysis a(sequence({action("a", 1.0, l1, 1.0), action("b", 1.0, l2, 1.0)}));
  for (double t : {0.2, 1.0, 2.5}) {
    const double cdf = 1 - (l2 * std::exp(-l1 * t) - l1 * std::exp(-l2 * t)) / (l2 - l1);
    EXPECT_NEAR(a.successProbability(t), cdf, 1e-9);
  }
  EXPECT_NEAR(a.successRate(), 1.0 / (1 / l1 + 1 / l2), 1e-9);  // E[T] = 1/l1 + 1/l2
}

TEST(Sbt, ConditionsBranchInstantly) {
  // Fallback(C, A): succeeds at t=0 with p_C, else runs A.
  Analysis a(fallback({condition("c", 0.4), action("a", 0.5, 1.0, 1.0)}));
  EXPECT_NEAR(a.successProbability(0.0), 0.4, 1e-12);
  EXPECT_NEAR(a.successProbability(), 0.4 + 0.6 * 0.5, 1e-12);
  EXPECT_NEAR(a.failureProbability(), 0.3, 1e-12);
  EXPECT_THROW(Analysis(sequence({})), std::invalid_argument);
  EXPECT_THROW(Analysis(action("x", 1.5, 1, 1)), std::invalid_argument);
}

// Validation demanded by the issue: analysis vs Monte-Carlo execution with sampled durations agree within 1 %.
TEST(Sbt, AgreesWithMonteCarloOnMixedTrees) {
  const std::vector<Node> trees = {
      sequence({condition("door_open", 0.8), action("go_through", 0.9, 0.2, 0.05),
                fallback({action("find_person", 0.6, 0.05, 0.02), action("ask_supervisor", 0.95, 0.01, 0.5)})}),
      fallback({sequence({action("wait0", 0.5, 0.1, 0.07), action("return", 0.98, 0.3, 0.01)}),
                sequence({action("search01", 0.6, 0.05, 0.04), action("wait1", 0.7, 0.08, 0.03),
                          action("return1", 0.97, 0.02, 0.01)}),
                action("last", 0.3, 0.5, 1.0)}),
  };
  std::vector<double> times;
  for (int k = 0; k <= 20; ++k) times.push_back(10.0 * k);
  for (const auto& tree : trees) {
    Analysis a(tree);
    auto exact = a.probabilities(times);
    auto mc = monteCarlo(tree, times, 200000, 42);
    for (std::size_t k = 0; k < times.size(); ++k) {
      EXPECT_NEAR(exact[k].first, mc[k].first, 0.01) << "t=" << times[k];
      EXPECT_NEAR(exact[k].second, mc[k].second, 0.01) << "t=" << times[k];
      EXPECT_NEAR(exact[k].first, a.successProbability(times[k]), 1e-9);  // stepping == direct exponential
    }
    EXPECT_NEAR(a.successProbability(1e5), a.successProbability(), 1e-6);  // long-run limit = fundamental matrix
    EXPECT_NEAR(a.successProbability() + a.failureProbability(), 1.0, 1e-9);
  }
}

TEST(Sbt, XmlExport) {
  std::string xml = toXml(sequence({condition("c", 1), action("a", 1, 1, 1)}), "T");
  EXPECT_NE(xml.find("<Condition ID=\"c\"/>"), std::string::npos);
  EXPECT_NE(xml.find("<BehaviorTree ID=\"T\">"), std::string::npos);
}

}  // namespace
