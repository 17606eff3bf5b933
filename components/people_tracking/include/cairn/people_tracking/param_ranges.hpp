// Valid ranges of the numeric parameters of the core's parameter structs (SegmentationParams, DetectorParams,
// TrackerParams, FusionParams, GuideParams, MaskParams), by the name the component declares them under
// ("tracker.process_noise"). One table: the component's parameter descriptors and the `cairn people` options that
// set the same fields both check against it.
#pragma once

#include <string>
#include <string_view>

namespace cairn::people_tracking {

struct ParamRange {
  double lo = 0.0;
  double hi = 0.0;
};

// The range of parameter `name`; std::out_of_range for a name that is not in the table (a programming error).
ParamRange paramRange(std::string_view name);

// A number in %g form ("1e+09", "0.25"), for messages.
std::string numberText(double x);

// "[lo, hi]" in numberText form.
std::string rangeText(const ParamRange& r);

}  // namespace cairn::people_tracking
