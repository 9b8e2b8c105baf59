#include "outputs/damage_png.h"

#include <cairo.h>
#include <pango/pangocairo.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <memory>
#include <numbers>
#include <string>
#include <string_view>
#include <vector>

#include "outputs/checkpoint_io.h"

namespace peritwin::outputs {

namespace {

constexpr Rgb kBlack{0, 0, 0};
constexpr Rgb kGrid{225, 225, 225};
constexpr Rgb kLine{31, 90, 180};
constexpr Rgb kCrackPath{200, 0, 200};
constexpr Rgb kEstimate{230, 110, 0};
constexpr Rgb kCritical{120, 120, 120};
constexpr int kMaxSide = 32767;  // cairo's largest image surface

// Spacing of the pictures, in pixels.
constexpr int kMargin = 12;       // around the picture
constexpr int kTick = 6;          // tick length
constexpr int kTickGap = 4;       // tick to its label
constexpr int kLabelGap = 12;     // least space between two tick labels along an axis
constexpr int kSampleWidth = 30;  // a legend entry's sample of its line
constexpr int kSampleGap = 6;     // sample to text
constexpr int kEntryGap = 22;     // between legend entries of a row
constexpr int kRowGap = 4;        // between legend rows

// --- cairo and pango handles -----------------------------------------------------------------

template <auto Release>
struct Releaser {
  template <class T>
  void operator()(T* p) const {
    Release(p);
  }
};
using SurfaceHandle = std::unique_ptr<cairo_surface_t, Releaser<cairo_surface_destroy>>;
using ContextHandle = std::unique_ptr<cairo_t, Releaser<cairo_destroy>>;
using LayoutHandle = std::unique_ptr<PangoLayout, Releaser<g_object_unref>>;
using FontHandle = std::unique_ptr<PangoFontDescription, Releaser<pango_font_description_free>>;
using FontOptionsHandle =
    std::unique_ptr<cairo_font_options_t, Releaser<cairo_font_options_destroy>>;

void check(cairo_t* cr, const char* what) {
  const cairo_status_t status = cairo_status(cr);
  if (status != CAIRO_STATUS_SUCCESS) {
    throw PngError(std::string("cairo (") + what + "): " + cairo_status_to_string(status));
  }
}

/// An RGB image surface of cairo, white, and its drawing context.
struct Surface {
  SurfaceHandle surface;
  ContextHandle cr;
  Surface(int width, int height)
      : surface(cairo_image_surface_create(CAIRO_FORMAT_RGB24, width, height)),
        cr(cairo_create(surface.get())) {
    check(cr.get(), "image surface");  // a failed surface makes a failed context
    cairo_set_source_rgb(cr.get(), 1.0, 1.0, 1.0);
    cairo_paint(cr.get());
  }
};

// --- text ------------------------------------------------------------------------------------

/// The faces of the pictures' text: fontconfig's "Sans" (DejaVu Sans on Debian), sizes in pixels.
enum class Face { text, title, small };
constexpr int kTextPixels = 14, kTitlePixels = 17, kSmallPixels = 12;

struct Size {
  int width = 0, height = 0;
};

/// Sets text with pango: measures it and draws it. Measures on a 1 x 1 surface of the pictures'
/// kind with the same font options, so a size measured before a picture exists is the size drawn.
class Typesetter {
 public:
  Typesetter() : measure_(1, 1) {
    layout_.reset(pango_cairo_create_layout(measure_.cr.get()));
    // Grey antialiasing (no colour fringes), slight hinting, whole-pixel advances: the same text
    // the same pixels on every machine with the same font.
    FontOptionsHandle options(cairo_font_options_create());
    cairo_font_options_set_antialias(options.get(), CAIRO_ANTIALIAS_GRAY);
    cairo_font_options_set_hint_style(options.get(), CAIRO_HINT_STYLE_SLIGHT);
    cairo_font_options_set_hint_metrics(options.get(), CAIRO_HINT_METRICS_ON);
    pango_cairo_context_set_font_options(pango_layout_get_context(layout_.get()), options.get());
    pango_layout_context_changed(layout_.get());
    text_font_.reset(pango_font_description_from_string("Sans"));
    pango_font_description_set_absolute_size(text_font_.get(), kTextPixels * PANGO_SCALE);
    title_font_.reset(pango_font_description_copy(text_font_.get()));
    pango_font_description_set_absolute_size(title_font_.get(), kTitlePixels * PANGO_SCALE);
    pango_font_description_set_weight(title_font_.get(), PANGO_WEIGHT_BOLD);
    small_font_.reset(pango_font_description_copy(text_font_.get()));
    pango_font_description_set_absolute_size(small_font_.get(), kSmallPixels * PANGO_SCALE);
  }

  /// The width and height of `text` (its logical extents) in whole pixels; with `wrap` > 0 the
  /// text is broken into lines of at most that many pixels.
  Size size(std::string_view text, Face face, int wrap = 0) {
    set(text, face, wrap);
    const PangoRectangle r = extents();
    return {r.width, r.height};
  }

  /// Draws `text` with the top-left corner of its extents at (left, top); returns its box.
  Box draw(cairo_t* cr, int left, int top, std::string_view text, Face face, Rgb colour,
           int wrap = 0) {
    set(text, face, wrap);
    const PangoRectangle r = extents();
    cairo_save(cr);
    pango_cairo_update_layout(cr, layout_.get());
    cairo_set_source_rgb(cr, colour.r / 255.0, colour.g / 255.0, colour.b / 255.0);
    cairo_move_to(cr, left - r.x, top - r.y);
    pango_cairo_show_layout(cr, layout_.get());
    cairo_restore(cr);
    pango_cairo_update_layout(measure_.cr.get(), layout_.get());
    return {left, top, r.width, r.height};
  }

