#include "cairn/sim/carmen.hpp"

#if CAIRN_SIM_HAVE_BZIP2
#include <bzlib.h>
#endif
#include <zlib.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <numbers>
#include <vector>

namespace cairn::sim {

// ---------------------------------------------------------------- line parser
namespace {

class Tokens {
 public:
  explicit Tokens(std::string_view s) : s_(s) {}
  bool next(std::string_view& tok) {
    while (pos_ < s_.size() && (s_[pos_] == ' ' || s_[pos_] == '\t' || s_[pos_] == '\r')) ++pos_;
    if (pos_ >= s_.size()) return false;
    const std::size_t b = pos_;
    while (pos_ < s_.size() && s_[pos_] != ' ' && s_[pos_] != '\t' && s_[pos_] != '\r') ++pos_;
    tok = s_.substr(b, pos_ - b);
    return true;
  }
  bool number(double& v) {
    std::string_view t;
    if (!next(t)) return false;
    // from_chars rejects a leading '+', which some writers emit
    if (!t.empty() && t[0] == '+') t.remove_prefix(1);
    const auto r = std::from_chars(t.data(), t.data() + t.size(), v);
    return r.ec == std::errc() && r.ptr == t.data() + t.size() && std::isfinite(v);
  }
  bool count(std::size_t& n, std::size_t limit) {
    double v = 0;
    if (!number(v) || v < 0 || v > static_cast<double>(limit) || v != std::floor(v)) return false;
    n = static_cast<std::size_t>(v);
    return true;
  }
  bool word(std::string& w) {
    std::string_view t;
    if (!next(t)) return false;
    w.assign(t);
    return true;
  }
  bool atEnd() {
    std::string_view t;
    return !next(t);
  }

