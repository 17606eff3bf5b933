#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <unistd.h>
#include <vector>
#include <zlib.h>

#include "cairn/sim/carmen.hpp"
#include "cairn/sim/log_playback.hpp"
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

namespace {
// gzip of `text`; finish = false stops at a sync flush (complete deflate blocks, no end block, no trailer).
std::string gzipOf(const std::string& text, bool finish) {
  z_stream zs{};
  EXPECT_EQ(deflateInit2(&zs, 6, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY), Z_OK);
  std::string out(text.size() + 1024, '\0');
  zs.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(text.data()));
  zs.avail_in = static_cast<uInt>(text.size());
  zs.next_out = reinterpret_cast<Bytef*>(out.data());
  zs.avail_out = static_cast<uInt>(out.size());
  EXPECT_EQ(deflate(&zs, finish ? Z_FINISH : Z_SYNC_FLUSH), finish ? Z_STREAM_END : Z_OK);
  out.resize(zs.total_out);
  deflateEnd(&zs);
  return out;
}
std::string readError(const std::string& path) {
  try {
    readAll(path);
  } catch (const InputError& e) {
    return e.message();
  }
  return "no error";
}
}  // namespace

TEST(CarmenReader, CutOffGzipIsAnErrorNotAShorterLog) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / "cairn_sim_test_carmen_gzip";
  fs::create_directories(dir);
  auto write = [&](const char* name, const std::string& bytes) {
    std::ofstream(dir / name, std::ios::binary) << bytes;
    return (dir / name).string();
  };
  const std::string log = "ODOM 0 0 0 0 0 0 1.0 h 1.0\nODOM 1 0 0 0 0 0 2.0 h 2.0\n";
  const std::string full = gzipOf(log, true);
  // these were all read without an error: as the first record only, or as an empty log
  const std::string cut = "gzip: truncated data (the compressed stream ends before its end marker)";
  EXPECT_EQ(readError(write("flush.gz", gzipOf(log, false))), cut);
  EXPECT_EQ(readError(write("no_trailer.gz", full.substr(0, full.size() - 8))), cut);
  EXPECT_EQ(readError(write("magic_only.gz", full.substr(0, 2))), cut);
  EXPECT_EQ(readError(write("header_only.gz", full.substr(0, 10))), cut);
  EXPECT_EQ(readError(write("trailing.gz", full + "ODOM 2 0 0 0 0 0 3.0 h 3.0\n")),
            "gzip: data after the end of the compressed stream");
  EXPECT_EQ(readError(write("garbage.gz", "\x1f\x8bnot deflate data at all\n")).rfind("gzip: corrupt data", 0), 0u);
  // concatenated members (cat a.gz b.gz) and zero padding after the last member are complete logs
  EXPECT_EQ(readAll(write("two.gz", full + full)).odoms, 4);
  EXPECT_EQ(readAll(write("padded.gz", full + std::string(512, '\0'))).odoms, 2);
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

TEST(LogPlayback, StreamsTheFullAcesLogWithABoundedLookAhead) {
  // Memory does not grow with the log: 14749 records pass through a look-ahead of 8.
  const std::string path = std::string(CAIRN_SOURCE_ROOT) + "/../shared/data/slam_logs_carmen/radish/aces.clf.bz2";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "shared data not present: " << path;
#if !CAIRN_SIM_HAVE_BZIP2
  GTEST_SKIP() << "built without bzip2";
#endif
  LogPlaybackOptions opt;
  opt.lookahead = 8;
  LogPlayback playback(path, opt);
  EXPECT_EQ(playback.buffered(), 8u);
  CarmenReader reference(path);
  CarmenRecord want;
  std::size_t lasers = 0, odoms = 0, most = 0;
  while (const CarmenRecord* r = playback.peek()) {
    most = std::max(most, playback.buffered());
    ASSERT_TRUE(reference.next(want));
    ASSERT_EQ(stampOf(*r), stampOf(want)) << "record " << lasers + odoms;
    ASSERT_EQ(r->index(), want.index());
    (std::holds_alternative<CarmenLaser>(*r) ? lasers : odoms)++;
    playback.pop();
  }
  EXPECT_FALSE(reference.next(want));
  EXPECT_EQ(lasers, 7374u);
  EXPECT_EQ(odoms, 7375u);
  EXPECT_EQ(playback.played(), 7374u + 7375u);
  EXPECT_EQ(most, 8u);
  EXPECT_EQ(playback.maxBuffered(), 8u);
  EXPECT_EQ(playback.buffered(), 0u);
}

TEST(LogPlayback, LimitRewindAndLateMalformedLines) {
  const std::string path = kData + "aces_head60.clf";
  LogPlaybackOptions opt;
  opt.lookahead = 4;
  opt.limit = 10;
  LogPlayback playback(path, opt);
  std::vector<double> first_pass;
  while (const CarmenRecord* r = playback.peek()) {
    first_pass.push_back(stampOf(*r));
    playback.pop();
  }
  ASSERT_EQ(first_pass.size(), 10u);
  playback.rewind();
  for (double t : first_pass) {
    ASSERT_NE(playback.peek(), nullptr);
    EXPECT_EQ(stampOf(*playback.peek()), t);
    playback.pop();
  }
  EXPECT_EQ(playback.peek(), nullptr);

  // A malformed line beyond the look-ahead: every record before it is played, then file:line is raised.
  namespace fs = std::filesystem;
  const fs::path bad = fs::temp_directory_path() / ("cairn_sim_late_bad_" + std::to_string(::getpid()) + ".clf");
  {
    std::ofstream out(bad);
    for (int i = 0; i < 20; ++i) out << "ODOM " << i << " 0 0 0 0 0 " << i << ".5 h 1.0\n";
    out << "ODOM 0 0 zero 0 0 0 99.0 h 2.0\n";
  }
  LogPlaybackOptions lo;
  lo.lookahead = 4;
  LogPlayback late(bad.string(), lo);
  int played = 0;
  try {
    while (late.peek()) {
      late.pop();
      ++played;
    }
    FAIL() << "expected the malformed line";
  } catch (const InputError& e) {
    EXPECT_EQ(e.line(), 21);
    EXPECT_EQ(played, 20);
  }
  // Within the look-ahead: rejected at construction.
  lo.lookahead = 32;
  EXPECT_THROW(LogPlayback(bad.string(), lo), InputError);
  lo.reader.skip_malformed = true;
  LogPlayback skipping(bad.string(), lo);
  played = 0;
  while (skipping.peek()) {
    skipping.pop();
    ++played;
  }
  EXPECT_EQ(played, 20);
  fs::remove(bad);
  EXPECT_THROW(LogPlayback("/nonexistent/log.clf"), InputError);
}
