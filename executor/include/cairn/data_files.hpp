// Finding a package's data files (models, behavior trees, worlds) in the working directory, the install
// prefixes ($CMAKE_PREFIX_PATH, $COLCON_PREFIX_PATH) and the build/source tree.
#ifndef CAIRN_DATA_FILES_HPP
#define CAIRN_DATA_FILES_HPP

#include <filesystem>
#include <string>
#include <vector>

namespace cairn {

/// <prefix>/<subpath> for every prefix in $CMAKE_PREFIX_PATH and $COLCON_PREFIX_PATH, in that order.
std::vector<std::filesystem::path> prefix_paths(const std::string& subpath);

/// The first candidate that is a regular file. Throws std::invalid_argument
/// "<what> not found (tried a, b, c)" when none is.
std::string first_existing_file(const std::vector<std::filesystem::path>& candidates, const std::string& what);

}  // namespace cairn

#endif  // CAIRN_DATA_FILES_HPP