 private:
  std::string_view s_;
  std::size_t pos_ = 0;
};

constexpr std::size_t kMaxBeams = 100000;

void fillScan(LaserScan& scan, const std::vector<double>& ranges, double angle_min, double increment, double max_range,
              double range_min) {
  scan.angle_min = static_cast<float>(angle_min);
  scan.angle_increment = static_cast<float>(increment);
  scan.angle_max = static_cast<float>(angle_min + increment * (ranges.empty() ? 0 : ranges.size() - 1));
  scan.range_min = static_cast<float>(range_min);
  scan.range_max = static_cast<float>(max_range);
  scan.ranges.resize(ranges.size());
  constexpr float inf = std::numeric_limits<float>::infinity();
  for (std::size_t i = 0; i < ranges.size(); ++i)
    scan.ranges[i] = ranges[i] >= max_range || ranges[i] < 0 ? inf : static_cast<float>(ranges[i]);
}

}  // namespace

CarmenLineStatus parseCarmenLine(std::string_view line, const CarmenLaserLayout& layout, CarmenRecord& out,
                                 std::string& error) {
  Tokens tk(line);
  std::string_view name;
  if (!tk.next(name) || name[0] == '#') return CarmenLineStatus::Skipped;
  auto bad = [&](const std::string& what) {
    error = std::string(name) + ": " + what;
    return CarmenLineStatus::Malformed;
  };
  auto tail = [&](double& ts, std::string& host, double& logger_ts) {
    return tk.number(ts) && tk.word(host) && tk.number(logger_ts) && tk.atEnd();
  };
  if (name == "ODOM") {
    CarmenOdom o;
    if (!(tk.number(o.pose.x) && tk.number(o.pose.y) && tk.number(o.pose.theta) && tk.number(o.tv) && tk.number(o.rv) &&
          tk.number(o.accel)))
      return bad("expected x y theta tv rv accel");
    if (!tail(o.stamp, o.host, o.logger_stamp)) return bad("expected ipc_timestamp hostname logger_timestamp at the end");
    out = std::move(o);
    return CarmenLineStatus::Record;
  }
  if (name == "FLASER" || name == "RLASER") {
    CarmenLaser l;
    l.message = std::string(name);
    std::size_t n = 0;
    if (!tk.count(n, kMaxBeams) || n == 0) return bad("bad number of readings");
    std::vector<double> r(n);
    for (auto& v : r)
      if (!tk.number(v)) return bad("expected " + std::to_string(n) + " range readings");
    if (!(tk.number(l.laser_pose.x) && tk.number(l.laser_pose.y) && tk.number(l.laser_pose.theta) &&
          tk.number(l.robot_pose.x) && tk.number(l.robot_pose.y) && tk.number(l.robot_pose.theta)))
      return bad("expected x y theta odom_x odom_y odom_theta after the readings");
    if (!tail(l.scan.stamp, l.host, l.logger_stamp)) return bad("expected ipc_timestamp hostname logger_timestamp at the end");
    l.has_pose = true;
    const double inc = (n % 2 == 0 || n == 1) ? layout.fov / static_cast<double>(n) : layout.fov / static_cast<double>(n - 1);
    const double start = name == "FLASER" ? -0.5 * layout.fov : std::numbers::pi - 0.5 * layout.fov;
    fillScan(l.scan, r, start, inc, layout.max_range, layout.range_min);
    l.scan.frame_id = name == "FLASER" ? "front_laser" : "rear_laser";
    out = std::move(l);
    return CarmenLineStatus::Record;
  }
  const bool robotlaser = name == "ROBOTLASER1" || name == "ROBOTLASER2";
  const bool rawlaser = name.substr(0, 8) == "RAWLASER" && name.size() == 9 && name[8] >= '1' && name[8] <= '4';
  if (robotlaser || rawlaser) {
    CarmenLaser l;
    l.message = std::string(name);
    double type = 0, start = 0, fov = 0, res = 0, maxr = 0, acc = 0, mode = 0;
    if (!(tk.number(type) && tk.number(start) && tk.number(fov) && tk.number(res) && tk.number(maxr) && tk.number(acc) &&
          tk.number(mode)))
      return bad("expected laser_type start_angle fov resolution max_range accuracy remission_mode");
    if (!(maxr > 0)) return bad("maximum_range must be > 0");
    std::size_t n = 0;
    if (!tk.count(n, kMaxBeams)) return bad("bad number of readings");
    std::vector<double> r(n);
    for (auto& v : r)
      if (!tk.number(v)) return bad("expected " + std::to_string(n) + " range readings");
    std::size_t m = 0;
    if (!tk.count(m, kMaxBeams)) return bad("bad number of remissions");
    std::vector<float> rem(m);
    for (auto& v : rem) {
      double d = 0;
      if (!tk.number(d)) return bad("expected " + std::to_string(m) + " remission values");
      v = static_cast<float>(d);
    }
    if (robotlaser) {
      double dummy = 0;
      if (!(tk.number(l.laser_pose.x) && tk.number(l.laser_pose.y) && tk.number(l.laser_pose.theta) &&
            tk.number(l.robot_pose.x) && tk.number(l.robot_pose.y) && tk.number(l.robot_pose.theta)))
        return bad("expected laser and robot poses after the remissions");
      for (int k = 0; k < 5; ++k)
        if (!tk.number(dummy)) return bad("expected tv rv forward_safety side_safety turn_axis");
      l.has_pose = true;
    }
    if (!tail(l.scan.stamp, l.host, l.logger_stamp)) return bad("expected ipc_timestamp hostname logger_timestamp at the end");
    fillScan(l.scan, r, start, res, maxr, layout.range_min);
    if (m == n) l.scan.intensities = std::move(rem);
    l.scan.frame_id = "laser";
    out = std::move(l);
    return CarmenLineStatus::Record;
  }
  return CarmenLineStatus::Skipped;  // PARAM, SYNC, NEFF, TRUEPOS, anything else
}

// ---------------------------------------------------------------- decompressing byte sources
class CarmenReader::Source {
 public:
  virtual ~Source() = default;
  /// Reads up to n bytes; returns 0 at the end; throws InputError on a decoding error.
  virtual std::size_t read(char* buf, std::size_t n) = 0;
};

namespace {
// gzip (any number of members, as `cat a.gz b.gz` gives) or a plain file. Inflated here rather than with
// gzread, which reads a stream cut off at a flush point, or without its trailer, as a shorter file without
// an error: a log must end with a complete member (CRC and length checked by zlib).
class GzSource : public CarmenReader::Source {
 public:
  explicit GzSource(const std::string& path) : path_(path), f_(std::fopen(path.c_str(), "rb")), in_(1 << 17) {
    if (!f_) throw InputError(path, 0, "cannot open log");
    gzip_ = fill() && zs_.avail_in >= 2 && in_[0] == 0x1f && in_[1] == 0x8b;
    if (gzip_ && inflateInit2(&zs_, 15 + 16) != Z_OK) {  // 16: gzip wrapper only
      std::fclose(f_);
      throw InputError(path, 0, "gzip: cannot start decoding");
    }
  }
  ~GzSource() override {
    if (gzip_) inflateEnd(&zs_);
    std::fclose(f_);
  }
  std::size_t read(char* buf, std::size_t n) override {
    const uInt want = static_cast<uInt>(std::min<std::size_t>(n, 1u << 30));
    if (!gzip_) {  // plain text: what was read to look for the magic first
      std::size_t got = std::min<std::size_t>(want, zs_.avail_in);
      std::memcpy(buf, zs_.next_in, got);
      zs_.next_in += got;
      zs_.avail_in -= static_cast<uInt>(got);
      if (got < want) {
        got += std::fread(buf + got, 1, want - got, f_);
        if (std::ferror(f_)) throw InputError(path_, 0, "read error");
      }
      return got;
    }
    zs_.next_out = reinterpret_cast<Bytef*>(buf);
    zs_.avail_out = want;
    while (zs_.avail_out == want) {
      if (member_done_) {
        // after a member: the end of the file (zero padding allowed, as gzip allows it) or another member
        for (;;) {
          if (zs_.avail_in == 0 && !fill()) return 0;
          if (*zs_.next_in != 0) break;
          ++zs_.next_in;
          --zs_.avail_in;
        }
        if (*zs_.next_in != 0x1f) throw InputError(path_, 0, "gzip: data after the end of the compressed stream");
        inflateReset(&zs_);
        member_done_ = false;
      }
      if (zs_.avail_in == 0 && !fill())
        throw InputError(path_, 0, "gzip: truncated data (the compressed stream ends before its end marker)");
      const int r = inflate(&zs_, Z_NO_FLUSH);
      if (r == Z_STREAM_END) member_done_ = true;
      else if (r != Z_OK && r != Z_BUF_ERROR)
        throw InputError(path_, 0, std::string("gzip: corrupt data") + (zs_.msg ? std::string(": ") + zs_.msg : ""));
    }
    return want - zs_.avail_out;
  }

