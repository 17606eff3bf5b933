#include "cairn/graph_slam/robust_kernel.hpp"

#include <cmath>
#include <stdexcept>

#include "cairn/strict_number.hpp"

namespace cairn::graph_slam {

void RobustKernel::evaluate(double s, double& rho, double& drho) const {
  const double d2 = delta * delta;
  switch (type) {
    case Type::kNone:
      rho = s;
      drho = 1.0;
      return;
    case Type::kHuber:
      // rho(s) = s for s <= delta^2, else 2 delta sqrt(s) - delta^2.
      if (s <= d2) {
        rho = s;
        drho = 1.0;
      } else {
        const double r = std::sqrt(s);
        rho = 2.0 * delta * r - d2;
        drho = delta / r;
      }
      return;
    case Type::kCauchy:
      // rho(s) = delta^2 log(1 + s / delta^2).
      rho = d2 * std::log1p(s / d2);
      drho = 1.0 / (1.0 + s / d2);
      return;
    case Type::kGemanMcClure: {
      // rho(s) = delta^2 s / (delta^2 + s).
      const double den = d2 + s;
      rho = d2 * s / den;
      drho = d2 * d2 / (den * den);
      return;
    }
    case Type::kDcs: {
      // Dynamic covariance scaling (Agarwal et al. 2013) scales the error by
      // min(1, 2 Phi / (Phi + s)), i.e. IRLS weight w(s) = min(1, 4 Phi^2 / (Phi + s)^2). Its cost is the
      // integral of w: rho(s) = s for s <= Phi, else 3 Phi - 4 Phi^2 / (Phi + s) (continuous, C1).
      const double phi = delta;
      if (s <= phi) {
        rho = s;
        drho = 1.0;
      } else {
        const double den = phi + s;
        rho = 3.0 * phi - 4.0 * phi * phi / den;
        drho = 4.0 * phi * phi / (den * den);
      }
      return;
    }
  }
  rho = s;
  drho = 1.0;
}

RobustKernel RobustKernel::parse(std::string_view text) {
  RobustKernel k;
  const auto colon = text.find(':');
  const std::string_view name = text.substr(0, colon);
  if (name == "none" && colon == std::string_view::npos) return k;
  if (name == "huber") {
    k.type = Type::kHuber;
  } else if (name == "cauchy") {
    k.type = Type::kCauchy;
  } else if (name == "gm" || name == "geman_mcclure" || name == "geman-mcclure") {
    k.type = Type::kGemanMcClure;
  } else if (name == "dcs") {
    k.type = Type::kDcs;
  } else {
    throw std::invalid_argument("unknown robust kernel '" + std::string(name) +
                                "' (expected none, huber, cauchy, gm or dcs)");
  }
  if (colon != std::string_view::npos) {
    const std::string_view value = text.substr(colon + 1);
    const auto parsed = strict_number::parse_finite(value);
    const double d = parsed.value_or(0.0);
    if (!(d > 0.0)) {
      throw std::invalid_argument("robust kernel parameter must be a positive number, got '" +
                                  std::string(value) + "'");
    }
    k.delta = d;
  }
  return k;
}

std::string RobustKernel::toString() const {
  switch (type) {
    case Type::kNone: return "none";
    case Type::kHuber: return "huber:" + std::to_string(delta);
    case Type::kCauchy: return "cauchy:" + std::to_string(delta);
    case Type::kGemanMcClure: return "gm:" + std::to_string(delta);
    case Type::kDcs: return "dcs:" + std::to_string(delta);
  }
  return "none";
}

}  // namespace cairn::graph_slam