  /// Draws `text` turned a quarter turn anticlockwise (reading upwards) with the top-left corner
  /// of its box at (left, top); returns the box (as wide as the text is high).
  Box draw_upwards(cairo_t* cr, int left, int top, std::string_view text, Face face, Rgb colour) {
    set(text, face);
    const PangoRectangle r = extents();
    cairo_save(cr);
    cairo_translate(cr, left, top + r.width);
    cairo_rotate(cr, -0.5 * std::numbers::pi);
    pango_cairo_update_layout(cr, layout_.get());
    cairo_set_source_rgb(cr, colour.r / 255.0, colour.g / 255.0, colour.b / 255.0);
    cairo_move_to(cr, -r.x, -r.y);
    pango_cairo_show_layout(cr, layout_.get());
    cairo_restore(cr);
    pango_cairo_update_layout(measure_.cr.get(), layout_.get());
    return {left, top, r.height, r.width};
  }

 private:
  void set(std::string_view text, Face face, int wrap = 0) {
    pango_layout_set_font_description(layout_.get(), face == Face::title   ? title_font_.get()
                                                     : face == Face::small ? small_font_.get()
                                                                           : text_font_.get());
    pango_layout_set_wrap(layout_.get(), PANGO_WRAP_WORD_CHAR);
    pango_layout_set_width(layout_.get(), wrap > 0 ? wrap * PANGO_SCALE : -1);
    const auto n = static_cast<gssize>(text.size());
    if (g_utf8_validate(text.data(), n, nullptr)) {
      pango_layout_set_text(layout_.get(), text.data(), static_cast<int>(n));
    } else {  // a detail id of other bytes: shown with replacement characters
      std::unique_ptr<gchar, Releaser<g_free>> valid(g_utf8_make_valid(text.data(), n));
      pango_layout_set_text(layout_.get(), valid.get(), -1);
    }
  }
  PangoRectangle extents() {
    PangoRectangle logical{};
    pango_layout_get_pixel_extents(layout_.get(), nullptr, &logical);
    return logical;
  }

  Surface measure_;
  LayoutHandle layout_;
  FontHandle text_font_, title_font_, small_font_;
};

// --- drawing ---------------------------------------------------------------------------------

void set_colour(cairo_t* cr, Rgb c) {
  cairo_set_source_rgb(cr, c.r / 255.0, c.g / 255.0, c.b / 255.0);
}

/// Fills whole pixels: exactly `c` inside the box.
void fill_box(cairo_t* cr, const Box& b, Rgb c) {
  cairo_rectangle(cr, b.left, b.top, b.width, b.height);
  set_colour(cr, c);
  cairo_fill(cr);
}

/// A straight line `width` pixels wide; dash > 0: dashes and gaps of `dash` pixels. A horizontal
/// or vertical line of an odd width on whole-pixel coordinates covers whole pixels (crisp).
void line(cairo_t* cr, double x0, double y0, double x1, double y1, double width, Rgb c,
          double dash = 0.0) {
  const bool odd = std::fmod(width, 2.0) == 1.0;
  if (odd && y0 == y1 && y0 == std::floor(y0)) y0 = y1 = y0 + 0.5;
  if (odd && x0 == x1 && x0 == std::floor(x0)) x0 = x1 = x0 + 0.5;
  cairo_save(cr);
  cairo_set_line_width(cr, width);
  cairo_set_line_cap(cr, CAIRO_LINE_CAP_BUTT);
  if (dash > 0.0) cairo_set_dash(cr, &dash, 1, 0.0);
  set_colour(cr, c);
  cairo_move_to(cr, x0, y0);
  cairo_line_to(cr, x1, y1);
  cairo_stroke(cr);
  cairo_restore(cr);
}

void dot(cairo_t* cr, double x, double y, double radius, Rgb c) {
  cairo_new_sub_path(cr);
  cairo_arc(cr, x, y, radius, 0.0, 2.0 * std::numbers::pi);
  set_colour(cr, c);
  cairo_fill(cr);
}

/// A diamond of half-diagonal `r` centred on (x, y).
void diamond(cairo_t* cr, double x, double y, double r, Rgb c) {
  cairo_move_to(cr, x, y - r);
  cairo_line_to(cr, x + r, y);
  cairo_line_to(cr, x, y + r);
  cairo_line_to(cr, x - r, y);
  cairo_close_path(cr);
  set_colour(cr, c);
  cairo_fill(cr);
}

/// A line through points, round joins; a non-finite point ends a piece, a piece of one point is
/// a dot.
class Polyline {
 public:
  Polyline(cairo_t* cr, double width, Rgb c, double dash = 0.0)
      : cr_(cr), width_(width), colour_(c), dash_(dash) {}
  void add(double x, double y) {
    if (!std::isfinite(x) || !std::isfinite(y)) {
      flush();
      return;
    }
    piece_.push_back({x, y});
  }
  void flush() {
    if (piece_.size() == 1) {
      dot(cr_, piece_[0][0], piece_[0][1], 0.5 * width_ + 0.5, colour_);
    } else if (piece_.size() > 1) {
      cairo_save(cr_);
      cairo_set_line_width(cr_, width_);
      cairo_set_line_join(cr_, CAIRO_LINE_JOIN_ROUND);
      cairo_set_line_cap(cr_, dash_ > 0.0 ? CAIRO_LINE_CAP_BUTT : CAIRO_LINE_CAP_ROUND);
      if (dash_ > 0.0) cairo_set_dash(cr_, &dash_, 1, 0.0);
      set_colour(cr_, colour_);
      cairo_move_to(cr_, piece_[0][0], piece_[0][1]);
      for (std::size_t i = 1; i < piece_.size(); ++i)
        cairo_line_to(cr_, piece_[i][0], piece_[i][1]);
      cairo_stroke(cr_);
      cairo_restore(cr_);
    }
    piece_.clear();
  }

