// peritwin-validate's dynamics cases (paper 001): D1 bar, D2 dispersion, D3 semi-infinite crack,
// D4 mode II plate. Each prints JSON lines and writes CSV and PNG files under `out`.
#pragma once

#include <filesystem>

namespace peritwin::validation {
int run_d1(const std::filesystem::path& out, int threads);
int run_d2(const std::filesystem::path& out);
int run_d3(const std::filesystem::path& out, int threads);
/// dx <= 0: the paper's 0.26 mm.
int run_d4(const std::filesystem::path& out, int threads, double dx);
}  // namespace peritwin::validation
