#include "cairn/data_files.hpp"

#include <cstdlib>
#include <sstream>
#include <stdexcept>

namespace cairn {

std::vector<std::filesystem::path> prefix_paths(const std::string& subpath) {
  std::vector<std::filesystem::path> out;
  for (const char* var : {"CMAKE_PREFIX_PATH", "COLCON_PREFIX_PATH"}) {
    const char* v = std::getenv(var);
    if (v == nullptr) continue;
    std::stringstream ss(v);
    std::string prefix;
    while (std::getline(ss, prefix, ':')) {
      if (!prefix.empty()) out.push_back(std::filesystem::path(prefix) / subpath);
    }
  }
  return out;
}

std::string first_existing_file(const std::vector<std::filesystem::path>& candidates, const std::string& what) {
  for (const auto& c : candidates) {
    std::error_code ec;
    if (std::filesystem::is_regular_file(c, ec)) return c.string();
  }
  std::string tried;
  for (const auto& c : candidates) tried += (tried.empty() ? "" : ", ") + c.string();
  throw std::invalid_argument(what + " not found (tried " + tried + ")");
}

}  // namespace cairn
