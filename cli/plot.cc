#include "cli/plot.h"

#include <cairo.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <unistd.h>

namespace dentsim::plot {
namespace {

struct Rgb {
  double r, g, b;
};
// Colour-blind-friendly palette (Okabe-Ito), then greys.
constexpr Rgb kPalette[] = {{0.00, 0.45, 0.70}, {0.90, 0.62, 0.00}, {0.00, 0.62, 0.45},
                            {0.80, 0.40, 0.00}, {0.80, 0.47, 0.65}, {0.34, 0.71, 0.91},
                            {0.94, 0.89, 0.26}, {0.35, 0.35, 0.35}, {0.75, 0.75, 0.75}};
constexpr double kPi = std::numbers::pi;
constexpr int kPaletteSize = sizeof(kPalette) / sizeof(kPalette[0]);

void set_color(cairo_t* cr, int i, double alpha = 1.0) {
  const Rgb& c = kPalette[((i % kPaletteSize) + kPaletteSize) % kPaletteSize];
  cairo_set_source_rgba(cr, c.r, c.g, c.b, alpha);
}

// "Nice" tick spacing covering [lo, hi] with about n ticks.
double nice_step(double span, int n) {
  const double raw = span / std::max(1, n);
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  const double f = raw / mag;
  const double nice = f < 1.5 ? 1 : f < 3 ? 2 : f < 7 ? 5 : 10;
  return nice * mag;
}

std::string fmt_num(double v) {
  char buf[32];
  const double a = std::abs(v);
  if (a != 0.0 && (a < 1e-3 || a >= 1e5)) {
    std::snprintf(buf, sizeof buf, "%.2g", v);
  } else {
    std::snprintf(buf, sizeof buf, "%.4g", v);
  }
  return buf;
}

void text(cairo_t* cr, double x, double y, const std::string& s, double size, double align_x,
          double align_y, bool bold = false, double angle = 0.0) {
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL,
                         bold ? CAIRO_FONT_WEIGHT_BOLD : CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, size);
  cairo_text_extents_t e;
  cairo_text_extents(cr, s.c_str(), &e);
  cairo_save(cr);
  cairo_translate(cr, x, y);
  cairo_rotate(cr, angle);
  cairo_move_to(cr, -e.width * align_x - e.x_bearing, e.height * (1.0 - align_y) * 1.0 -
                                                          (e.height + e.y_bearing));
  cairo_show_text(cr, s.c_str());
  cairo_restore(cr);
}

struct Range {
  double lo = std::numeric_limits<double>::infinity();
  double hi = -std::numeric_limits<double>::infinity();
  void add(double v) {
    if (!std::isfinite(v)) return;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  void finish() {
    if (!(lo <= hi)) {
      lo = 0.0;
      hi = 1.0;
    }
    if (hi - lo < 1e-300 * std::max(1.0, std::abs(hi))) {
      const double pad = lo == 0.0 ? 1.0 : 0.1 * std::abs(lo);
      lo -= pad;
      hi += pad;
    }
  }
  // After finish(): widens [lo, hi] by `fraction` of its span on each side.
  void pad(double fraction) {
    const double d = fraction * (hi - lo);
    lo -= d;
    hi += d;
  }
};

// An RGB image surface and its drawing context, released on scope exit.
class Canvas {
 public:
  Canvas(int width, int height, double grey)
      : surface_(cairo_image_surface_create(CAIRO_FORMAT_RGB24, width, height)),
        cr_(cairo_create(surface_)) {
    cairo_set_source_rgb(cr_, grey, grey, grey);
    cairo_paint(cr_);
  }
  ~Canvas() {
    cairo_destroy(cr_);
    cairo_surface_destroy(surface_);
  }
  Canvas(const Canvas&) = delete;
  Canvas& operator=(const Canvas&) = delete;
  cairo_t* cr() const { return cr_; }
  void save(const std::string& path);

