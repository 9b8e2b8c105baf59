#include "solver/fatigue/laws/crack_closure.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

namespace peritwin::fatigue {

core::Status validate(const NewmanClosure& c) {
  std::string why;
  if (!(c.constraint >= 1.0 && c.constraint <= 3.0)) {
    why += "closure_constraint must be in [1, 3] (1 plane stress, 3 plane strain)";
  }
  if (!(c.smax_over_flow_stress > 0.0 && c.smax_over_flow_stress < 1.0)) {
    if (!why.empty()) why += "; ";
    why += "closure_smax_over_flow_stress must be in (0, 1)";
  }
  return why.empty() ? core::Status{} : core::Status{core::failure(why)};
}

double newman_opening_ratio(double load_ratio, const NewmanClosure& c) {
  const double a = c.constraint;
  const double s = c.smax_over_flow_stress;
  const double a0 =
      (0.825 - 0.34 * a + 0.05 * a * a) * std::pow(std::cos(std::numbers::pi * s / 2.0), 1.0 / a);
  const double a1 = (0.415 - 0.071 * a) * s;
  const double a3 = 2.0 * a0 + a1 - 1.0;
  const double a2 = 1.0 - a0 - a1 - a3;
  const double r = load_ratio;
  if (r >= 0.0) return std::max(r, a0 + r * (a1 + r * (a2 + r * a3)));
  return a0 + a1 * std::max(r, -2.0);
}

double newman_effective_range_fraction(double load_ratio, const NewmanClosure& c) {
  return (1.0 - newman_opening_ratio(load_ratio, c)) / (1.0 - load_ratio);
}

}  // namespace peritwin::fatigue