 private:
  cairo_t* cr_;
  double width_;
  Rgb colour_;
  double dash_;
  std::vector<std::array<double, 2>> piece_;
};

/// The PNG of the surface, written atomically.
void save(const Surface& s, const std::filesystem::path& path) {
  check(s.cr.get(), "drawing");
  cairo_surface_flush(s.surface.get());
  std::string bytes;
  auto append = [](void* closure, const unsigned char* data, unsigned int length) {
    try {
      static_cast<std::string*>(closure)->append(reinterpret_cast<const char*>(data), length);
      return CAIRO_STATUS_SUCCESS;
    } catch (...) {
      return CAIRO_STATUS_NO_MEMORY;
    }
  };
  const cairo_status_t status = cairo_surface_write_to_png_stream(s.surface.get(), append, &bytes);
  if (status != CAIRO_STATUS_SUCCESS) {
    throw PngError(std::string("cairo (PNG): ") + cairo_status_to_string(status));
  }
  write_file_atomically(path, bytes, false);
}

// --- axes ------------------------------------------------------------------------------------

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

/// An axis over [lo, hi] stretched to multiples of a 1-2-5 step (the plots' value axes).
Axis nice_axis(double lo, double hi, int target) {
  if (!(hi > lo)) hi = lo + 1.0;
  const double step = nice_step(lo, hi, target);
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

/// Tick labels of one axis share a format: fixed with the decimals the step needs, or, for
/// |v| >= 1e6 (or tiny values), %.3g with a short exponent ("1.5e+06" -> "1.5e6"); negative
/// numbers with the minus sign U+2212 (as wide as a digit), not the hyphen.
std::string tick_label(double v, const Axis& axis) {
  if (std::abs(v) < 1e-9 * axis.step) v = 0.0;
  const double big = std::max(std::abs(axis.lo), std::abs(axis.hi));
  char buf[40];
  std::string s;
  if (big < 1e6 && axis.step >= 1e-4) {
    const int decimals = std::max(0, -static_cast<int>(std::floor(std::log10(axis.step) + 1e-9)));
    std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
    s = buf;
  } else {
    std::snprintf(buf, sizeof buf, "%.3g", v);
    s = buf;
    const auto e = s.find('e');
    if (e != std::string::npos) {
      std::string mant = s.substr(0, e), exp = s.substr(e + 1);
      const bool neg = exp[0] == '-';
      exp = exp.substr(1);
      exp.erase(0, std::min(exp.find_first_not_of('0'), exp.size() - 1));
      s = mant + "e" + (neg ? "-" : "") + exp;
    }
  }
  for (auto minus = s.find('-'); minus != std::string::npos; minus = s.find('-', minus)) {
    s.replace(minus, 1, "\u2212");
  }
  return s;
}

/// How an axis is made for a number of intervals (nice_axis or exact_axis over the data).
using AxisMaker = std::function<Axis(int target)>;

/// The axes one may get, from `target` intervals down to 1.
std::vector<Axis> candidate_axes(const AxisMaker& make, int target) {
  std::vector<Axis> out;
  for (int t = std::max(1, target); t >= 1; --t) out.push_back(make(t));
  return out;
}

/// The first of the candidates whose tick labels, centred on their ticks along `pixels` of a
/// horizontal axis, leave kLabelGap between neighbours (the last candidate if none does).
Axis fit_x_axis(Typesetter& ts, const std::vector<Axis>& candidates, int pixels) {
  for (const Axis& a : candidates) {
    double prev_right = -1e300;
    bool fits = true;
    for (const double v : ticks(a)) {
      const double p = (v - a.lo) / (a.hi - a.lo) * pixels;
      const int w = ts.size(tick_label(v, a), Face::text).width;
      if (p - 0.5 * w < prev_right + kLabelGap) fits = false;
      prev_right = p + 0.5 * w;
    }
    if (fits) return a;
  }
  return candidates.back();
}

/// The first of the candidates whose ticks along `pixels` of a vertical axis are at least a
/// label's height apart (plus a little).
Axis fit_y_axis(Typesetter& ts, const std::vector<Axis>& candidates, int pixels) {
  const int h = ts.size("0", Face::text).height;
  for (const Axis& a : candidates) {
    if (a.step / (a.hi - a.lo) * pixels >= h + 4) return a;
  }
  return candidates.back();
}

/// The widest tick label of any of the candidates.
int widest_label(Typesetter& ts, const std::vector<Axis>& candidates) {
  int w = 0;
  for (const Axis& a : candidates) {
    for (const double v : ticks(a)) w = std::max(w, ts.size(tick_label(v, a), Face::text).width);
  }
  return w;
}

/// The data rectangle of a plot in pixels and the ranges it maps (y up).
struct Frame {
  Box box;
  Axis x, y;
  [[nodiscard]] double px(double v) const {
    return box.left + (v - x.lo) / (x.hi - x.lo) * box.width;
  }
  [[nodiscard]] double py(double v) const {
    return box.bottom() - (v - y.lo) / (y.hi - y.lo) * box.height;
  }
};

/// Ticks with their labels below and left of the frame, the axis titles (x centred below the
/// labels, y upwards left of them, `y_title_left` its left edge), and (with `grid`) grid lines
/// across it; the frame's border in black. Puts the label and title boxes into `text`.
void draw_axes(cairo_t* cr, Typesetter& ts, const Frame& f, std::string_view x_title,
               std::string_view y_title, int y_title_left, bool grid, PictureText& text) {
  const Box& b = f.box;
  int label_height = 0;
  for (const double v : ticks(f.x)) {
    const double p = std::round(f.px(v));
    if (grid) line(cr, p, b.top, p, b.bottom(), 1, kGrid);
    line(cr, p, b.bottom(), p, b.bottom() + kTick, 1, kBlack);
    const std::string label = tick_label(v, f.x);
    const Size s = ts.size(label, Face::text);
    text.x_tick_labels.push_back(ts.draw(cr, static_cast<int>(p) - s.width / 2,
                                         b.bottom() + kTick + kTickGap, label, Face::text, kBlack));
    label_height = std::max(label_height, s.height);
  }
  for (const double v : ticks(f.y)) {
    const double p = std::round(f.py(v));
    if (grid) line(cr, b.left, p, b.right(), p, 1, kGrid);
    line(cr, b.left - kTick, p, b.left, p, 1, kBlack);
    const std::string label = tick_label(v, f.y);
    const Size s = ts.size(label, Face::text);
    text.y_tick_labels.push_back(ts.draw(cr, b.left - kTick - kTickGap - s.width,
                                         static_cast<int>(p) - s.height / 2, label, Face::text,
                                         kBlack));
  }
  if (grid) {  // a plot: the two axes
    line(cr, b.left, b.top, b.left, b.bottom() + 1, 2, kBlack);
    line(cr, b.left - 1, b.bottom(), b.right(), b.bottom(), 2, kBlack);
  } else {  // a map: a closed box around it
    cairo_rectangle(cr, b.left - 0.5, b.top - 0.5, b.width + 1, b.height + 1);
    set_colour(cr, kBlack);
    cairo_set_line_width(cr, 1.0);
    cairo_stroke(cr);
  }
  const Size xs = ts.size(x_title, Face::text);
  text.x_title =
      ts.draw(cr, b.left + b.width / 2 - xs.width / 2,
              b.bottom() + kTick + kTickGap + label_height + 6, x_title, Face::text, kBlack);
  const Size ys = ts.size(y_title, Face::text);
  text.y_title = ts.draw_upwards(cr, y_title_left, b.top + b.height / 2 - ys.width / 2, y_title,
                                 Face::text, kBlack);
}

// --- legends ---------------------------------------------------------------------------------

/// A legend entry to set: its text and how its sample is drawn into a box.
struct LegendItem {
  std::string label;
  std::function<void(cairo_t*, const Box&)> sample;
};

/// Places the entries in rows inside `width` pixels from the top `top`: each entry as wide as its
/// sample and its measured text, an entry goes to a new row when the row has no room for it; the
/// rows flush right against `right` (align_right) or left against right - width.
std::vector<LegendEntry> lay_out_legend(Typesetter& ts, const std::vector<LegendItem>& items,
                                        int right, int width, int top, bool align_right) {
  std::vector<LegendEntry> out;
  std::vector<std::vector<std::size_t>> rows;
  std::vector<int> row_width;
  for (std::size_t i = 0; i < items.size(); ++i) {
    const Size s = ts.size(items[i].label, Face::text);
    LegendEntry e;
    e.label = items[i].label;
    e.box = {0, 0, kSampleWidth + kSampleGap + s.width, s.height};
    out.push_back(e);
    if (rows.empty() || row_width.back() + kEntryGap + e.box.width > width) {
      rows.emplace_back();
      row_width.push_back(-kEntryGap);
    }
    rows.back().push_back(i);
    row_width.back() += kEntryGap + e.box.width;
  }
  int y = top;
  for (std::size_t r = 0; r < rows.size(); ++r) {
    int x = align_right ? right - row_width[r] : right - width;
    int height = 0;
    for (const std::size_t i : rows[r]) {
      LegendEntry& e = out[i];
      e.box.left = x;
      e.box.top = y;
      e.sample = {x, y + 2, kSampleWidth, e.box.height - 4};
      e.text = {x + kSampleWidth + kSampleGap, y, e.box.width - kSampleWidth - kSampleGap,
                e.box.height};
      x += e.box.width + kEntryGap;
      height = std::max(height, e.box.height);
    }
    y += height + kRowGap;
  }
  return out;
}

/// The bottom of the legend's last row (`top` when it is empty).
int legend_bottom(const std::vector<LegendEntry>& entries, int top) {
  int bottom = top;
  for (const auto& e : entries) bottom = std::max(bottom, e.box.bottom());
  return bottom;
}

void draw_legend(cairo_t* cr, Typesetter& ts, const std::vector<LegendItem>& items,
                 const std::vector<LegendEntry>& entries) {
  for (std::size_t i = 0; i < items.size(); ++i) {
    cairo_save(cr);
    items[i].sample(cr, entries[i].sample);
    cairo_restore(cr);
    ts.draw(cr, entries[i].text.left, entries[i].text.top, items[i].label, Face::text, kBlack);
  }
}

/// A legend sample: a line across the middle of the box.
std::function<void(cairo_t*, const Box&)> line_sample(Rgb c, double width, double dash = 0.0) {
  return [=](cairo_t* cr, const Box& b) {
    const double y = b.top + b.height / 2;
    line(cr, b.left, y, b.right(), y, width, c, dash);
  };
}

// --- plots -----------------------------------------------------------------------------------

/// What a plot shows around its data.
struct PlotText {
  std::string title, x_title, y_title;
  std::vector<LegendItem> legend;
};

/// Lays a plot out on a picture of the given size: the title on top (broken into lines when wider
/// than the picture), the legend below it (right aligned, rows as needed), the frame below the
/// legend with room left for the y tick labels and the y title and below for the x tick labels
/// and the x title; draws all of it but the data.
Frame draw_plot(cairo_t* cr, Typesetter& ts, int width, int height, const PlotText& t,
                const AxisMaker& make_x, int x_target, const AxisMaker& make_y, PlotLayout& out) {
  out.width = width;
  out.height = height;
  const Size y_title = ts.size(t.y_title, Face::text);
  const Size x_title = ts.size(t.x_title, Face::text);
  const int label_h = ts.size("0", Face::text).height;
  const std::vector<Axis> ys = candidate_axes(make_y, 5);
  const std::vector<Axis> xs = candidate_axes(make_x, x_target);
  int last_label = 0;  // the last x label may sit on the frame's right edge: half of it sticks out
  for (const Axis& a : xs) {
    const auto tk = ticks(a);
    if (!tk.empty())
      last_label = std::max(last_label, ts.size(tick_label(tk.back(), a), Face::text).width);
  }
  Box frame;
  frame.left = kMargin + y_title.height + 8 + widest_label(ts, ys) + kTickGap + kTick;
  const int right = width - std::max(kMargin + 8, kMargin + last_label / 2);
  frame.width = std::max(10, right - frame.left);
  const int title_wrap = std::max(10, width - kMargin - frame.left);  // lines as wide as fit
  const Size title = ts.size(t.title, Face::title, title_wrap);
  const int legend_top = kMargin + (t.title.empty() ? 0 : title.height + 8);
  out.text.legend = lay_out_legend(ts, t.legend, right, frame.width, legend_top, true);
  frame.top = legend_bottom(out.text.legend, legend_top) + 10 + label_h / 2;
  const int bottom = height - kMargin - x_title.height - 6 - label_h - kTickGap - kTick;
  frame.height = std::max(10, bottom - frame.top);
  out.frame = frame;
  const Frame f{frame, fit_x_axis(ts, xs, frame.width), fit_y_axis(ts, ys, frame.height)};
  if (!t.title.empty()) {
    out.text.title = ts.draw(cr, frame.left, kMargin, t.title, Face::title, kBlack, title_wrap);
  }
  draw_axes(cr, ts, f, t.x_title, t.y_title, kMargin, true, out.text);
  draw_legend(cr, ts, t.legend, out.text.legend);
  return f;
}

void check_plot_size(const PlotOptions& options, const char* who) {
  if (options.width < 200 || options.height < 150 || options.width > kMaxSide ||
      options.height > kMaxSide) {
    throw PngError(std::string(who) + ": image size out of range");
  }
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
void draw_nodes(cairo_t* cr, const DamageImageLayout& layout, int left, int top,
                std::span<const double> x, std::span<const double> y, double dx, Colour colour) {
  const int s = layout.node_pixels;
  for (std::size_t i = 0; i < x.size(); ++i) {
    const auto c = static_cast<int>(std::lround((x[i] - layout.x_min) / dx));
    const auto r = static_cast<int>(std::lround((layout.y_max - y[i]) / dx));
    fill_box(cr, {left + c * s, top + r * s, s, s}, colour(i));
  }
}

// --- gauges on the map -------------------------------------------------------------------------

constexpr double kGaugeCore = 5.0;  // the coloured bar's width (pixels)
constexpr double kGaugeRim = 1.0;   // the black rim around it
constexpr int kPlatePad = 2;        // label text to its plate's edge
constexpr int kPlateGap = 3;        // the bar's box to the plate

/// A gauge's bar in the picture's pixels (see GaugeMark), from the frame of the map.
GaugeMark gauge_mark(const Frame& f, const MapGauge& g, double dx, int node_pixels) {
  GaugeMark m;
  m.id = g.id;
  const double length = std::max(g.length, kGaugeMinLengthDx * dx) / dx * node_pixels;
  const double cx = f.px(1e3 * g.at.x), cy = f.py(1e3 * g.at.y);
  // Rows go down; a gauge along x or y (cos or sin ~ 1e-16) is drawn on whole pixels.
  auto snap = [](double v) { return std::abs(v) < 1e-12 ? 0.0 : v; };
  const double ux = snap(std::cos(g.angle)), uy = snap(-std::sin(g.angle));
  const double h = 0.5 * length;
  m.x0 = cx - h * ux;
  m.y0 = cy - h * uy;
  m.x1 = cx + h * ux;
  m.y1 = cy + h * uy;
  if (ux == 0.0 || uy == 0.0) {  // whole pixels: line() centres it on a pixel, crisp
    for (double* v : {&m.x0, &m.y0, &m.x1, &m.y1}) *v = std::round(*v);
  }
  const double mx = 0.5 * (m.x0 + m.x1), my = 0.5 * (m.y0 + m.y1);
  const double along = 0.5 * std::hypot(m.x1 - m.x0, m.y1 - m.y0) + kGaugeRim;
  const double across = 0.5 * kGaugeCore + kGaugeRim + 0.5;
  const double ex = along * std::abs(ux) + across * std::abs(uy);
  const double ey = along * std::abs(uy) + across * std::abs(ux);
  const auto left = static_cast<int>(std::floor(mx - ex));
  const auto top = static_cast<int>(std::floor(my - ey));
  m.bar = {left, top, static_cast<int>(std::ceil(mx + ex)) - left,
           static_cast<int>(std::ceil(my + ey)) - top};
  return m;
}

/// The bar: kGaugeColor with a black rim (butt ends, the rim past them too).
void draw_gauge_bar(cairo_t* cr, const GaugeMark& m) {
  const double len = std::hypot(m.x1 - m.x0, m.y1 - m.y0);
  const double ux = (m.x1 - m.x0) / len, uy = (m.y1 - m.y0) / len;
  line(cr, m.x0 - kGaugeRim * ux, m.y0 - kGaugeRim * uy, m.x1 + kGaugeRim * ux,
       m.y1 + kGaugeRim * uy, kGaugeCore + 2.0 * kGaugeRim, kBlack);
  line(cr, m.x0, m.y0, m.x1, m.y1, kGaugeCore, kGaugeColor);
}

/// Small boxes along the polylines (their lines are 3 pixels wide, a tip's dot 9), to keep the
/// gauges' labels off the notches and the crack paths.
std::vector<Box> line_boxes(const Frame& f, const std::vector<std::vector<MapPoint>>& lines) {
  std::vector<Box> out;
  auto around = [&](double x, double y, int r) {
    out.push_back({static_cast<int>(std::floor(x)) - r, static_cast<int>(std::floor(y)) - r,
                   2 * r + 1, 2 * r + 1});
  };
  for (const auto& l : lines) {
    for (std::size_t i = 0; i < l.size(); ++i) {
      const double x1 = f.px(1e3 * l[i].x), y1 = f.py(1e3 * l[i].y);
      if (!std::isfinite(x1) || !std::isfinite(y1)) continue;
      around(x1, y1, 5);
      if (i == 0) continue;
      const double x0 = f.px(1e3 * l[i - 1].x), y0 = f.py(1e3 * l[i - 1].y);
      if (!std::isfinite(x0) || !std::isfinite(y0)) continue;
      const int steps = static_cast<int>(std::ceil(std::hypot(x1 - x0, y1 - y0) / 4.0));
      for (int k = 1; k < std::min(steps, 100000); ++k) {
        const double t = static_cast<double>(k) / steps;
        around(x0 + t * (x1 - x0), y0 + t * (y1 - y0), 3);
      }
    }
  }
  return out;
}

/// Places every gauge's label plate (see MapGauge): `marks` have their bars; sets their labels.
void place_gauge_labels(Typesetter& ts, const Box& raster, const std::vector<Box>& lines,
                        std::vector<GaugeMark>& marks) {
  auto count = [](const Box& b, const std::vector<Box>& boxes) {
    return static_cast<int>(
        std::count_if(boxes.begin(), boxes.end(), [&](const Box& o) { return b.overlaps(o); }));
  };
  std::vector<Box> taken;  // every bar, and the plates placed so far
  for (const auto& m : marks) taken.push_back(m.bar);
  for (auto& m : marks) {
    const Size text = ts.size(m.id, Face::small);
    const int w = text.width + 2 * kPlatePad, h = text.height + 2 * kPlatePad;
    const Box& b = m.bar;
    const int cx = b.left + b.width / 2, cy = b.top + b.height / 2;
    const std::array<Box, 4> sides{{{b.right() + kPlateGap, cy - h / 2, w, h},
                                    {b.left - kPlateGap - w, cy - h / 2, w, h},
                                    {cx - w / 2, b.top - kPlateGap - h, w, h},
                                    {cx - w / 2, b.bottom() + kPlateGap, w, h}}};
    auto into_raster = [&](Box p) {
      p.left = std::max(raster.left, std::min(p.left, raster.right() - w));
      p.top = std::max(raster.top, std::min(p.top, raster.bottom() - h));
      return p;
    };
    // Cost: plates and bars covered weigh most, then notch or crack lines, then a moved plate.
    int best_cost = std::numeric_limits<int>::max();
    for (int moved = 0; moved < 2; ++moved) {
      for (const Box& side : sides) {
        if (moved == 0 && !raster.contains(side)) continue;
        const Box p = moved ? into_raster(side) : side;
        const int cost = 4 * count(p, taken) + 2 * (count(p, lines) > 0 ? 1 : 0) + moved;
        if (cost < best_cost) {
          best_cost = cost;
          m.label = p;
        }
      }
    }
    taken.push_back(m.label);
  }
}

}  // namespace

DamageImageLayout write_damage_png(const std::filesystem::path& path, std::span<const double> x,
                                   std::span<const double> y, std::span<const double> damage,
                                   double dx, const DamagePngOptions& options) {
  const DamageImageLayout layout = grid_layout(x, y, damage, dx, options);
  Surface s(layout.width, layout.height);
  draw_nodes(s.cr.get(), layout, 0, 0, x, y, dx,
             [&](std::size_t i) { return damage_color(damage[i]); });
  save(s, path);
  return layout;
}

Rgb notch_color(double damage) {
  const double t = std::clamp(std::isnan(damage) ? 0.0 : damage, 0.0, 1.0);
  const auto v = static_cast<std::uint8_t>(std::lround(200.0 - 160.0 * t));
  return {v, v, v};
}

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
  const bool have_notch = !map.notch_damage.empty();
  Typesetter ts;
  // Axes in mm over the raster's extent: node centres ± dx/2.
  const double x_lo = 1e3 * (g.x_min - 0.5 * dx), x_hi = x_lo + 1e3 * dx * g.columns;
  const double y_hi = 1e3 * (g.y_max + 0.5 * dx), y_lo = y_hi - 1e3 * dx * g.rows;
  const Axis ax = fit_x_axis(
      ts, candidate_axes([&](int t) { return exact_axis(x_lo, x_hi, t); }, g.width / 120), g.width);
  const Axis ay = fit_y_axis(
      ts, candidate_axes([&](int t) { return exact_axis(y_lo, y_hi, t); }, g.height / 80),
      g.height);
  const Size title = ts.size(map.title, Face::title);
  const Size y_title = ts.size("y [mm]", Face::text);
  const int label_h = ts.size("0", Face::text).height;
  out.left = kMargin + y_title.height + 8 + widest_label(ts, {ay}) + kTickGap + kTick;
  out.top = kMargin + title.height + 12 + label_h / 2;
  const Box raster{out.left, out.top, g.width, g.height};

  // The column right of the map: the colour bar's title, the bar with its labels (φ from 0 at
  // the bottom to 1 at the top, every 0.25), then the legend.
  constexpr int bar_width = 24;
  const int column = raster.right() + 28;
  const Size bar_title = ts.size("damage φ", Face::text);
  const int bar_top = raster.top + bar_title.height + 8 + label_h / 2;
  const int bar_height = std::max(200, raster.bottom() - label_h / 2 - bar_top);
  out.colour_bar = {column, bar_top, bar_width, bar_height};
  int bar_labels_width = 0;
  for (const char* label : {"0.00", "0.25", "0.50", "0.75", "1.00"}) {
    bar_labels_width = std::max(bar_labels_width, ts.size(label, Face::text).width);
  }
  std::vector<LegendItem> legend;
  if (std::any_of(map.notch_damage.begin(), map.notch_damage.end(), [](double phi) {
        return phi > 0.0;
      })) {  // the grey of notch-only nodes, light (φ = 0) to dark (φ = 1)
    legend.push_back({"notch", [](cairo_t* cr, const Box& b) {
                        for (int k = 0; k < b.width; ++k) {
                          fill_box(cr, {b.left + k, b.top, 1, b.height},
                                   notch_color(static_cast<double>(k) / b.width));
                        }
                      }});
  }
  legend.push_back({"crack", [](cairo_t* cr, const Box& b) {
                      const double yc = b.top + 0.5 * b.height;
                      line(cr, b.left, yc, b.right() - 4, yc, 3, kCrackPath);
                      dot(cr, b.right() - 4.5, yc, 4.5, kCrackPath);
                    }});
  if (!map.gauges.empty()) {
    legend.push_back({"gauge", [](cairo_t* cr, const Box& b) {
                        GaugeMark m;
                        m.y0 = m.y1 = b.top + b.height / 2;
                        m.x0 = b.left + 4;
                        m.x1 = b.right() - 4;
                        draw_gauge_bar(cr, m);
                      }});
  }
  int entries_width = 0;
  for (const auto& item : legend) {
    entries_width =
        std::max(entries_width, kSampleWidth + kSampleGap + ts.size(item.label, Face::text).width);
  }
  const int column_width =
      std::max({bar_title.width, bar_width + kTick + kTickGap + bar_labels_width, entries_width});
  const int legend_top = out.colour_bar.bottom() + label_h / 2 + 16;
  out.text.legend =
      lay_out_legend(ts, legend, column + column_width, column_width, legend_top, false);

  out.width = std::max(column + column_width, out.left + title.width) + kMargin;
  out.height = std::max(raster.bottom() + kTick + kTickGap + 2 * label_h + 6,
                        legend_bottom(out.text.legend, legend_top)) +
               kMargin;
  if (out.width > kMaxSide || out.height > kMaxSide) {
    throw PngError("write_damage_map_png: picture too large");
  }

  Surface s(out.width, out.height);
  cairo_t* cr = s.cr.get();
  cairo_set_antialias(cr, CAIRO_ANTIALIAS_NONE);  // the nodes: whole pixels, exact colours
  draw_nodes(cr, g, out.left, out.top, x, y, dx, [&](std::size_t i) {
    if (have_notch && damage[i] > 0.0 && damage[i] <= map.notch_damage[i] + 1e-6) {
      return notch_color(damage[i]);
    }
    return damage_color(damage[i]);
  });
  cairo_set_antialias(cr, CAIRO_ANTIALIAS_DEFAULT);
  const Frame f{raster, ax, ay};
  cairo_save(cr);
  cairo_rectangle(cr, raster.left, raster.top, raster.width, raster.height);
  cairo_clip(cr);
  for (const auto& notch : map.notches) {
    Polyline p(cr, 3, kBlack);
    for (const auto& q : notch) p.add(f.px(1e3 * q.x), f.py(1e3 * q.y));
    p.flush();
  }
  for (const auto& crack : map.crack_paths) {
    Polyline p(cr, 3, kCrackPath);
    for (const auto& q : crack) p.add(f.px(1e3 * q.x), f.py(1e3 * q.y));
    p.flush();
    if (!crack.empty())
      dot(cr, f.px(1e3 * crack.back().x), f.py(1e3 * crack.back().y), 4.5,
          kCrackPath);  // the tip now
  }
  // The gauges over the cracks: the bars, then their labels on white plates.
  for (const auto& gauge : map.gauges)
    out.gauges.push_back(gauge_mark(f, gauge, dx, g.node_pixels));
  if (!out.gauges.empty()) {
    std::vector<std::vector<MapPoint>> lines = map.notches;
    lines.insert(lines.end(), map.crack_paths.begin(), map.crack_paths.end());
    place_gauge_labels(ts, raster, line_boxes(f, lines), out.gauges);
  }
  for (const auto& m : out.gauges) draw_gauge_bar(cr, m);
  for (const auto& m : out.gauges) {
    fill_box(cr, m.label, {255, 255, 255});
    cairo_rectangle(cr, m.label.left + 0.5, m.label.top + 0.5, m.label.width - 1,
                    m.label.height - 1);
    set_colour(cr, kGaugeColor);
    cairo_set_line_width(cr, 1.0);
    cairo_stroke(cr);
    ts.draw(cr, m.label.left + kPlatePad, m.label.top + kPlatePad, m.id, Face::small, kBlack);
  }
  cairo_restore(cr);
  draw_axes(cr, ts, f, "x [mm]", "y [mm]", kMargin, false, out.text);
  out.text.title = ts.draw(cr, out.left, kMargin, map.title, Face::title, kBlack);

  out.colour_bar_title = ts.draw(cr, column, raster.top, "damage φ", Face::text, kBlack);
  const Box& bar = out.colour_bar;
  for (int r = 0; r < bar.height; ++r) {
    const double phi = 1.0 - static_cast<double>(r) / (bar.height - 1);
    fill_box(cr, {bar.left, bar.top + r, bar.width, 1}, damage_color(phi));
  }
  for (int k = 0; k <= 4; ++k) {
    const int p = bar.top + static_cast<int>(std::lround((1.0 - 0.25 * k) * (bar.height - 1)));
    line(cr, bar.right(), p, bar.right() + kTick, p, 1, kBlack);
    char label[8];
    std::snprintf(label, sizeof label, "%.2f", 0.25 * k);
    out.colour_bar_labels.push_back(
        ts.draw(cr, bar.right() + kTick + kTickGap, p - label_h / 2, label, Face::text, kBlack));
  }
  draw_legend(cr, ts, legend, out.text.legend);
  save(s, path);
  return out;
}

PlotLayout write_crack_length_png(const std::filesystem::path& path, std::span<const double> cycles,
                                  std::span<const double> lengths_m, const PlotOptions& options) {
  if (cycles.size() != lengths_m.size()) {
    throw PngError("write_crack_length_png: cycles and lengths differ in size");
  }
  CrackGrowthPlot plot;
  plot.cycles.assign(cycles.begin(), cycles.end());
  plot.lengths_m.assign(lengths_m.begin(), lengths_m.end());
  return write_crack_growth_png(path, plot, options);
}

PlotLayout write_crack_growth_png(const std::filesystem::path& path, const CrackGrowthPlot& plot,
                                  const PlotOptions& options) {
  const std::size_t n = plot.cycles.size();
  if (plot.lengths_m.size() != n) {
    throw PngError("write_crack_growth_png: cycles and lengths differ in size");
  }
  check_plot_size(options, "write_crack_growth_png");
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
  bool estimates = false;
  for (const auto& p : plot.predictions) {
    if (!drawable(p)) continue;
    estimates = true;
    for (const double r : {p.remaining, p.low, p.high}) include_x(p.cycles + r);
  }
  const bool critical = std::isfinite(plot.critical_length_m);
  if (critical) y_hi = std::max(y_hi, 1e3 * plot.critical_length_m);

  PlotText text{plot.title, "cycles", "crack length [mm]", {}};
  text.legend.push_back({"crack length", line_sample(kLine, 3)});
  if (estimates) {
    text.legend.push_back({"predicted end (band)", [](cairo_t* cr, const Box& b) {
                             const double yc = b.top + 0.5 * b.height, xc = b.left + 0.5 * b.width;
                             line(cr, b.left + 2, yc, b.right() - 2, yc, 1, kEstimate);
                             line(cr, b.left + 2, yc - 3, b.left + 2, yc + 4, 1, kEstimate);
                             line(cr, b.right() - 3, yc - 3, b.right() - 3, yc + 4, 1, kEstimate);
                             diamond(cr, xc, yc, 5, kEstimate);
                           }});
  }
  if (critical) text.legend.push_back({"critical", line_sample(kCritical, 1, 6)});
  if (plot.end_of_life_cycle >= 0)
    text.legend.push_back({"end of life", line_sample(kCrackPath, 2)});

  PlotLayout out;
  Surface s(options.width, options.height);
  cairo_t* cr = s.cr.get();
  Typesetter ts;
  const Frame f = draw_plot(
      cr, ts, options.width, options.height, text, [&](int t) { return nice_axis(x_lo, x_hi, t); },
      std::max(2, options.width / 100), [&](int t) { return nice_axis(y_lo, y_hi, t); }, out);
  if (critical) {
    const double p = std::round(f.py(1e3 * plot.critical_length_m));
    line(cr, f.box.left, p, f.box.right(), p, 1, kCritical, 6);
  }
  // The estimates: band bar and a diamond at the central prediction; the latest one dashed.
  double latest = std::numeric_limits<double>::quiet_NaN();
  for (const auto& p : plot.predictions) {
    if (!drawable(p)) continue;
    const double py = std::round(f.py(1e3 * p.length_m));
    if (std::isfinite(p.low) && std::isfinite(p.high)) {
      const double a = std::round(f.px(p.cycles + p.low)), b = std::round(f.px(p.cycles + p.high));
      line(cr, a, py, b, py, 1, kEstimate);
      line(cr, a, py - 4, a, py + 5, 1, kEstimate);
      line(cr, b, py - 4, b, py + 5, 1, kEstimate);
    }
    diamond(cr, f.px(p.cycles + p.remaining), py + 0.5, 5, kEstimate);
    latest = p.cycles + p.remaining;
  }
  if (std::isfinite(latest)) {
    const double p = std::round(f.px(latest));
    line(cr, p, f.box.top, p, f.box.bottom(), 2, kEstimate, 8);
  }
  if (plot.end_of_life_cycle >= 0) {
    const double p = std::round(f.px(static_cast<double>(plot.end_of_life_cycle)));
    line(cr, p, f.box.top, p, f.box.bottom(), 2, kCrackPath);
  }
  Polyline curve(cr, 3, kLine);
  for (std::size_t i = 0; i < n; ++i) {
    curve.add(std::isfinite(plot.cycles[i]) ? f.px(plot.cycles[i]) : plot.cycles[i],
              f.py(1e3 * plot.lengths_m[i]));
  }
  curve.flush();
  save(s, path);
  return out;
}

PlotLayout write_line_plot_png(const std::filesystem::path& path, const LinePlot& plot,
                               const PlotOptions& options) {
  check_plot_size(options, "write_line_plot_png");
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
  PlotText text{plot.title, plot.x_title, plot.y_title, {}};
  for (const auto& s : plot.series) {
    text.legend.push_back({s.label, line_sample(s.color, 2, s.dashed ? 4.0 : 0.0)});
  }
  PlotLayout out;
  Surface surface(options.width, options.height);
  cairo_t* cr = surface.cr.get();
  Typesetter ts;
  const Frame f = draw_plot(
      cr, ts, options.width, options.height, text, [&](int t) { return exact_axis(x_lo, x_hi, t); },
      std::max(2, options.width / 100), [&](int t) { return nice_axis(y_lo, y_hi, t); }, out);
  cairo_save(cr);
  cairo_rectangle(cr, f.box.left, f.box.top, f.box.width, f.box.height);
  cairo_clip(cr);
  for (const auto& s : plot.series) {
    Polyline p(cr, 2, s.color, s.dashed ? 4.0 : 0.0);
    for (std::size_t i = 0; i < s.x.size(); ++i) {
      p.add(std::isfinite(s.x[i]) ? f.px(s.x[i]) : s.x[i],
            std::isfinite(s.y[i]) ? f.py(std::clamp(s.y[i], f.y.lo, f.y.hi)) : s.y[i]);
    }
    p.flush();
  }
  cairo_restore(cr);
  save(surface, path);
  return out;
}

}  // namespace peritwin::outputs