 private:
  bool fill() {  // more compressed input; false at the end of the file
    const std::size_t got = std::fread(in_.data(), 1, in_.size(), f_);
    if (std::ferror(f_)) throw InputError(path_, 0, "read error");
    zs_.next_in = in_.data();
    zs_.avail_in = static_cast<uInt>(got);
    return got > 0;
  }

  std::string path_;
  FILE* f_;
  std::vector<Bytef> in_;
  z_stream zs_{};
  bool gzip_ = false, member_done_ = false;
};

#if CAIRN_SIM_HAVE_BZIP2
class Bz2Source : public CarmenReader::Source {
 public:
  explicit Bz2Source(const std::string& path) : path_(path), f_(std::fopen(path.c_str(), "rb")) {
    if (!f_) throw InputError(path, 0, "cannot open log");
    int err = 0;
    bz_ = BZ2_bzReadOpen(&err, f_, 0, 0, nullptr, 0);
    if (err != BZ_OK) {
      std::fclose(f_);
      throw InputError(path, 0, "bzip2: cannot start decoding");
    }
  }
  ~Bz2Source() override {
    int err = 0;
    BZ2_bzReadClose(&err, bz_);
    std::fclose(f_);
  }
  std::size_t read(char* buf, std::size_t n) override {
    while (!done_) {
      int err = 0;
      const int r = BZ2_bzRead(&err, bz_, buf, static_cast<int>(n));
      if (err == BZ_OK) return static_cast<std::size_t>(r);
      if (err != BZ_STREAM_END) throw InputError(path_, 0, "bzip2: corrupt or truncated data");
      // concatenated streams (pbzip2, `cat a.bz2 b.bz2`): continue with the unused bytes
      void* unused = nullptr;
      int nunused = 0;
      BZ2_bzReadGetUnused(&err, bz_, &unused, &nunused);
      std::vector<char> rest(static_cast<char*>(unused), static_cast<char*>(unused) + nunused);
      BZ2_bzReadClose(&err, bz_);
      if (rest.empty()) {
        const int c = std::fgetc(f_);
        if (c == EOF) done_ = true;
        else std::ungetc(c, f_);
      }
      if (!done_) {
        bz_ = BZ2_bzReadOpen(&err, f_, 0, 0, rest.empty() ? nullptr : rest.data(), static_cast<int>(rest.size()));
        if (err != BZ_OK) throw InputError(path_, 0, "bzip2: cannot continue decoding");
      } else {
        bz_ = BZ2_bzReadOpen(&err, f_, 0, 0, nullptr, 0);  // keeps the destructor valid
      }
      if (r > 0) return static_cast<std::size_t>(r);
    }
    return 0;
  }

