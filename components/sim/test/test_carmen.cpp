#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>

#include "cairn/sim/carmen.hpp"
#include "cairn/sim/rng.hpp"

using namespace cairn::sim;
const std::string kData = std::string(CAIRN_SOURCE_ROOT) + "/test/data/carmen/";

namespace {
struct Counts {
  int lasers = 0, odoms = 0;
  double first_laser = -1, last_laser = -1, first_odom = -1;
  bool monotonic = true;
  std::size_t beams = 0;
};
Counts readAll(const std::string& path, CarmenReaderOptions opt = {}) {
  CarmenReader reader(path, std::move(opt));
  CarmenRecord r;
  Counts c;
  double last = -1e300;
  while (reader.next(r)) {
    const double t = stampOf(r);
    if (auto* l = std::get_if<CarmenLaser>(&r)) {
      if (c.lasers++ == 0) c.first_laser = t, c.beams = l->scan.ranges.size();
      if (t < c.last_laser) c.monotonic = false;
      c.last_laser = t;
    } else {
      if (c.odoms++ == 0) c.first_odom = t;
    }
    last = t;
  }
  (void)last;
  return c;
}
}  // namespace

TEST(CarmenLine, FlaserFieldsAndLayout) {
  std::string line = "FLASER 4 1.0 2.5 81.9 3.0 0.5 0.6 0.7 0.4 0.5 0.6 12.25 myhost 0.5";
  CarmenRecord r;
  std::string err;
  ASSERT_EQ(parseCarmenLine(line, {}, r, err), CarmenLineStatus::Record) << err;
  const auto& l = std::get<CarmenLaser>(r);
  EXPECT_EQ(l.message, "FLASER");
  ASSERT_EQ(l.scan.ranges.size(), 4u);
  EXPECT_FLOAT_EQ(l.scan.ranges[1], 2.5F);
  EXPECT_TRUE(std::isinf(l.scan.ranges[2]));  // max range = no return
  EXPECT_FLOAT_EQ(l.scan.angle_min, static_cast<float>(-std::numbers::pi / 2));
  EXPECT_FLOAT_EQ(l.scan.angle_increment, static_cast<float>(std::numbers::pi / 4));
  EXPECT_DOUBLE_EQ(l.laser_pose.x, 0.5);
  EXPECT_DOUBLE_EQ(l.robot_pose.theta, 0.6);
  EXPECT_DOUBLE_EQ(l.scan.stamp, 12.25);
  EXPECT_EQ(l.host, "myhost");
  // 181 beams: -90° .. +90° in 1° steps
  std::string l181 = "FLASER 181";
  for (int i = 0; i < 181; ++i) l181 += " 1";
  l181 += " 0 0 0 0 0 0 1 h 1";
  ASSERT_EQ(parseCarmenLine(l181, {}, r, err), CarmenLineStatus::Record);
  EXPECT_NEAR(std::get<CarmenLaser>(r).scan.angle_max, std::numbers::pi / 2, 1e-6);
}

TEST(CarmenLine, OdomRobotlaserRawlaser) {
  CarmenRecord r;
  std::string err;
  ASSERT_EQ(parseCarmenLine("ODOM 1 2 0.5 0.3 0.1 0 100.5 h 100.6", {}, r, err), CarmenLineStatus::Record);
  const auto& o = std::get<CarmenOdom>(r);
  EXPECT_DOUBLE_EQ(o.pose.y, 2.0);
  EXPECT_DOUBLE_EQ(o.tv, 0.3);
  EXPECT_DOUBLE_EQ(o.stamp, 100.5);
  ASSERT_EQ(parseCarmenLine("ROBOTLASER1 0 -1.5 3.0 1.0 30 0.01 0 3 1 2 3 3 10 20 30 1 1 0 0.9 1 0 0.2 0.1 0.5 0.3 0 "
                            "7.5 h 7.6",
                            {}, r, err),
            CarmenLineStatus::Record)
      << err;
  const auto& rl = std::get<CarmenLaser>(r);
  EXPECT_FLOAT_EQ(rl.scan.angle_min, -1.5F);
  EXPECT_FLOAT_EQ(rl.scan.angle_increment, 1.0F);
  EXPECT_FLOAT_EQ(rl.scan.range_max, 30.0F);
  ASSERT_EQ(rl.scan.intensities.size(), 3u);
  EXPECT_FLOAT_EQ(rl.scan.intensities[2], 30.0F);
  EXPECT_DOUBLE_EQ(rl.robot_pose.x, 0.9);
  EXPECT_DOUBLE_EQ(rl.scan.stamp, 7.5);
  ASSERT_EQ(parseCarmenLine("RAWLASER1 0 -1.5 3.0 1.0 30 0.01 0 2 1 2 0 4.5 h 4.6", {}, r, err), CarmenLineStatus::Record) << err;
  EXPECT_FALSE(std::get<CarmenLaser>(r).has_pose);
  for (const char* skip : {"# comment", "", "PARAM a b c h 0", "NEFF 30", "SYNC tag 1 h 1", "TRUEPOS 1 2 3 4 5 6 7 h 8"})
    EXPECT_EQ(parseCarmenLine(skip, {}, r, err), CarmenLineStatus::Skipped) << skip;
}

TEST(CarmenLine, MalformedLinesAreReportedNotCrashed) {
  CarmenRecord r;
  std::string err;
  for (const char* bad : {"ODOM 1 2", "ODOM 1 2 x 0 0 0 1 h 1", "ODOM 1 2 3 0 0 0 1 h 1 extra", "FLASER -3 1 2",
                          "FLASER 3 1 2", "FLASER 1e9", "FLASER 2 1 2 0 0 0 0 0 0 5 h", "ROBOTLASER1 0 0 3 1 -1 0 0 0 0",
                          "FLASER nan", "ODOM inf 0 0 0 0 0 1 h 1"}) {
    EXPECT_EQ(parseCarmenLine(bad, {}, r, err), CarmenLineStatus::Malformed) << bad;
    EXPECT_FALSE(err.empty());
  }
}

