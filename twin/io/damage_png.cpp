#include "twin/io/damage_png.h"

#include <png.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <string>
#include <string_view>
#include <vector>

#include "twin/io/checkpoint_io.h"

namespace peritwin::twin {

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

constexpr std::array<Glyph, 29> kFont{{
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
}};

constexpr int kGlyphAdvance = 6;  // 5 columns + 1 of spacing

int text_width(std::string_view s, int scale) {
  return s.empty() ? 0 : (static_cast<int>(s.size()) * kGlyphAdvance - 1) * scale;
}

/// Draws `s` with its top-left corner at (x, y); characters without a glyph are left blank.
void draw_text(Image& img, int x, int y, std::string_view s, int scale, Rgb color) {
  for (const char ch : s) {
    const auto it =
        std::find_if(kFont.begin(), kFont.end(), [ch](const Glyph& g) { return g.c == ch; });
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

Axis nice_axis(double lo, double hi) {
  if (!(hi > lo)) hi = lo + 1.0;
  const double step = nice_step(lo, hi, 5);
  return {std::floor(lo / step + 1e-9) * step, std::ceil(hi / step - 1e-9) * step, step};
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

DamageImageLayout write_damage_png(const std::filesystem::path& path, std::span<const double> x,
                                   std::span<const double> y, std::span<const double> damage,
                                   double dx, const DamagePngOptions& options) {
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
  Image img(layout.width, layout.height, kWhite);
  const int s = layout.node_pixels;
  for (std::size_t i = 0; i < x.size(); ++i) {
    const auto c = static_cast<int>(std::lround((x[i] - x_min) / dx));
    const auto r = static_cast<int>(std::lround((y_max - y[i]) / dx));
    img.fill(c * s, r * s, s, s, damage_color(damage[i]));
  }
  save(path, img);
  return layout;
}

void write_crack_length_png(const std::filesystem::path& path, std::span<const double> cycles,
                            std::span<const double> lengths_m, const PlotOptions& options) {
  if (cycles.size() != lengths_m.size()) {
    throw PngError("write_crack_length_png: cycles and lengths differ in size");
  }
  if (options.width < 200 || options.height < 150 || options.width > kMaxSide ||
      options.height > kMaxSide) {
    throw PngError("write_crack_length_png: image size out of range");
  }
  // Data range (lengths in mm); the axes start at 0 unless the data go below.
  double x_lo = 0.0, x_hi = 0.0, y_lo = 0.0, y_hi = 0.0;
  for (std::size_t i = 0; i < cycles.size(); ++i) {
    if (!std::isfinite(cycles[i]) || !std::isfinite(lengths_m[i])) continue;
    x_lo = std::min(x_lo, cycles[i]);
    x_hi = std::max(x_hi, cycles[i]);
    y_lo = std::min(y_lo, 1e3 * lengths_m[i]);
    y_hi = std::max(y_hi, 1e3 * lengths_m[i]);
  }
  const Axis ax = nice_axis(x_lo, x_hi);
  const Axis ay = nice_axis(y_lo, y_hi);

  constexpr int scale = 2;  // font scale: 10 x 14 pixel glyphs
  constexpr int glyph_h = 7 * scale;
  const int left = 20 + text_width("-0.00000", scale), right = 30;
  const int top = 20 + glyph_h + 10, bottom = 20 + 2 * glyph_h + 20;
  const int pw = options.width - left - right, ph = options.height - top - bottom;
  auto px = [&](double v) {
    return left + static_cast<int>(std::lround((v - ax.lo) / (ax.hi - ax.lo) * pw));
  };
  auto py = [&](double v) {
    return top + ph - static_cast<int>(std::lround((v - ay.lo) / (ay.hi - ay.lo) * ph));
  };

  Image img(options.width, options.height, kWhite);
  // Grid lines, ticks and labels.
  for (long k = 0; k <= std::lround((ax.hi - ax.lo) / ax.step); ++k) {
    const double v = ax.lo + static_cast<double>(k) * ax.step;
    const int p = px(v);
    draw_line(img, p, top, p, top + ph, 1, kGrid);
    draw_line(img, p, top + ph, p, top + ph + 6, 1, kBlack);
    const std::string label = tick_label(v, ax);
    draw_text(img, p - text_width(label, scale) / 2, top + ph + 10, label, scale, kBlack);
  }
  for (long k = 0; k <= std::lround((ay.hi - ay.lo) / ay.step); ++k) {
    const double v = ay.lo + static_cast<double>(k) * ay.step;
    const int p = py(v);
    draw_line(img, left, p, left + pw, p, 1, kGrid);
    draw_line(img, left - 6, p, left, p, 1, kBlack);
    const std::string label = tick_label(v, ay);
    draw_text(img, left - 10 - text_width(label, scale), p - glyph_h / 2, label, scale, kBlack);
  }
  // Axes and titles.
  draw_line(img, left, top, left, top + ph, 2, kBlack);
  draw_line(img, left, top + ph, left + pw, top + ph, 2, kBlack);
  draw_text(img, left - text_width("-0.0", scale), top - glyph_h - 10, "crack length [mm]", scale,
            kBlack);
  draw_text(img, left + pw / 2 - text_width("cycles", scale) / 2, top + ph + 20 + glyph_h, "cycles",
            scale, kBlack);
  // The curve; a non-finite point breaks it.
  bool have_prev = false;
  int prev_x = 0, prev_y = 0;
  for (std::size_t i = 0; i < cycles.size(); ++i) {
    if (!std::isfinite(cycles[i]) || !std::isfinite(lengths_m[i])) {
      have_prev = false;
      continue;
    }
    const int cx = px(cycles[i]), cy = py(1e3 * lengths_m[i]);
    if (have_prev) {
      draw_line(img, prev_x, prev_y, cx, cy, 3, kLine);
    } else {
      img.fill(cx - 1, cy - 1, 3, 3, kLine);
    }
    prev_x = cx;
    prev_y = cy;
    have_prev = true;
  }
  save(path, img);
}

}  // namespace peritwin::twin
