#include "outputs/damage_png.h"

#include <png.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <string>
#include <string_view>
#include <vector>

#include "outputs/checkpoint_io.h"

namespace peritwin::outputs {

namespace {

constexpr Rgb kWhite{255, 255, 255};
constexpr Rgb kBlack{0, 0, 0};
constexpr Rgb kGrid{225, 225, 225};
constexpr Rgb kLine{31, 90, 180};
constexpr int kMaxSide = 32768;

/// An 8-bit RGB raster, row 0 on top.
struct Image {
  int width, height;
  std::vector<std::uint8_t> rgb;
  Image(int w, int h, Rgb fill) : width(w), height(h), rgb(3 * std::size_t(w) * std::size_t(h)) {
    for (std::size_t i = 0; i < rgb.size(); i += 3) {
      rgb[i] = fill.r;
      rgb[i + 1] = fill.g;
      rgb[i + 2] = fill.b;
    }
  }
  void set(int x, int y, Rgb c) {
    if (x < 0 || y < 0 || x >= width || y >= height) return;
    const std::size_t i = 3 * (std::size_t(y) * std::size_t(width) + std::size_t(x));
    rgb[i] = c.r;
    rgb[i + 1] = c.g;
    rgb[i + 2] = c.b;
  }
  void fill(int x0, int y0, int w, int h, Rgb c) {
    for (int y = y0; y < y0 + h; ++y) {
      for (int x = x0; x < x0 + w; ++x) set(x, y, c);
    }
  }
};

/// libpng's simplified write API (no setjmp); png_image_free releases what it holds on any path.
class PngImage {
 public:
  PngImage(int width, int height) {
    image_.version = PNG_IMAGE_VERSION;
    image_.width = static_cast<png_uint_32>(width);
    image_.height = static_cast<png_uint_32>(height);
    image_.format = PNG_FORMAT_RGB;
  }
  ~PngImage() { png_image_free(&image_); }
  PngImage(const PngImage&) = delete;
  PngImage& operator=(const PngImage&) = delete;

  std::string encode(const Image& img) {
    const auto stride = static_cast<png_int_32>(3 * img.width);
    png_alloc_size_t size = 0;
    if (png_image_write_to_memory(&image_, nullptr, &size, 0, img.rgb.data(), stride, nullptr) ==
        0) {
      throw PngError(std::string("libpng: ") + image_.message);
    }
    std::string bytes(size, '\0');
    if (png_image_write_to_memory(&image_, bytes.data(), &size, 0, img.rgb.data(), stride,
                                  nullptr) == 0) {
      throw PngError(std::string("libpng: ") + image_.message);
    }
    bytes.resize(size);
    return bytes;
  }

