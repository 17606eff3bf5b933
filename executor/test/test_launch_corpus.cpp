// Replays the launch-spec fuzz corpus (test/fuzz/launch_spec) through the parser in every build, so the
// inputs the fuzzer found keep being checked without clang: each parses or gives a one-line LaunchError.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "cairn/launch.hpp"

TEST(LaunchCorpus, EveryInputParsesOrGivesALaunchError) {
  int files = 0, rejected = 0;
  for (const auto& e : std::filesystem::directory_iterator(CORPUS_DIR)) {
    std::ifstream in(e.path(), std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    ++files;
    try {
      (void)cairn::parse_launch_spec_text(ss.str(), e.path().filename().string());
    } catch (const cairn::LaunchError& err) {
      ++rejected;
      const std::string msg = err.what();
      EXPECT_EQ(msg.find('\n'), std::string::npos) << e.path() << ": error spans several lines: " << msg;
      EXPECT_EQ(msg.rfind(e.path().filename().string() + ":", 0), 0u) << msg;
    } catch (const std::exception& other) {
      ADD_FAILURE() << e.path() << ": unexpected exception " << other.what();
    }
  }
  EXPECT_GE(files, 5);
  EXPECT_GE(rejected, 3) << "the corpus holds invalid specs too";
}