 private:
  cairo_surface_t* surface_;
  cairo_t* cr_;
};

void write_surface(cairo_surface_t* surface, const std::string& path) {
  const std::string tmp = path + ".tmp." + std::to_string(::getpid()) + ".png";
  const cairo_status_t st = cairo_surface_write_to_png(surface, tmp.c_str());
  if (st != CAIRO_STATUS_SUCCESS) {
    std::remove(tmp.c_str());
    throw std::runtime_error("cannot write '" + path + "': " + cairo_status_to_string(st));
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    std::remove(tmp.c_str());
    throw std::runtime_error("cannot write '" + path + "'");
  }
}

// Draws one figure in the box (x0, y0, w, h).
void draw_figure(cairo_t* cr, const Figure& f, double x0, double y0, double w, double h) {
  const double ml = 78, mr = 20, mt = 34, mb = 52;
  const double px = x0 + ml, py = y0 + mt, pw = w - ml - mr, ph = h - mt - mb;
  auto tx = [&](double v) { return f.log_x ? std::log10(std::max(v, 1e-300)) : v; };
  auto ty = [&](double v) { return f.log_y ? std::log10(std::max(v, 1e-300)) : v; };
  Range rx, ry;
  for (const Series& s : f.series) {
    for (std::size_t i = 0; i < s.x.size() && i < s.y.size(); ++i) {
      if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) continue;
      if ((f.log_x && s.x[i] <= 0) || (f.log_y && s.y[i] <= 0)) continue;
      rx.add(tx(s.x[i]));
      ry.add(ty(s.y[i]));
    }
  }
  rx.finish();
  ry.finish();
  // Markers at the data's extremes would sit on the frame, half drawn: a figure with point series
  // keeps 5 % of each axis's span (in its own scale, log or linear) free on both sides.
  bool markers = false;
  for (const Series& s : f.series) markers = markers || s.points;
  if (markers) {
    rx.pad(0.05);
    ry.pad(0.05);
  }
  const double ypad = 0.05 * (ry.hi - ry.lo);
  ry.lo -= ypad;
  ry.hi += ypad;
  auto sx = [&](double v) { return px + (tx(v) - rx.lo) / (rx.hi - rx.lo) * pw; };
  auto sy = [&](double v) { return py + ph - (ty(v) - ry.lo) / (ry.hi - ry.lo) * ph; };

  // Frame, grid and ticks.
  cairo_set_source_rgb(cr, 1, 1, 1);
  cairo_rectangle(cr, px, py, pw, ph);
  cairo_fill(cr);
  cairo_set_line_width(cr, 1.0);
  const double xs = nice_step(rx.hi - rx.lo, 6), ys = nice_step(ry.hi - ry.lo, 5);
  for (double v = std::ceil(rx.lo / xs) * xs; v <= rx.hi + 1e-9 * xs; v += xs) {
    const double X = px + (v - rx.lo) / (rx.hi - rx.lo) * pw;
    cairo_set_source_rgb(cr, 0.9, 0.9, 0.9);
    cairo_move_to(cr, X, py);
    cairo_line_to(cr, X, py + ph);
    cairo_stroke(cr);
    cairo_set_source_rgb(cr, 0.2, 0.2, 0.2);
    text(cr, X, py + ph + 6, f.log_x ? fmt_num(std::pow(10.0, v)) : fmt_num(v), 11, 0.5, 0.0);
  }
  for (double v = std::ceil(ry.lo / ys) * ys; v <= ry.hi + 1e-9 * ys; v += ys) {
    const double Y = py + ph - (v - ry.lo) / (ry.hi - ry.lo) * ph;
    cairo_set_source_rgb(cr, 0.9, 0.9, 0.9);
    cairo_move_to(cr, px, Y);
    cairo_line_to(cr, px + pw, Y);
    cairo_stroke(cr);
    cairo_set_source_rgb(cr, 0.2, 0.2, 0.2);
    text(cr, px - 6, Y, f.log_y ? fmt_num(std::pow(10.0, v)) : fmt_num(std::abs(v) < 1e-12 * ys ? 0.0 : v),
         11, 1.0, 0.5);
  }
  cairo_set_source_rgb(cr, 0.3, 0.3, 0.3);
  cairo_rectangle(cr, px, py, pw, ph);
  cairo_stroke(cr);
  text(cr, px + pw / 2, y0 + 8, f.title, 14, 0.5, 0.0, true);
  text(cr, px + pw / 2, py + ph + 26, f.xlabel, 12, 0.5, 0.0);
  text(cr, x0 + 14, py + ph / 2, f.ylabel, 12, 0.5, 0.5, false, -kPi / 2);