 private:
  std::string path_;
  FILE* f_;
  BZFILE* bz_ = nullptr;
  bool done_ = false;
};
#endif
}  // namespace

CarmenReader::CarmenReader(const std::string& path, CarmenReaderOptions options) : path_(path), options_(std::move(options)) {
  FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) throw InputError(path, 0, "cannot open log");
  unsigned char magic[3] = {0, 0, 0};
  const std::size_t got = std::fread(magic, 1, 3, f);
  std::fclose(f);
  if (got == 3 && magic[0] == 'B' && magic[1] == 'Z' && magic[2] == 'h') {
#if CAIRN_SIM_HAVE_BZIP2
    source_ = std::make_unique<Bz2Source>(path);
#else
    throw InputError(path, 0, "bzip2-compressed log, but cairn_sim was built without bzip2 (install libbz2-dev)");
#endif
  } else {
    source_ = std::make_unique<GzSource>(path);
  }
}

CarmenReader::~CarmenReader() = default;

bool CarmenReader::readLine(std::string& line) {
  line.clear();
  for (;;) {
    if (buffer_pos_ >= buffer_.size()) {
      if (eof_) return !line.empty();
      buffer_.resize(1 << 16);
      const std::size_t n = source_->read(buffer_.data(), buffer_.size());
      buffer_.resize(n);
      buffer_pos_ = 0;
      if (n == 0) {
        eof_ = true;
        return !line.empty();
      }
    }
    const char* b = buffer_.data() + buffer_pos_;
    const std::size_t avail = buffer_.size() - buffer_pos_;
    const void* nl = std::memchr(b, '\n', avail);
    const std::size_t take = nl ? static_cast<std::size_t>(static_cast<const char*>(nl) - b) : avail;
    if (line.size() + take > options_.max_line_length) {
      // keep memory bounded: drop the rest of an over-long line but remember that it was too long
      line.resize(options_.max_line_length + 1, ' ');
    } else {
      line.append(b, take);
    }
    buffer_pos_ += take + (nl ? 1 : 0);
    if (nl) return true;
  }
}

bool CarmenReader::next(CarmenRecord& record) {
  std::string line, error;
  while (readLine(line)) {
    ++stats_.lines;
    CarmenLineStatus st;
    if (line.size() > options_.max_line_length) {
      st = CarmenLineStatus::Malformed;
      error = "line longer than " + std::to_string(options_.max_line_length) + " bytes";
    } else {
      st = parseCarmenLine(line, options_.layout, record, error);
    }
    if (st == CarmenLineStatus::Record) {
      if (std::holds_alternative<CarmenLaser>(record)) ++stats_.lasers;
      else ++stats_.odoms;
      return true;
    }
    if (st == CarmenLineStatus::Skipped) {
      ++stats_.skipped;
      continue;
    }
    InputError e(path_, static_cast<int>(stats_.lines), error);
    if (!options_.skip_malformed) throw e;
    ++stats_.malformed;
    if (options_.on_warning) options_.on_warning(e);
  }
  return false;
}

}  // namespace cairn::sim
