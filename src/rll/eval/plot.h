// rll's figures: log-log line plots (an error metric against time) as inline SVG for HTML reports,
// with real text and points that name their values on hover, and as PNG (the same SVG rasterized
// by librsvg, eval/raster.h); and the labelled row of images published as side-by-side.png.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace rll {

class Image;

struct PlotSeries {
  std::string name;
  uint32_t colour = 0;  // 0xRRGGBB
  // One curve per repeat, points (x, y); points with x <= 0 or y <= 0 cannot be placed on log
  // axes and are skipped. One curve is drawn as it is; several as their median line over a
  // min..max band (see repeat_band), so that repeats read as one result with its spread.
  std::vector<std::vector<std::pair<double, double>>> curves;
};

struct LogLogPlot {
  std::string title, x_label, y_label;
  std::vector<PlotSeries> series;
  int width = 760, height = 460;  // pixels (PNG) or user units (SVG)
};

// A series' repeats reduced on a common grid: at each x, the median, smallest and largest y of
// the curves whose x range holds it.
struct BandPoint {
  double x = 0, median = 0, lo = 0, hi = 0;
  int count = 0;  // curves that hold x
};
// Every curve with two usable points at different x at least is resampled on one grid: the ends
// of every such curve and `grid_points` x spaced evenly in log x from the smallest to the largest
// x of them; log y is interpolated linearly in log x, and only inside the curve's own x range (no
// extrapolation). The median of an even count is the geometric mean of the middle two. Grid x
// that no curve holds are left out. Exposed for tests.
std::vector<BandPoint> repeat_band(
    const std::vector<std::vector<std::pair<double, double>>>& curves, int grid_points = 64);

// The colour of the i-th series: a fixed qualitative palette, repeating after ten.
uint32_t series_colour(size_t i);
// "#rrggbb".
std::string css_colour(uint32_t rgb);

// An <svg> element, self-contained, to be embedded in HTML. Text is set in the figure font
// (raster.h); a title, axis title or legend name too wide for its room is set smaller (down to
// 9 pixels) and past that cut with an ellipsis, its whole text on hover, so that no text is cut
// by the picture's edge. Throws rll::Error for a plot under 200x150.
std::string plot_svg(const LogLogPlot& plot);
// plot_svg rasterized: the contents of a PNG file.
std::string plot_png(const LogLogPlot& plot);

// The side-by-side picture: the images in one row, 4 white pixels apart (kSideBySideGap), each
// tone-mapped to sRGB with `exposure_stops`, and under each its caption in dark text on a white
// band (the images keep their rows 0..h-1; the band adds rows below). Captions hold lines
// separated by '\n', the first drawn bold (the sampler's name), and are word-wrapped to the
// image's width by pango (raster.h); the font grows with the image width so that the text stays
// legible when the picture is shown at a size that fits a page. Throws rll::Error unless there is one caption per
// image and all images have one size. Returns the contents of a PNG file.
constexpr int kSideBySideGap = 4;
std::string side_by_side_png(const std::vector<const Image*>& images,
                             const std::vector<std::string>& captions, float exposure_stops);

// Labelled tick positions of a log axis spanning [lo, hi] (lo > 0): every decade inside, plus 2x
// and 5x of each decade when fewer than three decades fall inside. Exposed for tests.
std::vector<double> log_ticks(double lo, double hi);
// Unlabelled ticks: 1x to 9x of every decade, inside [lo, hi].
std::vector<double> log_minor_ticks(double lo, double hi);
// A tick value as short text: "0.01", "1", "200", "1e-05" -> "1e-5", "2e+06" -> "2e6".
std::string tick_label(double v);

}  // namespace rll