 private:
  png_image image_{};
};

void save(const std::filesystem::path& path, const Image& img) {
  PngImage png(img.width, img.height);
  write_file_atomically(path, png.encode(img), false);
}

// --- 5x7 bitmap font: rows top to bottom, bit 4 = leftmost column ---------------------------

struct Glyph {
  char c;
  std::array<std::uint8_t, 7> rows;
};

constexpr std::array<Glyph, 51> kFont{{
    {'0', {0x0E, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0E}},
    {'1', {0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E}},
    {'2', {0x0E, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1F}},
    {'3', {0x1F, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0E}},
    {'4', {0x02, 0x06, 0x0A, 0x12, 0x1F, 0x02, 0x02}},
    {'5', {0x1F, 0x10, 0x1E, 0x01, 0x01, 0x11, 0x0E}},
    {'6', {0x06, 0x08, 0x10, 0x1E, 0x11, 0x11, 0x0E}},
    {'7', {0x1F, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08}},
    {'8', {0x0E, 0x11, 0x11, 0x0E, 0x11, 0x11, 0x0E}},
    {'9', {0x0E, 0x11, 0x11, 0x0F, 0x01, 0x02, 0x0C}},
    {'.', {0x00, 0x00, 0x00, 0x00, 0x00, 0x0C, 0x0C}},
    {'-', {0x00, 0x00, 0x00, 0x1F, 0x00, 0x00, 0x00}},
    {'+', {0x00, 0x04, 0x04, 0x1F, 0x04, 0x04, 0x00}},
    {'e', {0x00, 0x00, 0x0E, 0x11, 0x1F, 0x10, 0x0E}},
    {'c', {0x00, 0x00, 0x0E, 0x10, 0x10, 0x11, 0x0E}},
    {'y', {0x00, 0x00, 0x11, 0x11, 0x0F, 0x01, 0x0E}},
    {'l', {0x0C, 0x04, 0x04, 0x04, 0x04, 0x04, 0x0E}},
    {'s', {0x00, 0x00, 0x0E, 0x10, 0x0E, 0x01, 0x1E}},
    {'r', {0x00, 0x00, 0x16, 0x19, 0x10, 0x10, 0x10}},
    {'a', {0x00, 0x00, 0x0E, 0x01, 0x0F, 0x11, 0x0F}},
    {'k', {0x10, 0x10, 0x12, 0x14, 0x18, 0x14, 0x12}},
    {'n', {0x00, 0x00, 0x16, 0x19, 0x11, 0x11, 0x11}},
    {'g', {0x00, 0x00, 0x0F, 0x11, 0x0F, 0x01, 0x0E}},
    {'t', {0x08, 0x08, 0x1C, 0x08, 0x08, 0x09, 0x06}},
    {'h', {0x10, 0x10, 0x16, 0x19, 0x11, 0x11, 0x11}},
    {'m', {0x00, 0x00, 0x1A, 0x15, 0x15, 0x11, 0x11}},
    {'[', {0x0E, 0x08, 0x08, 0x08, 0x08, 0x08, 0x0E}},
    {']', {0x0E, 0x02, 0x02, 0x02, 0x02, 0x02, 0x0E}},
    {' ', {0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00}},
    {'b', {0x10, 0x10, 0x16, 0x19, 0x11, 0x11, 0x1E}},
    {'d', {0x01, 0x01, 0x0D, 0x13, 0x11, 0x11, 0x0F}},
    {'f', {0x06, 0x09, 0x08, 0x1C, 0x08, 0x08, 0x08}},
    {'i', {0x04, 0x00, 0x0C, 0x04, 0x04, 0x04, 0x0E}},
    {'j', {0x02, 0x00, 0x06, 0x02, 0x02, 0x12, 0x0C}},
    {'o', {0x00, 0x00, 0x0E, 0x11, 0x11, 0x11, 0x0E}},
    {'p', {0x00, 0x00, 0x1E, 0x11, 0x1E, 0x10, 0x10}},
    {'q', {0x00, 0x00, 0x0D, 0x13, 0x0F, 0x01, 0x01}},
    {'u', {0x00, 0x00, 0x11, 0x11, 0x11, 0x13, 0x0D}},
    {'v', {0x00, 0x00, 0x11, 0x11, 0x11, 0x0A, 0x04}},
    {'w', {0x00, 0x00, 0x11, 0x11, 0x15, 0x15, 0x0A}},
    {'x', {0x00, 0x00, 0x11, 0x0A, 0x04, 0x0A, 0x11}},
    {'z', {0x00, 0x00, 0x1F, 0x02, 0x04, 0x08, 0x1F}},
    {'N', {0x11, 0x11, 0x19, 0x15, 0x13, 0x11, 0x11}},
    {'=', {0x00, 0x00, 0x1F, 0x00, 0x1F, 0x00, 0x00}},
    {':', {0x00, 0x0C, 0x0C, 0x00, 0x0C, 0x0C, 0x00}},
    {'(', {0x02, 0x04, 0x08, 0x08, 0x08, 0x04, 0x02}},
    {')', {0x08, 0x04, 0x02, 0x02, 0x02, 0x04, 0x08}},
    {'/', {0x00, 0x01, 0x02, 0x04, 0x08, 0x10, 0x00}},
    {',', {0x00, 0x00, 0x00, 0x00, 0x0C, 0x04, 0x08}},
    {'_', {0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x1F}},
    {'%', {0x18, 0x19, 0x02, 0x04, 0x08, 0x13, 0x03}},
}};

constexpr int kGlyphAdvance = 6;  // 5 columns + 1 of spacing

int text_width(std::string_view s, int scale) {
  return s.empty() ? 0 : (static_cast<int>(s.size()) * kGlyphAdvance - 1) * scale;
}

/// Draws `s` with its top-left corner at (x, y); characters without a glyph are left blank.
/// An upper-case letter without a glyph of its own is drawn as its lower case.
void draw_text(Image& img, int x, int y, std::string_view s, int scale, Rgb color) {
  for (const char ch : s) {
    auto it = std::find_if(kFont.begin(), kFont.end(), [ch](const Glyph& g) { return g.c == ch; });
    if (it == kFont.end() && ch >= 'A' && ch <= 'Z') {
      const char lower = static_cast<char>(ch - 'A' + 'a');
      it = std::find_if(kFont.begin(), kFont.end(),
                        [lower](const Glyph& g) { return g.c == lower; });
    }
    if (it != kFont.end()) {
      for (int r = 0; r < 7; ++r) {
        for (int c = 0; c < 5; ++c) {
          if ((it->rows[static_cast<std::size_t>(r)] >> (4 - c)) & 1) {
            img.fill(x + c * scale, y + r * scale, scale, scale, color);
          }
        }
      }
    }
    x += kGlyphAdvance * scale;
  }
}

/// Bresenham with a square pen of `pen` pixels.
void draw_line(Image& img, int x0, int y0, int x1, int y1, int pen, Rgb color) {
  const int dx = std::abs(x1 - x0), sx = x0 < x1 ? 1 : -1;
  const int dy = -std::abs(y1 - y0), sy = y0 < y1 ? 1 : -1;
  int err = dx + dy;
  while (true) {
    img.fill(x0 - pen / 2, y0 - pen / 2, pen, pen, color);
    if (x0 == x1 && y0 == y1) break;
    const int e2 = 2 * err;
    if (e2 >= dy) {
      err += dy;
      x0 += sx;
    }
    if (e2 <= dx) {
      err += dx;
      y0 += sy;
    }
  }
}

/// A 1-2-5 step giving about `target` intervals over [lo, hi].
double nice_step(double lo, double hi, int target) {
  const double raw = (hi - lo) / target;
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  const double f = raw / mag;
  return (f <= 1.0 ? 1.0 : f <= 2.0 ? 2.0 : f <= 5.0 ? 5.0 : 10.0) * mag;
}

struct Axis {
  double lo, hi, step;
};

/// An axis over [lo, hi] stretched to multiples of a 1-2-5 step (the a-N plot).
Axis nice_axis(double lo, double hi) {
  if (!(hi > lo)) hi = lo + 1.0;
  const double step = nice_step(lo, hi, 5);
  return {std::floor(lo / step + 1e-9) * step, std::ceil(hi / step - 1e-9) * step, step};
}

/// An axis over exactly [lo, hi] with a 1-2-5 step for its ticks (the damage map's extent).
Axis exact_axis(double lo, double hi, int target) {
  if (!(hi > lo)) hi = lo + 1.0;
  return {lo, hi, nice_step(lo, hi, target)};
}

/// The multiples of axis.step inside [lo, hi].
std::vector<double> ticks(const Axis& axis) {
  std::vector<double> out;
  const double eps = 1e-9 * axis.step;
  for (double k = std::ceil((axis.lo - eps) / axis.step); k * axis.step <= axis.hi + eps;
       k += 1.0) {
    out.push_back(k * axis.step);
  }
  return out;
}

/// The data rectangle of a plot in pixels and the ranges it maps (y up).
struct Frame {
  int left, top, width, height;
  Axis x, y;
  [[nodiscard]] int px(double v) const {
    return left + static_cast<int>(std::lround((v - x.lo) / (x.hi - x.lo) * width));
  }
  [[nodiscard]] int py(double v) const {
    return top + height - static_cast<int>(std::lround((v - y.lo) / (y.hi - y.lo) * height));
  }
};

constexpr int kScale = 2;  // font scale: 10 x 14 pixel glyphs
constexpr int kGlyphHeight = 7 * kScale;

std::string tick_label(double v, const Axis& axis);

/// Ticks with labels below and left of the frame, axis titles, and (with `grid`) grid lines
/// across it; the frame's border in black.
void draw_frame(Image& img, const Frame& f, std::string_view x_title, std::string_view y_title,
                bool grid) {
  for (const double v : ticks(f.x)) {
    const int p = f.px(v);
    if (grid) draw_line(img, p, f.top, p, f.top + f.height, 1, kGrid);
    draw_line(img, p, f.top + f.height, p, f.top + f.height + 6, 1, kBlack);
    const std::string label = tick_label(v, f.x);
    draw_text(img, p - text_width(label, kScale) / 2, f.top + f.height + 10, label, kScale, kBlack);
  }
  for (const double v : ticks(f.y)) {
    const int p = f.py(v);
    if (grid) draw_line(img, f.left, p, f.left + f.width, p, 1, kGrid);
    draw_line(img, f.left - 6, p, f.left, p, 1, kBlack);
    const std::string label = tick_label(v, f.y);
    draw_text(img, f.left - 10 - text_width(label, kScale), p - kGlyphHeight / 2, label, kScale,
              kBlack);
  }
  const int right = f.left + f.width, bottom = f.top + f.height;
  draw_line(img, f.left, f.top, f.left, bottom, 2, kBlack);
  draw_line(img, f.left, bottom, right, bottom, 2, kBlack);
  if (!grid) {  // a map: a closed box
    draw_line(img, f.left, f.top, right, f.top, 1, kBlack);
    draw_line(img, right, f.top, right, bottom, 1, kBlack);
  }
  draw_text(img, f.left + f.width / 2 - text_width(x_title, kScale) / 2, bottom + 20 + kGlyphHeight,
            x_title, kScale, kBlack);
  draw_text(img, f.left - text_width("-0.0", kScale), f.top - kGlyphHeight - 18, y_title, kScale,
            kBlack);
}

/// A dashed line (dash and gap of `dash` pixels).
void draw_dashed_line(Image& img, int x0, int y0, int x1, int y1, int pen, int dash, Rgb color) {
  const double length = std::hypot(x1 - x0, y1 - y0);
  const int pieces = std::max(1, static_cast<int>(length / dash));
  for (int k = 0; k < pieces; k += 2) {
    const double a = static_cast<double>(k) / pieces, b = static_cast<double>(k + 1) / pieces;
    draw_line(img, x0 + static_cast<int>(std::lround(a * (x1 - x0))),
              y0 + static_cast<int>(std::lround(a * (y1 - y0))),
              x0 + static_cast<int>(std::lround(b * (x1 - x0))),
              y0 + static_cast<int>(std::lround(b * (y1 - y0))), pen, color);
  }
}

/// Tick labels of one axis share a format: fixed with the decimals the step needs, or, for
/// |v| >= 1e6 (or tiny values), %.3g with a short exponent ("1.5e+06" -> "1.5e6").
std::string tick_label(double v, const Axis& axis) {
  if (std::abs(v) < 1e-9 * axis.step) v = 0.0;
  const double big = std::max(std::abs(axis.lo), std::abs(axis.hi));
  char buf[40];
  if (big < 1e6 && axis.step >= 1e-4) {
    const int decimals = std::max(0, -static_cast<int>(std::floor(std::log10(axis.step) + 1e-9)));
    std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
    return buf;
  }
  std::snprintf(buf, sizeof buf, "%.3g", v);
  std::string s = buf;
  const auto e = s.find('e');
  if (e != std::string::npos) {
    std::string mant = s.substr(0, e), exp = s.substr(e + 1);
    const bool neg = exp[0] == '-';
    exp = exp.substr(1);
    exp.erase(0, std::min(exp.find_first_not_of('0'), exp.size() - 1));
    s = mant + "e" + (neg ? "-" : "") + exp;
  }
  return s;
}

}  // namespace

Rgb damage_color(double damage) {
  if (std::isnan(damage)) return {128, 128, 128};
  const double t = std::clamp(damage, 0.0, 1.0);
  // Through teal and orange rather than straight lines, which would pass through grey.
  constexpr std::array<std::array<double, 3>, 5> stops{
      {{40, 60, 190}, {30, 160, 180}, {250, 220, 40}, {240, 130, 30}, {200, 20, 20}}};
  const auto k = std::min<std::size_t>(static_cast<std::size_t>(t * 4.0), 3);
  const double u = t * 4.0 - static_cast<double>(k);
  auto mix = [&](std::size_t ch) {
    return static_cast<std::uint8_t>(
        std::lround(stops[k][ch] + u * (stops[k + 1][ch] - stops[k][ch])));
  };
  return {mix(0), mix(1), mix(2)};
}

namespace {

/// The grid the nodes sit on and the raster size (see DamageImageLayout); checks the input.
DamageImageLayout grid_layout(std::span<const double> x, std::span<const double> y,
                              std::span<const double> damage, double dx,
                              const DamagePngOptions& options) {
  if (x.size() != y.size() || x.size() != damage.size() || x.empty()) {
    throw PngError("write_damage_png: x, y and damage must be non-empty and of equal size");
  }
  if (!(dx > 0.0) || !std::isfinite(dx)) throw PngError("write_damage_png: dx must be positive");
  double x_min = x[0], x_max = x[0], y_min = y[0], y_max = y[0];
  for (std::size_t i = 0; i < x.size(); ++i) {
    if (!std::isfinite(x[i]) || !std::isfinite(y[i])) {
      throw PngError("write_damage_png: node " + std::to_string(i) + " has a non-finite position");
    }
    x_min = std::min(x_min, x[i]);
    x_max = std::max(x_max, x[i]);
    y_min = std::min(y_min, y[i]);
    y_max = std::max(y_max, y[i]);
  }
  const double cols = std::round((x_max - x_min) / dx) + 1.0;
  const double rows = std::round((y_max - y_min) / dx) + 1.0;
  if (cols > kMaxSide || rows > kMaxSide) {
    throw PngError("write_damage_png: the grid (" + std::to_string(cols) + " x " +
                   std::to_string(rows) + " nodes) is too large for an image; is dx right?");
  }
  DamageImageLayout layout;
  layout.columns = static_cast<int>(cols);
  layout.rows = static_cast<int>(rows);
  layout.node_pixels = std::max(options.min_node_pixels,
                                options.target_pixels / std::max(layout.columns, layout.rows));
  layout.width = layout.columns * layout.node_pixels;
  layout.height = layout.rows * layout.node_pixels;
  layout.x_min = x_min;
  layout.y_max = y_max;
  if (layout.width > kMaxSide || layout.height > kMaxSide) {
    throw PngError("write_damage_png: image of " + std::to_string(layout.width) + " x " +
                   std::to_string(layout.height) + " pixels is too large");
  }
  return layout;
}

/// Fills node i's square with colour(i), the raster's top-left corner at (left, top).
template <class Colour>
void draw_nodes(Image& img, const DamageImageLayout& layout, int left, int top,
                std::span<const double> x, std::span<const double> y, double dx, Colour colour) {
  const int s = layout.node_pixels;
  for (std::size_t i = 0; i < x.size(); ++i) {
    const auto c = static_cast<int>(std::lround((x[i] - layout.x_min) / dx));
    const auto r = static_cast<int>(std::lround((layout.y_max - y[i]) / dx));
    img.fill(left + c * s, top + r * s, s, s, colour(i));
  }
}

}  // namespace

DamageImageLayout write_damage_png(const std::filesystem::path& path, std::span<const double> x,
                                   std::span<const double> y, std::span<const double> damage,
                                   double dx, const DamagePngOptions& options) {
  const DamageImageLayout layout = grid_layout(x, y, damage, dx, options);
  Image img(layout.width, layout.height, kWhite);
  draw_nodes(img, layout, 0, 0, x, y, dx, [&](std::size_t i) { return damage_color(damage[i]); });
  save(path, img);
  return layout;
}

Rgb notch_color(double damage) {
  const double t = std::clamp(std::isnan(damage) ? 0.0 : damage, 0.0, 1.0);
  const auto v = static_cast<std::uint8_t>(std::lround(200.0 - 160.0 * t));
  return {v, v, v};
}

namespace {
constexpr Rgb kCrackPath{200, 0, 200};
constexpr Rgb kEstimate{230, 110, 0};
constexpr Rgb kCritical{120, 120, 120};
}  // namespace

DamageMapLayout write_damage_map_png(const std::filesystem::path& path, std::span<const double> x,
                                     std::span<const double> y, std::span<const double> damage,
                                     double dx, const DamageMap& map,
                                     const DamagePngOptions& options) {
  DamageMapLayout out;
  out.grid = grid_layout(x, y, damage, dx, options);
  if (!map.notch_damage.empty() && map.notch_damage.size() != damage.size()) {
    throw PngError("write_damage_map_png: notch_damage must have one value per node");
  }
  const DamageImageLayout& g = out.grid;
  // Axes in mm over the raster's extent: node centres ± dx/2.
  const double x_lo = 1e3 * (g.x_min - 0.5 * dx), x_hi = x_lo + 1e3 * dx * g.columns;
  const double y_hi = 1e3 * (g.y_max + 0.5 * dx), y_lo = y_hi - 1e3 * dx * g.rows;
  const Axis ax = exact_axis(x_lo, x_hi, std::max(2, g.width / 120));
  const Axis ay = exact_axis(y_lo, y_hi, std::max(2, g.height / 80));
  constexpr int bar_width = 24;
  const int label_w = std::max(text_width(tick_label(ay.lo, ay), kScale),
                               text_width(tick_label(ay.hi, ay), kScale));
  out.left = 30 + label_w;
  out.top = 20 + 2 * kGlyphHeight + 30;
  const int legend_left = out.left + g.width + 30;
  out.width = legend_left + bar_width + 10 + text_width("notch", kScale) + 20;
  out.height = out.top + std::max(g.height, 300) + 20 + 2 * kGlyphHeight + 30;
  if (out.width > kMaxSide || out.height > kMaxSide) {
    throw PngError("write_damage_map_png: picture too large");
  }
  Image img(out.width, out.height, kWhite);
  const bool have_notch = !map.notch_damage.empty();
  draw_nodes(img, g, out.left, out.top, x, y, dx, [&](std::size_t i) {
    if (have_notch && damage[i] > 0.0 && damage[i] <= map.notch_damage[i] + 1e-6) {
      return notch_color(damage[i]);
    }
    return damage_color(damage[i]);
  });
  const Frame f{out.left, out.top, g.width, g.height, ax, ay};
  auto polyline = [&](const std::vector<MapPoint>& line, int pen, Rgb colour) {
    for (std::size_t k = 1; k < line.size(); ++k) {
      draw_line(img, f.px(1e3 * line[k - 1].x), f.py(1e3 * line[k - 1].y), f.px(1e3 * line[k].x),
                f.py(1e3 * line[k].y), pen, colour);
    }
  };
  for (const auto& notch : map.notches) polyline(notch, 3, kBlack);
  for (const auto& crack : map.crack_paths) {
    polyline(crack, 3, kCrackPath);
    if (!crack.empty()) {  // the tip now
      img.fill(f.px(1e3 * crack.back().x) - 4, f.py(1e3 * crack.back().y) - 4, 9, 9, kCrackPath);
    }
  }
  draw_frame(img, f, "x [mm]", "y [mm]", false);
  draw_text(img, out.left, 15, map.title, kScale, kBlack);
  // The colour bar: φ from 0 (bottom) to 1 (top), ticks every 0.25.
  const int bar_top = out.top + kGlyphHeight, bar_h = std::max(g.height, 300) - 3 * kGlyphHeight;
  draw_text(img, legend_left, out.top - kGlyphHeight - 10, "damage", kScale, kBlack);
  for (int r = 0; r < bar_h; ++r) {
    const double phi = 1.0 - static_cast<double>(r) / (bar_h - 1);
    img.fill(legend_left, bar_top + r, bar_width, 1, damage_color(phi));
  }
  for (int k = 0; k <= 4; ++k) {
    const int p = bar_top + static_cast<int>(std::lround((1.0 - 0.25 * k) * (bar_h - 1)));
    draw_line(img, legend_left + bar_width, p, legend_left + bar_width + 5, p, 1, kBlack);
    char label[8];
    std::snprintf(label, sizeof label, "%.2f", 0.25 * k);
    draw_text(img, legend_left + bar_width + 8, p - kGlyphHeight / 2, label, kScale, kBlack);
  }
  if (have_notch) {  // the grey swatch of notch-only nodes, the notch line, the crack path
    const int y0 = bar_top + bar_h + 15;
    for (int k = 0; k < bar_width; ++k) {
      img.fill(legend_left + k, y0, 1, kGlyphHeight,
               notch_color(static_cast<double>(k) / bar_width));
    }
    draw_text(img, legend_left + bar_width + 8, y0, "notch", kScale, kBlack);
  }
  const int y1 = bar_top + bar_h + 15 + kGlyphHeight + 12;
  draw_line(img, legend_left, y1 + kGlyphHeight / 2, legend_left + bar_width, y1 + kGlyphHeight / 2,
            3, kCrackPath);
  draw_text(img, legend_left + bar_width + 8, y1, "crack", kScale, kBlack);
  save(path, img);
  return out;
}

void write_crack_length_png(const std::filesystem::path& path, std::span<const double> cycles,
                            std::span<const double> lengths_m, const PlotOptions& options) {
  if (cycles.size() != lengths_m.size()) {
    throw PngError("write_crack_length_png: cycles and lengths differ in size");
  }
  CrackGrowthPlot plot;
  plot.cycles.assign(cycles.begin(), cycles.end());
  plot.lengths_m.assign(lengths_m.begin(), lengths_m.end());
  write_crack_growth_png(path, plot, options);
}

void write_crack_growth_png(const std::filesystem::path& path, const CrackGrowthPlot& plot,
                            const PlotOptions& options) {
  const std::size_t n = plot.cycles.size();
  if (plot.lengths_m.size() != n) {
    throw PngError("write_crack_growth_png: cycles and lengths differ in size");
  }
  if (options.width < 200 || options.height < 150 || options.width > kMaxSide ||
      options.height > kMaxSide) {
    throw PngError("write_crack_growth_png: image size out of range");
  }
  // Data range (lengths in mm, predictions included); the axes start at 0 unless data go below.
  double x_lo = 0.0, x_hi = 0.0, y_lo = 0.0, y_hi = 0.0;
  auto include_x = [&](double v) {
    if (std::isfinite(v)) {
      x_lo = std::min(x_lo, v);
      x_hi = std::max(x_hi, v);
    }
  };
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(plot.cycles[i]) || !std::isfinite(plot.lengths_m[i])) continue;
    include_x(plot.cycles[i]);
    y_lo = std::min(y_lo, 1e3 * plot.lengths_m[i]);
    y_hi = std::max(y_hi, 1e3 * plot.lengths_m[i]);
  }
  auto drawable = [](const LifePrediction& p) {
    return std::isfinite(p.cycles) && std::isfinite(p.length_m) && std::isfinite(p.remaining);
  };
  for (const auto& p : plot.predictions) {
    if (!drawable(p)) continue;
    for (const double r : {p.remaining, p.low, p.high}) include_x(p.cycles + r);
  }
  if (std::isfinite(plot.critical_length_m)) y_hi = std::max(y_hi, 1e3 * plot.critical_length_m);
  const Axis ax = nice_axis(x_lo, x_hi);
  const Axis ay = nice_axis(y_lo, y_hi);

  const int left = 20 + text_width("-0.00000", kScale), right = 30;
  const int top = 20 + 3 * kGlyphHeight + 20, bottom = 20 + 2 * kGlyphHeight + 20;
  const Frame f{left, top, options.width - left - right, options.height - top - bottom, ax, ay};
  Image img(options.width, options.height, kWhite);
  draw_frame(img, f, "cycles", "crack length [mm]", true);
  draw_text(img, left - text_width("-0.0", kScale), 10, plot.title, kScale, kBlack);
  if (std::isfinite(plot.critical_length_m)) {
    const int p = f.py(1e3 * plot.critical_length_m);
    draw_dashed_line(img, f.left, p, f.left + f.width, p, 1, 6, kCritical);
  }
  // The estimates: band bar and a diamond at the central prediction; the latest one dashed.
  double latest = std::numeric_limits<double>::quiet_NaN();
  for (const auto& p : plot.predictions) {
    if (!drawable(p)) continue;
    const int py = f.py(1e3 * p.length_m);
    if (std::isfinite(p.low) && std::isfinite(p.high)) {
      const int a = f.px(p.cycles + p.low), b = f.px(p.cycles + p.high);
      draw_line(img, a, py, b, py, 1, kEstimate);
      draw_line(img, a, py - 3, a, py + 3, 1, kEstimate);
      draw_line(img, b, py - 3, b, py + 3, 1, kEstimate);
    }
    const int cx = f.px(p.cycles + p.remaining);
    for (int d = 0; d <= 4; ++d)
      img.fill(cx - (4 - d), py - d, 2 * (4 - d) + 1, 2 * d + 1, kEstimate);
    latest = p.cycles + p.remaining;
  }
  if (std::isfinite(latest)) {
    const int p = f.px(latest);
    draw_dashed_line(img, p, f.top, p, f.top + f.height, 2, 8, kEstimate);
  }
  if (plot.end_of_life_cycle >= 0) {
    const int p = f.px(static_cast<double>(plot.end_of_life_cycle));
    draw_line(img, p, f.top, p, f.top + f.height, 2, kCrackPath);
  }
  // The curve; a non-finite point breaks it.
  bool have_prev = false;
  int prev_x = 0, prev_y = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(plot.cycles[i]) || !std::isfinite(plot.lengths_m[i])) {
      have_prev = false;
      continue;
    }
    const int cx = f.px(plot.cycles[i]), cy = f.py(1e3 * plot.lengths_m[i]);
    if (have_prev) {
      draw_line(img, prev_x, prev_y, cx, cy, 3, kLine);
    } else {
      img.fill(cx - 1, cy - 1, 3, 3, kLine);
    }
    prev_x = cx;
    prev_y = cy;
    have_prev = true;
  }
  // Legend, top right, one row.
  int lx = f.left + f.width;
  const int ly = 10 + kGlyphHeight + 8;
  auto legend = [&](std::string_view text, Rgb colour) {
    lx -= text_width(text, kScale) + 40;
    draw_line(img, lx, ly + kGlyphHeight / 2, lx + 22, ly + kGlyphHeight / 2, 3, colour);
    draw_text(img, lx + 28, ly, text, kScale, kBlack);
  };
  if (plot.end_of_life_cycle >= 0) legend("end of life", kCrackPath);
  if (std::isfinite(plot.critical_length_m)) legend("critical", kCritical);
  legend("predicted end (band)", kEstimate);
  legend("crack length", kLine);
  save(path, img);
}

