// Log-log line plots (relMSE against time) drawn by rll itself, as a PNG (a small rasterizer,
// text from stb_easy_font) and as inline SVG for HTML reports; both come from one layout.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace rll {

struct PlotSeries {
  std::string name;
  uint32_t colour = 0;  // 0xRRGGBB
  // One polyline per curve (e.g. per repeat), points (x, y); points with x <= 0 or y <= 0
  // cannot be placed on log axes and are skipped.
  std::vector<std::vector<std::pair<double, double>>> curves;
};

struct LogLogPlot {
  std::string title, x_label, y_label;
  std::vector<PlotSeries> series;
  int width = 760, height = 460;  // pixels (PNG) or user units (SVG)
};

// The colour of the i-th series: a fixed qualitative palette, repeating after ten.
uint32_t series_colour(size_t i);
// "#rrggbb".
std::string css_colour(uint32_t rgb);

// The contents of a PNG file.
std::string plot_png(const LogLogPlot& plot);
// An <svg> element, self-contained, to be embedded in HTML.
std::string plot_svg(const LogLogPlot& plot);

// Labelled tick positions of a log axis spanning [lo, hi] (lo > 0): every decade inside, plus 2x
// and 5x of each decade when fewer than three decades fall inside. Exposed for tests.
std::vector<double> log_ticks(double lo, double hi);
// Unlabelled ticks: 1x to 9x of every decade, inside [lo, hi].
std::vector<double> log_minor_ticks(double lo, double hi);
// A tick value as short text: "0.01", "1", "200", "1e-05" -> "1e-5", "2e+06" -> "2e6".
std::string tick_label(double v);

}  // namespace rll