  // Series, clipped to the plot area.
  cairo_save(cr);
  cairo_rectangle(cr, px, py, pw, ph);
  cairo_clip(cr);
  int auto_color = 0;
  std::vector<int> colors;
  for (const Series& s : f.series) {
    const int c = s.color >= 0 ? s.color : auto_color++;
    colors.push_back(c);
    set_color(cr, c);
    cairo_set_line_width(cr, 1.6);
    if (s.dashed) {
      const double d[] = {6.0, 4.0};
      cairo_set_dash(cr, d, 2, 0);
    } else {
      cairo_set_dash(cr, nullptr, 0, 0);
    }
    bool pen = false;
    for (std::size_t i = 0; i < s.x.size() && i < s.y.size(); ++i) {
      const bool ok = std::isfinite(s.x[i]) && std::isfinite(s.y[i]) &&
                      !(f.log_x && s.x[i] <= 0) && !(f.log_y && s.y[i] <= 0);
      if (!ok) {
        pen = false;
        continue;
      }
      const double X = sx(s.x[i]), Y = sy(s.y[i]);
      if (s.points) {
        cairo_arc(cr, X, Y, 2.6, 0, 2 * kPi);
        cairo_fill(cr);
      } else if (!pen) {
        cairo_move_to(cr, X, Y);
        pen = true;
      } else {
        cairo_line_to(cr, X, Y);
      }
    }
    if (!s.points) cairo_stroke(cr);
  }
  cairo_restore(cr);
  cairo_set_dash(cr, nullptr, 0, 0);

  // Legend (top right).
  double ly = py + 10;
  for (std::size_t i = 0; i < f.series.size(); ++i) {
    if (f.series[i].label.empty()) continue;
    set_color(cr, colors[i]);
    cairo_rectangle(cr, px + pw - 170, ly - 4, 14, 8);
    cairo_fill(cr);
    cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
    text(cr, px + pw - 150, ly, f.series[i].label, 11, 0.0, 0.5);
    ly += 16;
  }
}

void Canvas::save(const std::string& path) {
  cairo_surface_flush(surface_);
  write_surface(surface_, path);
}

}  // namespace

void write_png(const std::vector<Figure>& panels, const std::string& path, int columns,
               int panel_width, int panel_height) {
  if (panels.empty()) throw std::invalid_argument("plot: no panels for '" + path + "'");
  columns = std::max(1, columns);
  const int rows = static_cast<int>((panels.size() + columns - 1) / columns);
  Canvas canvas(columns * panel_width, rows * panel_height, 0.97);
  cairo_t* cr = canvas.cr();
  for (std::size_t i = 0; i < panels.size(); ++i) {
    const int r = static_cast<int>(i) / columns, c = static_cast<int>(i) % columns;
    draw_figure(cr, panels[i], c * panel_width, r * panel_height, panel_width, panel_height);
  }
  canvas.save(path);
}

void write_png(const BarChart& chart, const std::string& path, int width, int height) {
  Canvas canvas(width, height, 1.0);
  cairo_t* cr = canvas.cr();
  const double ml = 80, mr = 20, mt = 40, mb = 60;
  const double px = ml, py = mt, pw = width - ml - mr, ph = height - mt - mb;
  double hi = 0.0;
  for (const auto& set : chart.values) {
    for (double v : set) {
      if (std::isfinite(v)) hi = std::max(hi, v);
    }
  }
  if (hi <= 0) hi = 1;
  hi *= 1.12;
  const double ys = nice_step(hi, 5);
  cairo_set_line_width(cr, 1.0);
  for (double v = 0; v <= hi; v += ys) {
    const double Y = py + ph - v / hi * ph;
    cairo_set_source_rgb(cr, 0.9, 0.9, 0.9);
    cairo_move_to(cr, px, Y);
    cairo_line_to(cr, px + pw, Y);
    cairo_stroke(cr);
    cairo_set_source_rgb(cr, 0.2, 0.2, 0.2);
    text(cr, px - 6, Y, fmt_num(v), 11, 1.0, 0.5);
  }
  const std::size_t groups = chart.labels.size(), sets = chart.values.size();
  const double gw = pw / std::max<std::size_t>(1, groups);
  const double bw = 0.8 * gw / std::max<std::size_t>(1, sets);
  for (std::size_t g = 0; g < groups; ++g) {
    for (std::size_t s = 0; s < sets; ++s) {
      if (g >= chart.values[s].size() || !std::isfinite(chart.values[s][g])) continue;
      const double v = chart.values[s][g];
      const double X = px + g * gw + 0.1 * gw + s * bw;
      const double Y = py + ph - v / hi * ph;
      set_color(cr, static_cast<int>(s));
      cairo_rectangle(cr, X, Y, bw * 0.92, py + ph - Y);
      cairo_fill(cr);
      cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
      text(cr, X + bw * 0.46, Y - 4, fmt_num(v), 10, 0.5, 1.0);
    }
    cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
    text(cr, px + (g + 0.5) * gw, py + ph + 8, chart.labels[g], 12, 0.5, 0.0);
  }
  cairo_set_source_rgb(cr, 0.3, 0.3, 0.3);
  cairo_rectangle(cr, px, py, pw, ph);
  cairo_stroke(cr);
  text(cr, px + pw / 2, 10, chart.title, 14, 0.5, 0.0, true);
  text(cr, 16, py + ph / 2, chart.ylabel, 12, 0.5, 0.5, false, -kPi / 2);
  double lx = px + 10;
  for (std::size_t s = 0; s < chart.set_names.size(); ++s) {
    set_color(cr, static_cast<int>(s));
    cairo_rectangle(cr, lx, py + 8, 14, 8);
    cairo_fill(cr);
    cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
    text(cr, lx + 18, py + 12, chart.set_names[s], 11, 0.0, 0.5);
    lx += 30 + 7.0 * chart.set_names[s].size();
  }
  canvas.save(path);
}

