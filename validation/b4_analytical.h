#pragma once
namespace peritwin::validation {
/// B4: closed-form checks of the fatigue laws and the rainflow counter, one JSON line each.
int run_b4();
}  // namespace peritwin::validation
