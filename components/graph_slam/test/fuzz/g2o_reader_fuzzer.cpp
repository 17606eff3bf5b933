// libFuzzer target for the g2o reader (build with -DCAIRN_BUILD_FUZZERS=ON and clang):
//   cairn_g2o_fuzzer components/graph_slam/test/fuzz/g2o/
// Oracle: the reader either throws G2oError or returns a graph that the writer can write and the reader can
// read back to the same structure and chi2 (the same options for both reads).
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <sstream>
#include <string>

#include "cairn/graph_slam/g2o_io.hpp"

namespace gs = cairn::graph_slam;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  gs::G2oReadOptions opt;
  // First byte selects the reader options, the rest is the file.
  if (data[0] & 1) opt.information_fix = gs::G2oReadOptions::InformationFix::kClamp;
  if (data[0] & 2) opt.skip_unknown_tags = true;
  std::istringstream in(std::string(reinterpret_cast<const char*>(data + 1), size - 1));
  gs::PoseGraph g;
  gs::G2oReadReport report;
  try {
    g = gs::readG2o(in, "fuzz.g2o", opt, &report);
  } catch (const gs::G2oError&) {
    return 0;
  }
  std::stringstream out;
  gs::writeG2o(g, out);  // every tag the reader accepts can be written
  gs::PoseGraph h;
  try {
    h = gs::readG2o(out, "roundtrip.g2o", opt);
  } catch (const gs::G2oError& e) {
    std::fprintf(stderr, "round trip failed: %s\n", e.what());
    std::abort();
  }
  if (h.variables().size() != g.variables().size() || h.factors().size() != g.factors().size()) std::abort();
  const double a = g.chi2(), b = h.chi2();
  if (std::isfinite(a) && std::isfinite(b) && std::abs(a - b) > 1e-9 * std::max(1.0, std::abs(a))) std::abort();
  return 0;
}