TEST(CarmenLine, RandomMutationsNeverCrash) {
  // Deterministic poor man's fuzzing (the libFuzzer target is fuzz/fuzz_carmen_line.cpp): byte flips,
  // truncations and token duplications of real lines must give Record, Skipped or Malformed.
  std::ifstream in(kData + "aces_head60.clf");
  std::vector<std::string> lines;
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  ASSERT_EQ(lines.size(), 60u);
  Rng rng(99);
  const char alphabet[] = "0123456789.-+eE naxFLSERODM#\t";
  int records = 0, malformed = 0;
  for (int k = 0; k < 20000; ++k) {
    std::string s = lines[static_cast<std::size_t>(rng.uniform() * lines.size())];
    const int edits = 1 + static_cast<int>(rng.uniform() * 4);
    for (int e = 0; e < edits && !s.empty(); ++e) {
      const std::size_t pos = static_cast<std::size_t>(rng.uniform() * s.size());
      switch (static_cast<int>(rng.uniform() * 4)) {
        case 0: s[pos] = alphabet[static_cast<std::size_t>(rng.uniform() * (sizeof alphabet - 1))]; break;
        case 1: s.resize(pos); break;
        case 2: s.insert(pos, s.substr(pos, 8)); break;
        default: s[pos] = static_cast<char>(rng.uniform() * 256); break;
      }
    }
    CarmenRecord r;
    std::string err;
    const auto st = parseCarmenLine(s, {}, r, err);
    records += st == CarmenLineStatus::Record;
    malformed += st == CarmenLineStatus::Malformed;
  }
  EXPECT_GT(malformed, 1000);
  EXPECT_GT(records, 100);
}

TEST(CarmenReader, ExcerptPlainGzipBzip2GiveTheSameRecords) {
  std::vector<std::string> files = {"aces_head60.clf", "aces_head60.clf.gz"};
#if CAIRN_SIM_HAVE_BZIP2
  files.push_back("aces_head60.clf.bz2");
#else
  EXPECT_THROW(CarmenReader(kData + "aces_head60.clf.bz2"), InputError);  // a clear error instead of garbage
#endif
  for (const auto& f : files) {
    const Counts c = readAll(kData + f);
    EXPECT_EQ(c.lasers, 23) << f;
    EXPECT_EQ(c.odoms, 24) << f;
    EXPECT_EQ(c.beams, 180u) << f;
    EXPECT_DOUBLE_EQ(c.first_laser, 70.2899) << f;
    EXPECT_DOUBLE_EQ(c.first_odom, 70.179699) << f;
    EXPECT_TRUE(c.monotonic) << f;
  }
  CarmenReader reader(kData + files.back());
  CarmenRecord r;
  while (reader.next(r)) {
  }
  EXPECT_EQ(reader.stats().lines, 60u);
  EXPECT_EQ(reader.stats().skipped, 13u);
}

TEST(CarmenReader, CorrectedLogWithNeffLines) {
  const Counts c = readAll(kData + "aces_corrected_head162.log.gz");
  EXPECT_EQ(c.lasers, 3);
  EXPECT_EQ(c.odoms, 150);
  EXPECT_DOUBLE_EQ(c.first_laser, 21.0199);
}

TEST(CarmenReader, MalformedLineStopsWithFileLineOrIsSkipped) {
  namespace fs = std::filesystem;
  const fs::path p = fs::temp_directory_path() / "cairn_sim_bad.clf";
  {
    std::ofstream out(p);
    out << "# header\nODOM 0 0 0 0 0 0 1.0 h 1.0\nODOM 0 0 zero 0 0 0 2.0 h 2.0\nODOM 1 0 0 0 0 0 3.0 h 3.0\n";
  }
  try {
    readAll(p.string());
    FAIL() << "expected an error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), p.string());
    EXPECT_EQ(e.line(), 3);
    EXPECT_NE(std::string(e.what()).find(":3: ODOM: expected x y theta"), std::string::npos) << e.what();
  }
  CarmenReaderOptions opt;
  opt.skip_malformed = true;
  int warnings = 0;
  opt.on_warning = [&](const InputError& e) {
    ++warnings;
    EXPECT_EQ(e.line(), 3);
  };
  const Counts c = readAll(p.string(), opt);
  EXPECT_EQ(c.odoms, 2);
  EXPECT_EQ(warnings, 1);
  EXPECT_THROW(CarmenReader("/nonexistent/log.clf"), InputError);
}

TEST(CarmenReader, FullAcesLogFromSharedData) {
  // The full Freiburg ACES log (shared/data next to the repo; CI has it). Counts from shared/data/README.md.
  const std::string path = std::string(CAIRN_SOURCE_ROOT) + "/../shared/data/slam_logs_carmen/radish/aces.clf.bz2";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "shared data not present: " << path;
#if !CAIRN_SIM_HAVE_BZIP2
  GTEST_SKIP() << "built without bzip2";
#endif
  const Counts c = readAll(path);
  EXPECT_EQ(c.lasers, 7374);
  EXPECT_EQ(c.odoms, 7375);
  EXPECT_EQ(c.beams, 180u);
  EXPECT_TRUE(c.monotonic);
  EXPECT_NEAR(c.last_laser - c.first_laser, 1365.5, 0.5);  // README: 1365.5 s
}
