// PNG pictures of a detail for people: the damage map (nodes rasterized on their grid, colormapped,
// white where there is no material; the annotated one with a title, axes in mm, a colour bar, the
// notches, the crack paths and the strain gauges) and the a-N plot (crack length against cycles
// with the remaining-life estimates), with axes, ticks, tick labels and legends. Drawn with cairo,
// the text set by pango in fontconfig's "Sans" (DejaVu Sans on Debian), the picture laid out by the
// measured size of its text; encoded by cairo's PNG writer and written atomically (temp file +
// rename). Each writer returns where it put things (boxes in pixels) so that a test can check the
// layout. Units: positions and dx in m, crack lengths in m (plotted in mm).
#pragma once

#include <cstdint>
#include <filesystem>
#include <limits>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

namespace peritwin::outputs {

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

/// A point of a polyline on the damage map (m).
struct MapPoint {
  double x = 0.0, y = 0.0;
};

/// A strain gauge on the damage map (config::GaugeConfig): drawn as a bar along its direction,
/// kGaugeColor with a black rim, at least kGaugeMinLengthDx·dx long (a point gauge shows), its id
/// beside it on a white plate inside the map (first of right, left, above, below of the bar that
/// covers no other gauge, label, notch or crack path; else the least covered, moved into the map).
struct MapGauge {
  std::string id;
  MapPoint at;          ///< centre of its measuring grid (m)
  double angle = 0.0;   ///< measuring direction from +x (rad)
  double length = 0.0;  ///< m
};
inline constexpr Rgb kGaugeColor{0, 200, 0};  ///< not a colour of damage_color nor notch_color
inline constexpr double kGaugeMinLengthDx = 3.0;

/// What the annotated damage map shows besides the damage.
struct DamageMap {
  std::string title;  ///< e.g. "b1-ct  N = 38373 cycles"
  /// φ per node from the notch cuts alone (the damage of the virgin detail), or empty. A node
  /// whose damage is all notch (φ ≤ notch φ + 1e-6) is drawn in grey (kNotchGrey scaled by φ),
  /// so the notch (φ ≈ 0.42 along its faces) and a grown crack (≈ 0.48) do not share a colour.
  std::vector<double> notch_damage;
  std::vector<std::vector<MapPoint>> notches;      ///< notch polylines, drawn black
  std::vector<std::vector<MapPoint>> crack_paths;  ///< crack tip tracks, drawn magenta
  std::vector<MapGauge> gauges;                    ///< strain gauges, drawn over the cracks
};

/// Grey of a notch-only node with damage φ: from light (φ = 0) to dark (φ = 1).
Rgb notch_color(double damage);

/// A rectangle of a picture in pixels: its top-left pixel and its size (row 0 on top).
struct Box {
  int left = 0, top = 0, width = 0, height = 0;
  [[nodiscard]] int right() const { return left + width; }
  [[nodiscard]] int bottom() const { return top + height; }
  /// Whether the two share a pixel.
  [[nodiscard]] bool overlaps(const Box& o) const {
    return left < o.right() && o.left < right() && top < o.bottom() && o.top < bottom();
  }
  /// Whether `o` lies inside this box.
  [[nodiscard]] bool contains(const Box& o) const {
    return o.left >= left && o.top >= top && o.right() <= right() && o.bottom() <= bottom();
  }
};

/// One entry of a legend: the sample of its line or colour, its text, and the box around both.
struct LegendEntry {
  std::string label;
  Box sample, text, box;
};

/// Where a picture's text went: the title, the axis titles, the tick labels and the legend.
struct PictureText {
  Box title;
  Box x_title, y_title;  ///< the y title reads upwards along the y axis
  std::vector<Box> x_tick_labels, y_tick_labels;
  std::vector<LegendEntry> legend;
};

/// Where a gauge went on the annotated map: its bar's end points (pixels of the picture, the
/// coloured core without its rim), the box around the bar with its rim, and its label's plate.
struct GaugeMark {
  std::string id;
  double x0 = 0.0, y0 = 0.0, x1 = 0.0, y1 = 0.0;
  Box bar, label;
};

/// Where the annotated map put things: the node raster (as write_damage_png) at (left, top).
struct DamageMapLayout {
  DamageImageLayout grid;  ///< its width and height are the raster's
  int left = 0, top = 0;   ///< the raster's top-left pixel in the picture
  int width = 0, height = 0;
  /// legend: the notch swatch (with notch damage), the crack path, the gauge (with gauges)
  PictureText text;
  Box colour_bar;  ///< φ = 1 on its top row, φ = 0 on its bottom row
  Box colour_bar_title;
  std::vector<Box> colour_bar_labels;  ///< "0.00" at the bottom to "1.00" at the top
  std::vector<GaugeMark> gauges;       ///< as DamageMap::gauges
};

/// The damage map with a title, axes in mm with ticks, a colour bar for φ (and a grey swatch for
/// the notch) and the notches, crack paths and gauges drawn over it.
DamageMapLayout write_damage_map_png(const std::filesystem::path& path, std::span<const double> x,
                                     std::span<const double> y, std::span<const double> damage,
                                     double dx, const DamageMap& map,
                                     const DamagePngOptions& options = {});

struct PlotOptions {
  int width = 800;
  int height = 500;
};

/// Where a plot put things: its size, the data rectangle (the frame) and the text.
struct PlotLayout {
  int width = 0, height = 0;
  Box frame;
  PictureText text;
};

/// Crack length (m, drawn in mm) against cycles; non-finite points break the line.
PlotLayout write_crack_length_png(const std::filesystem::path& path, std::span<const double> cycles,
                                  std::span<const double> lengths_m,
                                  const PlotOptions& options = {});

/// A remaining-life estimate made at a state with `cycles` applied and a crack of `length_m`.
struct LifePrediction {
  double cycles = 0.0;
  double length_m = 0.0;
  double remaining = 0.0;                                 ///< cycles to the end of life (central)
  double low = std::numeric_limits<double>::quiet_NaN();  ///< band, NaN: none
  double high = std::numeric_limits<double>::quiet_NaN();
};

/// The a-N plot: crack length against cycles and, for every estimate, the predicted end of life
/// N + remaining as a diamond at the crack length of the state it was made on, with its band
/// [N + low, N + high] as a horizontal bar; the latest prediction as a dashed vertical line; the
/// critical crack length (if finite) as a dashed horizontal line; the end of life, if reached.
struct CrackGrowthPlot {
  std::string title;
  std::vector<double> cycles;               ///< per state
  std::vector<double> lengths_m;            ///< per state
  std::vector<LifePrediction> predictions;  ///< in the order made; non-finite ones are skipped
  double critical_length_m = std::numeric_limits<double>::quiet_NaN();
  std::int64_t end_of_life_cycle = -1;  ///< >= 0: the twin reached its end of life there
};
/// The legend (its entries in this order, as many rows as their measured widths need, above the
/// frame): "crack length", "predicted end (band)" (if there is an estimate), "critical" (if
/// finite), "end of life" (if reached).
PlotLayout write_crack_growth_png(const std::filesystem::path& path, const CrackGrowthPlot& plot,
                                  const PlotOptions& options = {});

/// One curve of a line plot: its points, legend text, colour and whether it is dashed.
struct PlotSeries {
  std::string label;
  std::vector<double> x, y;  ///< same size; a non-finite point breaks the line
  Rgb color{31, 90, 180};
  bool dashed = false;
};

/// A generic x-y line plot (validation figures: K(t) against Freund, ε(t) against the exact
/// solution, ω(k) curves): a title, axis titles, 1-2-5 axes over the data (or the given range when
/// y_lo < y_hi), a legend with one entry per series (rows as their measured widths need).
struct LinePlot {
  std::string title, x_title, y_title;
  std::vector<PlotSeries> series;
  double y_lo = 0.0, y_hi = 0.0;  ///< y_lo < y_hi: fixed y range
};
PlotLayout write_line_plot_png(const std::filesystem::path& path, const LinePlot& plot,
                               const PlotOptions& options = {});

}  // namespace peritwin::outputs
