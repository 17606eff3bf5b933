// Seeded, platform-independent random numbers. std::normal_distribution differs between standard
// libraries, so the simulator uses its own generator (xoshiro256** seeded by splitmix64) and its own
// Gaussian (Marsaglia polar method): the same seed gives the same stream everywhere.
#pragma once

#include <cstdint>

namespace cairn::sim {

class Rng {
 public:
  explicit Rng(std::uint64_t seed = 1);
  std::uint64_t next();
  /// Uniform in [0, 1).
  double uniform();
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  /// Standard normal N(0, 1).
  double gaussian();
  double gaussian(double mean, double sigma) { return mean + sigma * gaussian(); }
  /// Poisson-distributed count with the given mean (Knuth for small means, normal approximation above 30).
  int poisson(double mean);
  /// Derives an independent generator (for sub-systems that must not disturb each other's streams).
  Rng fork(std::uint64_t stream_id) const;

 private:
  std::uint64_t s_[4];
  bool have_spare_ = false;
  double spare_ = 0.0;
  std::uint64_t seed_ = 0;
};

}  // namespace cairn::sim