void write_line_plot_png(const std::filesystem::path& path, const LinePlot& plot,
                         const PlotOptions& options) {
  if (options.width < 200 || options.height < 150 || options.width > kMaxSide ||
      options.height > kMaxSide) {
    throw PngError("write_line_plot_png: image size out of range");
  }
  double x_lo = std::numeric_limits<double>::infinity(), x_hi = -x_lo;
  double y_lo = x_lo, y_hi = -x_lo;
  for (const auto& s : plot.series) {
    if (s.x.size() != s.y.size()) throw PngError("write_line_plot_png: x and y differ in size");
    for (std::size_t i = 0; i < s.x.size(); ++i) {
      if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) continue;
      x_lo = std::min(x_lo, s.x[i]);
      x_hi = std::max(x_hi, s.x[i]);
      y_lo = std::min(y_lo, s.y[i]);
      y_hi = std::max(y_hi, s.y[i]);
    }
  }
  if (!(x_lo <= x_hi)) x_lo = x_hi = 0.0;
  if (!(y_lo <= y_hi)) y_lo = y_hi = 0.0;
  if (plot.y_lo < plot.y_hi) {
    y_lo = plot.y_lo;
    y_hi = plot.y_hi;
  }
  const Axis ax = exact_axis(x_lo, x_hi, 6);
  const Axis ay = nice_axis(y_lo, y_hi);
  const int left = 20 + text_width("-0.00000", kScale), right = 30;
  const int top = 20 + 3 * kGlyphHeight + 20, bottom = 20 + 2 * kGlyphHeight + 20;
  const Frame f{left, top, options.width - left - right, options.height - top - bottom, ax, ay};
  Image img(options.width, options.height, kWhite);
  draw_frame(img, f, plot.x_title, plot.y_title, true);
  draw_text(img, left - text_width("-0.0", kScale), 10, plot.title, kScale, kBlack);
  auto clamp_y = [&](double v) { return std::clamp(v, ay.lo, ay.hi); };
  for (const auto& s : plot.series) {
    bool have_prev = false;
    int prev_x = 0, prev_y = 0;
    for (std::size_t i = 0; i < s.x.size(); ++i) {
      if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) {
        have_prev = false;
        continue;
      }
      const int cx = f.px(s.x[i]), cy = f.py(clamp_y(s.y[i]));
      if (have_prev) {
        if (s.dashed) {
          draw_dashed_line(img, prev_x, prev_y, cx, cy, 2, 4, s.color);
        } else {
          draw_line(img, prev_x, prev_y, cx, cy, 2, s.color);
        }
      }
      prev_x = cx;
      prev_y = cy;
      have_prev = true;
    }
  }
  int lx = f.left + f.width;
  const int ly = 10 + kGlyphHeight + 8;
  for (auto it = plot.series.rbegin(); it != plot.series.rend(); ++it) {
    lx -= text_width(it->label, kScale) + 40;
    draw_line(img, lx, ly + kGlyphHeight / 2, lx + 22, ly + kGlyphHeight / 2, 3, it->color);
    draw_text(img, lx + 28, ly, it->label, kScale, kBlack);
  }
  save(path, img);
}

}  // namespace peritwin::outputs
