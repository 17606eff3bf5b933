// Conversion between ParameterValue and rcl_interfaces/msg/ParameterValue (parameter services, LoadNode).
#ifndef CAIRN_PARAMETER_MSGS_HPP
#define CAIRN_PARAMETER_MSGS_HPP

#include "cairn/parameters.hpp"
#include "rcl_interfaces/msg/ParameterValue.hpp"

namespace cairn {
rcl_interfaces::msg::ParameterValue to_parameter_msg(const ParameterValue& v);
ParameterValue from_parameter_msg(const rcl_interfaces::msg::ParameterValue& m);
}  // namespace cairn

#endif  // CAIRN_PARAMETER_MSGS_HPP
