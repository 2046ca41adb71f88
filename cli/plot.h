// Plots as PNG files (cairo): line/point plots in one or more panels, bar charts and category
// maps (e.g. a stability map over a gain grid). Every file is written atomically.
//
//   plot::Figure f{"Contact force", "time [s]", "force [N]"};
//   f.series.push_back({"force", t, F});
//   plot::write_png({f}, "force.png");
#pragma once

#include <string>
#include <vector>

namespace dentsim::plot {

struct Series {
  std::string label;
  std::vector<double> x, y;
  bool points = false;   // markers instead of a line
  int color = -1;        // index into the palette; -1 = next colour
  bool dashed = false;
};

struct Figure {
  std::string title, xlabel, ylabel;
  std::vector<Series> series;
  bool log_y = false;
  bool log_x = false;
};

struct BarChart {
  std::string title, ylabel;
  std::vector<std::string> labels;             // one group per label
  std::vector<std::string> set_names;          // one bar per set in each group (legend)
  std::vector<std::vector<double>> values;     // values[set][group]
};

// A grid of categories: cell (ix, iy) has category cells[iy * xs.size() + ix] (index into
// category_names; -1 = not run). Axis values are printed as tick labels.
struct CategoryMap {
  std::string title, xlabel, ylabel;
  std::vector<double> xs, ys;
  std::vector<int> cells;
  std::vector<std::string> category_names;
  std::vector<int> category_colors;            // palette index per category (optional)
};

// Panels laid out in `columns` columns; width/height per panel in pixels.
void write_png(const std::vector<Figure>& panels, const std::string& path, int columns = 1,
               int panel_width = 900, int panel_height = 420);
void write_png(const BarChart& chart, const std::string& path, int width = 900, int height = 480);
void write_png(const std::vector<CategoryMap>& maps, const std::string& path, int columns = 3,
               int panel_width = 420, int panel_height = 400);

}  // namespace dentsim::plot
