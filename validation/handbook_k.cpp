// Handbook K for through cracks at a central hole; formulas and sources in handbook_k.h and
// docs/handbook-k.md.
#include "validation/handbook_k.h"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace peritwin::validation {
namespace {

void require_non_negative_ratio(double c_over_r, const char* who) {
  if (!(c_over_r >= 0.0) || !std::isfinite(c_over_r))
    throw std::invalid_argument(std::string(who) + ": c/R must be finite and >= 0");
}

// Horner form of p0 + p1·λ + p2·λ² + p3·λ³ + p4·λ⁴.
double quartic(double l, double p0, double p1, double p2, double p3, double p4) {
  return p0 + l * (p1 + l * (p2 + l * (p3 + l * p4)));
}

}  // namespace

double newman_lambda(double c_over_r) {
  require_non_negative_ratio(c_over_r, "newman_lambda");
  return 1.0 / (1.0 + c_over_r);
}

double bowie_factor_two_cracks(double c_over_r) {
  // Newman & Raju (TM-85793), numerator of g2: 1 + 0.358λ + 1.425λ² − 1.578λ³ + 2.156λ⁴.
  return quartic(newman_lambda(c_over_r), 1.0, 0.358, 1.425, -1.578, 2.156);
}

double bowie_factor_one_crack(double c_over_r) {
  // DTD Handbook Sec. 11.3 eq. 2.12: 0.7071 + 0.7548λ + 0.3415λ² + 0.6420λ³ + 0.9196λ⁴.
  return quartic(newman_lambda(c_over_r), 0.7071, 0.7548, 0.3415, 0.6420, 0.9196);
}

double bowie_fit_paul_lombardo_two_cracks(double c_over_r) {
  require_non_negative_ratio(c_over_r, "bowie_fit_paul_lombardo_two_cracks");
  return 0.9439 + 0.6865 / (0.2772 + c_over_r);
}

double bowie_fit_paul_lombardo_one_crack(double c_over_r) {
  require_non_negative_ratio(c_over_r, "bowie_fit_paul_lombardo_one_crack");
  return 0.6762 + 0.8734 / (0.3246 + c_over_r);
}

double finite_width_factor_hole_cracks(double width, double hole_radius, double crack_length,
                                       bool two_cracks) {
  if (!(hole_radius > 0.0) || !(crack_length >= 0.0) || !(width > 0.0) || !std::isfinite(width) ||
      !(hole_radius + crack_length < 0.5 * width))
    throw std::invalid_argument(
        "finite_width_factor_hole_cracks: need R > 0, c >= 0, W > 0 and R + c < W/2");
  constexpr double pi = std::numbers::pi;
  const double n = two_cracks ? 2.0 : 1.0;
  const double b = 0.5 * width;
  const double hole_term = 1.0 / std::cos(pi * hole_radius / width);
  const double crack_term = 1.0 / std::cos(pi * (2.0 * hole_radius + n * crack_length) /
                                           (4.0 * (b - crack_length) + 2.0 * n * crack_length));
  return std::sqrt(hole_term * crack_term);
}

double k_crack_at_hole(double sigma, double width, double hole_radius, double crack_length,
                       bool two_cracks) {
  if (!(crack_length > 0.0))
    throw std::invalid_argument("k_crack_at_hole: the crack length must be > 0");
  const double fw = finite_width_factor_hole_cracks(width, hole_radius, crack_length, two_cracks);
  const double c_over_r = crack_length / hole_radius;
  const double f =
      two_cracks ? bowie_factor_two_cracks(c_over_r) : bowie_factor_one_crack(c_over_r);
  return sigma * std::sqrt(std::numbers::pi * crack_length) * f * fw;
}

}  // namespace peritwin::validation
