// The tunable parameters of GraphSlam as one flat, named table: the `cairn slam run --config` YAML keys and the
// component's typed parameters are both this table, so names, types, defaults and documentation are defined once.
#pragma once

#include <functional>
#include <string>
#include <variant>
#include <vector>

#include "cairn/graph_slam/slam.hpp"

namespace cairn::graph_slam {

using SlamParamRef = std::variant<double*, int*, bool*, std::string*>;

struct SlamParam {
  std::string name;         ///< e.g. "r_min", "filter.max_range"
  std::string description;  ///< one line, with the seed reference where there is one
  std::function<SlamParamRef(SlamOptions&)> ref;
  double min = -1e300;      ///< numeric parameters: allowed range (inclusive)
  double max = 1e300;
};

/// All parameters, in documentation order.
const std::vector<SlamParam>& slamParameters();
/// The parameter of that name, or nullptr.
const SlamParam* findSlamParameter(const std::string& name);
/// Sets a parameter from text ("0.25", "true", "42", a path). Throws std::invalid_argument
/// "<name>: <what>" for unknown names, unparsable values or values outside the range.
void setSlamParameter(SlamOptions& options, const std::string& name, const std::string& value);
/// Current value as text (for --help / dumps).
std::string slamParameterText(const SlamOptions& options, const SlamParam& param);

}  // namespace cairn::graph_slam
