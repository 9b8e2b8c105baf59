// PNG pictures of a detail for people: the damage map (nodes rasterized on their grid, colormapped,
// white where there is no material) and a crack-length-versus-cycles line plot with axes, ticks and
// numeric tick labels (a built-in 5x7 bitmap font). Encoded with libpng's simplified API and
// written atomically (temp file + rename). Units: positions and dx in m, crack lengths in m
// (plotted in mm).
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <stdexcept>

namespace peritwin::twin {

struct Rgb {
  std::uint8_t r = 0, g = 0, b = 0;
  bool operator==(const Rgb&) const = default;
};

/// Blue (φ = 0) -> teal (0.25) -> yellow (0.5) -> orange (0.75) -> red (φ = 1), linear in
/// between, clamped to [0, 1]; NaN is grey.
Rgb damage_color(double damage);

struct DamagePngOptions {
  int target_pixels = 800;  ///< the longer side of the grid spans about this many pixels
  int min_node_pixels = 2;  ///< a node is never drawn smaller than this square
};

/// Where the nodes landed: node (x, y) fills the square of `node_pixels` starting at pixel column
/// round((x - x_min)/dx)·node_pixels and row round((y_max - y)/dx)·node_pixels (row 0 on top).
struct DamageImageLayout {
  int width = 0, height = 0;  ///< = columns·node_pixels, rows·node_pixels
  int columns = 0, rows = 0;
  int node_pixels = 0;  ///< max(min_node_pixels, target_pixels / max(columns, rows))
  double x_min = 0.0, y_max = 0.0;
};

/// Thrown for bad input (sizes, dx, an image that would be absurdly large) and encoder failures;
/// file system failures arrive as std::system_error.
class PngError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

DamageImageLayout write_damage_png(const std::filesystem::path& path, std::span<const double> x,
                                   std::span<const double> y, std::span<const double> damage,
                                   double dx, const DamagePngOptions& options = {});

struct PlotOptions {
  int width = 800;
  int height = 500;
};

/// Crack length (m, drawn in mm) against cycles; non-finite points break the line.
void write_crack_length_png(const std::filesystem::path& path, std::span<const double> cycles,
                            std::span<const double> lengths_m, const PlotOptions& options = {});

}  // namespace peritwin::twin
