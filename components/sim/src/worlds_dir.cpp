#include <cstdlib>
#include <filesystem>

#include "cairn/sim/world.hpp"

namespace cairn::sim {

namespace {
std::vector<std::string> worldDirs() {
  std::vector<std::string> dirs;
  if (const char* env = std::getenv("CAIRN_SIM_WORLDS")) dirs.emplace_back(env);
  dirs.emplace_back(CAIRN_SIM_WORLDS_SOURCE_DIR);
  dirs.emplace_back(CAIRN_SIM_WORLDS_INSTALL_DIR);
  return dirs;
}
}  // namespace

std::string resolveWorldPath(const std::string& name_or_path) {
  namespace fs = std::filesystem;
  if (fs::is_regular_file(name_or_path)) return name_or_path;
  for (const auto& d : worldDirs()) {
    const fs::path p = fs::path(d) / (name_or_path + ".yaml");
    if (fs::is_regular_file(p)) return p.string();
  }
  throw InputError(name_or_path, 0, "no such world (not a file, and not a shipped world name)");
}

std::vector<std::string> shippedWorlds() { return {"office", "apartment", "warehouse"}; }

}  // namespace cairn::sim