void write_png(const std::vector<CategoryMap>& maps, const std::string& path, int columns,
               int panel_width, int panel_height) {
  if (maps.empty()) throw std::invalid_argument("plot: no maps for '" + path + "'");
  columns = std::max(1, columns);
  const int rows = static_cast<int>((maps.size() + columns - 1) / columns);
  Canvas canvas(columns * panel_width, rows * panel_height, 1.0);
  cairo_t* cr = canvas.cr();
  for (std::size_t m = 0; m < maps.size(); ++m) {
    const CategoryMap& map = maps[m];
    const double x0 = (m % columns) * panel_width, y0 = (m / columns) * panel_height;
    const double ml = 70, mr = 12, mt = 34, mb = 90;
    const double px = x0 + ml, py = y0 + mt, pw = panel_width - ml - mr,
                 ph = panel_height - mt - mb;
    const std::size_t nx = map.xs.size(), ny = map.ys.size();
    const double cw = pw / std::max<std::size_t>(1, nx), ch = ph / std::max<std::size_t>(1, ny);
    for (std::size_t iy = 0; iy < ny; ++iy) {
      for (std::size_t ix = 0; ix < nx; ++ix) {
        const std::size_t idx = iy * nx + ix;
        const int cat = idx < map.cells.size() ? map.cells[idx] : -1;
        if (cat < 0) {
          cairo_set_source_rgb(cr, 0.95, 0.95, 0.95);
        } else {
          const int col = static_cast<std::size_t>(cat) < map.category_colors.size()
                              ? map.category_colors[cat]
                              : cat;
          set_color(cr, col);
        }
        cairo_rectangle(cr, px + ix * cw + 1, py + ph - (iy + 1) * ch + 1, cw - 2, ch - 2);
        cairo_fill(cr);
      }
    }
    cairo_set_source_rgb(cr, 0.2, 0.2, 0.2);
    for (std::size_t ix = 0; ix < nx; ++ix) {
      text(cr, px + (ix + 0.5) * cw, py + ph + 4, fmt_num(map.xs[ix]), 9, 0.5, 0.0);
    }
    for (std::size_t iy = 0; iy < ny; ++iy) {
      text(cr, px - 4, py + ph - (iy + 0.5) * ch, fmt_num(map.ys[iy]), 9, 1.0, 0.5);
    }
    text(cr, px + pw / 2, y0 + 8, map.title, 13, 0.5, 0.0, true);
    text(cr, px + pw / 2, py + ph + 20, map.xlabel, 11, 0.5, 0.0);
    text(cr, x0 + 12, py + ph / 2, map.ylabel, 11, 0.5, 0.5, false, -kPi / 2);
    double ly = py + ph + 40;
    for (std::size_t c = 0; c < map.category_names.size(); ++c) {
      const int col = c < map.category_colors.size() ? map.category_colors[c] : static_cast<int>(c);
      set_color(cr, col);
      cairo_rectangle(cr, px, ly - 4, 12, 8);
      cairo_fill(cr);
      cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
      text(cr, px + 16, ly, map.category_names[c], 10, 0.0, 0.5);
      ly += 14;
    }
  }
  canvas.save(path);
}

}  // namespace dentsim::plot
