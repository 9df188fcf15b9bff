#include "rll/eval/plot.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <tuple>

#include "rll/core/error.h"
#include "rll/core/image.h"
#include "rll/core/encode.h"
#include "rll/eval/raster.h"

namespace rll {

namespace {

struct Point {
  double x = 0, y = 0;
};

struct Polyline {
  std::vector<Point> points;
  uint32_t colour = 0;
  double width = 1;
};

// Font sizes in pixels (user units): labels and ticks, the title.
constexpr double kFontSize = 13.0, kTitleSize = 14.0;

// A region between two x-monotone lines that share their x: the spread of a series' repeats.
struct Band {
  std::vector<Point> upper, lower;
  uint32_t colour = 0;
  double opacity = 0.2;
};

enum class Anchor { Start, Middle, End };

struct Label {
  std::string text;
  double x = 0, y = 0;  // the anchor point; y is the middle of the text's height
  Anchor anchor = Anchor::Start;
  bool vertical = false;  // rotated 90 degrees counter-clockwise (reads bottom to top)
  uint32_t colour = 0;
  bool bold = false;
  double size = kFontSize;  // font size, pixels
  std::string full;         // the whole text, shown on hover, where `text` had to be cut
};

// A data point that names its values when the mouse is over it (an SVG <title>); drawn
// transparent, so that the PNG does not show it.
struct Marker {
  double x = 0, y = 0;
  uint32_t colour = 0;
  std::string text;
};

// The whole plot as primitives in pixel coordinates, y down: what both back ends draw, in this
// order: lines before data_begin (grid, frame), bands, the other lines, labels.
struct Drawing {
  int width = 0, height = 0;
  std::vector<Polyline> lines;
  size_t data_begin = 0;
  std::vector<Band> bands;
  std::vector<Label> labels;
  std::vector<Marker> markers;
};

// The smallest font size a label is set in to fit its room; below it the text is cut.
constexpr double kSmallestFontSize = 9.0;

// `l` made to fit `room` pixels of width: at its size, or smaller down to kSmallestFontSize,
// or at that size cut to the characters that fit with an ellipsis (the whole text in `full`).
Label fitted(Label l, double room) {
  const double w = text_width(l.text, l.size, l.bold);
  if (w <= room || !(w > 0)) return l;
  l.size = std::max(kSmallestFontSize, l.size * room / w);
  if (text_width(l.text, l.size, l.bold) <= room) return l;
  l.full = l.text;
  std::string cut = l.text;
  while (!cut.empty() && text_width(cut + "\u2026", l.size, l.bold) > room) {
    cut.pop_back();
    while (!cut.empty() && (static_cast<unsigned char>(cut.back()) & 0xc0) == 0x80) cut.pop_back();
    if (!cut.empty() && static_cast<unsigned char>(cut.back()) >= 0xc0) cut.pop_back();
  }
  l.text = cut + "\u2026";
  return l;
}

// A value for a hover text: "0.0123", "1.23e-5".
std::string value_text(double v) {
  return fmt::format("{:.3g}", v);
}

struct LogAxis {
  double lo = 0, hi = 1;  // log10 of the range ends
  double p0 = 0, p1 = 1;  // pixel positions of lo and hi
  double map(double v) const { return p0 + (std::log10(v) - lo) / (hi - lo) * (p1 - p0); }
};

// The log10 range covering every value, padded a little; a default for no values.
std::pair<double, double> log_range(const std::vector<double>& values, double default_lo,
                                    double default_hi) {
  if (values.empty()) return {std::log10(default_lo), std::log10(default_hi)};
  auto [mn, mx] = std::minmax_element(values.begin(), values.end());
  double lo = std::log10(*mn), hi = std::log10(*mx);
  if (hi - lo < 0.3) {
    const double mid = 0.5 * (lo + hi);
    lo = mid - 0.15;
    hi = mid + 0.15;
  }
  const double pad = 0.04 * (hi - lo);
  return {lo - pad, hi + pad};
}

constexpr uint32_t kAxisColour = 0x333333, kGridColour = 0xe4e4e4, kTextColour = 0x222222;
constexpr uint32_t kNoteColour = 0x666666;

bool usable(double x, double y) {
  return x > 0 && y > 0 && std::isfinite(x) && std::isfinite(y);
}

size_t usable_points(const std::vector<std::pair<double, double>>& curve) {
  size_t n = 0;
  for (const auto& [x, y] : curve) n += usable(x, y);
  return n;
}

// A curve on log axes: its usable points as (log10 x, log10 y) by increasing x.
struct LogCurve {
  std::vector<std::pair<double, double>> p;
  // log10 y at log10 x, linear between points (lx inside the curve's range).
  double y_at(double lx) const {
    auto it = std::lower_bound(p.begin(), p.end(), lx,
                               [](const auto& q, double v) { return q.first < v; });
    if (it == p.begin()) return it->second;
    if (it == p.end()) return p.back().second;
    const auto& a = *(it - 1);
    const auto& b = *it;
    return a.second + (lx - a.first) / (b.first - a.first) * (b.second - a.second);
  }
};

// The curves that span a range of x (two usable points at least, not all at one x).
std::vector<LogCurve> log_curves(
    const std::vector<std::vector<std::pair<double, double>>>& curves) {
  std::vector<LogCurve> logs;
  for (const auto& c : curves) {
    LogCurve lc;
    for (const auto& [x, y] : c)
      if (usable(x, y)) lc.p.emplace_back(std::log10(x), std::log10(y));
    std::stable_sort(lc.p.begin(), lc.p.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
    if (lc.p.size() >= 2 && lc.p.back().first > lc.p.front().first) logs.push_back(std::move(lc));
  }
  return logs;
}

Drawing layout(const LogLogPlot& plot) {
  Drawing d;
  d.width = plot.width;
  d.height = plot.height;
  std::vector<double> xs, ys;
  for (const auto& s : plot.series)
    for (const auto& c : s.curves)
      for (const auto& [x, y] : c)
        if (usable(x, y)) {
          xs.push_back(x);
          ys.push_back(y);
        }

  // Series with several curves are drawn as a band; the note under the title says so.
  std::vector<bool> banded;
  size_t fewest = SIZE_MAX, most = 0;
  for (const auto& s : plot.series) {
    const size_t n = log_curves(s.curves).size();
    banded.push_back(n >= 2);
    if (n >= 2) {
      fewest = std::min(fewest, n);
      most = std::max(most, n);
    }
  }
  std::string note;
  if (most > 0)
    note = fewest == most ? fmt::format("lines: median of {} repeats, bands: min to max", most)
                          : "lines: median over repeats, bands: min to max";

  LogAxis ax, ay;
  std::tie(ax.lo, ax.hi) = log_range(xs, 0.1, 10);
  std::tie(ay.lo, ay.hi) = log_range(ys, 1e-3, 1);
  // Margins from the text they hold: the widest y tick label beside the y axis' title, the
  // legend's names (up to 40% of the width), half the last x tick label.
  double tick_width = 0, legend_width = 0;
  for (double t : log_ticks(std::pow(10.0, ay.lo), std::pow(10.0, ay.hi)))
    tick_width = std::max(tick_width, text_width(tick_label(t), kFontSize));
  for (const auto& s : plot.series)
    legend_width = std::max(legend_width, text_width(s.name, kFontSize));
  double last_x_tick = 0;
  for (double t : log_ticks(std::pow(10.0, ax.lo), std::pow(10.0, ax.hi)))
    last_x_tick = text_width(tick_label(t), kFontSize);
  const double left = std::max(78.0, 40 + tick_width), top = note.empty() ? 40 : 56, bottom = 56;
  const double right = std::max(0.5 * last_x_tick + 4,
                                std::min(0.4 * plot.width, 44 + legend_width + 12));
  ax.p0 = left;
  ax.p1 = plot.width - right;
  ay.p0 = plot.height - bottom;  // y grows upwards
  ay.p1 = top;

  auto hline = [&](double x0, double x1, double y, uint32_t c) {
    d.lines.push_back({{{x0, y}, {x1, y}}, c, 1});
  };
  auto vline = [&](double x, double y0, double y1, uint32_t c) {
    d.lines.push_back({{{x, y0}, {x, y1}}, c, 1});
  };
  // Grid and ticks (pixel centres at .5 keep 1-pixel lines crisp in the PNG).
  for (double t : log_ticks(std::pow(10.0, ax.lo), std::pow(10.0, ax.hi))) {
    const double x = std::round(ax.map(t)) + 0.5;
    vline(x, ay.p1, ay.p0, kGridColour);
    vline(x, ay.p0, ay.p0 + 5, kAxisColour);
    d.labels.push_back({tick_label(t), x, ay.p0 + 17, Anchor::Middle, false, kTextColour});
  }
  for (double t : log_minor_ticks(std::pow(10.0, ax.lo), std::pow(10.0, ax.hi))) {
    const double x = std::round(ax.map(t)) + 0.5;
    vline(x, ay.p0, ay.p0 + 3, kAxisColour);
  }
  for (double t : log_minor_ticks(std::pow(10.0, ay.lo), std::pow(10.0, ay.hi))) {
    const double y = std::round(ay.map(t)) + 0.5;
    hline(ax.p0 - 3, ax.p0, y, kAxisColour);
  }
  for (double t : log_ticks(std::pow(10.0, ay.lo), std::pow(10.0, ay.hi))) {
    const double y = std::round(ay.map(t)) + 0.5;
    hline(ax.p0, ax.p1, y, kGridColour);
    hline(ax.p0 - 5, ax.p0, y, kAxisColour);
    d.labels.push_back({tick_label(t), ax.p0 - 9, y, Anchor::End, false, kTextColour});
  }
  // Frame.
  const double fx0 = std::round(ax.p0) + 0.5, fx1 = std::round(ax.p1) + 0.5;
  const double fy0 = std::round(ay.p1) + 0.5, fy1 = std::round(ay.p0) + 0.5;
  d.lines.push_back({{{fx0, fy0}, {fx1, fy0}, {fx1, fy1}, {fx0, fy1}, {fx0, fy0}}, kAxisColour, 1});

  // Data, clipped to the frame by construction (the ranges cover every point, and a band's
  // values are interpolated between points).
  d.data_begin = d.lines.size();
  for (size_t i = 0; i < plot.series.size(); ++i) {
    const PlotSeries& s = plot.series[i];
    if (banded[i]) {
      // The median line where every repeat has data, the band where two or more have; before
      // and after that, the repeats' own curves, thin: a median of fewer curves would jump
      // where one of them starts or ends.
      const std::vector<LogCurve> logs = log_curves(s.curves);
      double all_from = -HUGE_VAL, all_to = HUGE_VAL;
      for (const auto& lc : logs) {
        all_from = std::max(all_from, lc.p.front().first);
        all_to = std::min(all_to, lc.p.back().first);
      }
      Band band{{}, {}, s.colour, 0.2};
      Polyline median{{}, s.colour, 2.0};
      auto end_band = [&] {
        if (band.upper.size() >= 2) d.bands.push_back(band);
        band.upper.clear();
        band.lower.clear();
      };
      for (const BandPoint& p : repeat_band(s.curves)) {
        const double x = ax.map(p.x);
        if (p.count >= 2) {
          band.upper.push_back({x, ay.map(p.hi)});
          band.lower.push_back({x, ay.map(p.lo)});
        } else {
          end_band();
        }
        if (size_t(p.count) == logs.size()) median.points.push_back({x, ay.map(p.median)});
      }
      end_band();
      if (median.points.size() == 1) median.points.push_back(median.points[0]);
      if (!median.points.empty()) d.lines.push_back(std::move(median));
      for (const auto& lc : logs) {
        auto to_pixels = [&](double lx, double ly) {
          return Point{ax.map(std::pow(10.0, lx)), ay.map(std::pow(10.0, ly))};
        };
        Polyline head{{}, s.colour, 1.0}, tail{{}, s.colour, 1.0};
        for (const auto& [lx, ly] : lc.p) {
          if (lx < all_from) head.points.push_back(to_pixels(lx, ly));
          if (lx > all_to) tail.points.push_back(to_pixels(lx, ly));
        }
        if (!head.points.empty()) {  // joined to where the median starts
          head.points.push_back(to_pixels(all_from, lc.y_at(all_from)));
          d.lines.push_back(std::move(head));
        }
        if (!tail.points.empty()) {
          tail.points.insert(tail.points.begin(), to_pixels(all_to, lc.y_at(all_to)));
          d.lines.push_back(std::move(tail));
        }
      }
    }
    for (const auto& c : s.curves) {
      // A banded series keeps only its one-point curves (a run that never reached a second
      // checkpoint) as dots: the band stands for the others.
      if (banded[i] && usable_points(c) >= 2) continue;
      Polyline line{{}, s.colour, 2.0};
      for (const auto& [x, y] : c)
        if (usable(x, y)) line.points.push_back({ax.map(x), ay.map(y)});
      if (line.points.size() == 1) line.points.push_back(line.points[0]);  // a dot
      if (!line.points.empty()) d.lines.push_back(std::move(line));
    }
  }
  // Every usable point names its values on hover.
  for (const PlotSeries& s : plot.series)
    for (size_t r = 0; r < s.curves.size(); ++r)
      for (const auto& [x, y] : s.curves[r])
        if (usable(x, y))
          d.markers.push_back(
              {ax.map(x), ay.map(y), s.colour,
               fmt::format("{}{}: {} {}, {} {}", s.name,
                           s.curves.size() > 1 ? fmt::format(" (repeat {})", r + 1) : "",
                           plot.x_label, value_text(x), plot.y_label, value_text(y))});
  const double mid = 0.5 * (ax.p0 + ax.p1);
  if (xs.empty())
    d.labels.push_back(
        {"no data", mid, 0.5 * (ay.p0 + ay.p1), Anchor::Middle, false, kTextColour});

  // Titles and legend, each fitted to its room: a long title or name is set smaller, and cut
  // with an ellipsis only past that, never cut by the picture's edge.
  const double title_room = 2 * std::min(mid, plot.width - mid) - 8;
  d.labels.push_back(fitted(
      {plot.title, mid, 20, Anchor::Middle, false, kTextColour, true, kTitleSize}, title_room));
  if (!note.empty())
    d.labels.push_back(fitted({note, mid, 38, Anchor::Middle, false, kNoteColour}, title_room));
  d.labels.push_back(fitted(
      {plot.x_label, mid, plot.height - 16.0, Anchor::Middle, false, kTextColour}, title_room));
  d.labels.push_back(
      fitted({plot.y_label, 18, 0.5 * (ay.p0 + ay.p1), Anchor::Middle, true, kTextColour},
             ay.p0 - ay.p1));
  double ly = top + 10;
  for (size_t i = 0; i < plot.series.size(); ++i) {
    const PlotSeries& s = plot.series[i];
    const double lx = ax.p1 + 14;
    if (banded[i])
      d.bands.push_back(
          {{{lx, ly - 6}, {lx + 24, ly - 6}}, {{lx, ly + 6}, {lx + 24, ly + 6}}, s.colour, 0.2});
    d.lines.push_back({{{lx, ly}, {lx + 24, ly}}, s.colour, 3});
    d.labels.push_back(fitted({s.name, lx + 30, ly, Anchor::Start, false, kTextColour},
                              plot.width - (lx + 30) - 4));
    ly += 22;
  }
  return d;
}

// Both back ends draw in one order: grid and frame, bands, data and legend lines, labels.
template <class LineFn, class BandFn>
void for_each_shape(const Drawing& d, LineFn line, BandFn band) {
  for (size_t i = 0; i < d.data_begin && i < d.lines.size(); ++i) line(d.lines[i]);
  for (const auto& b : d.bands) band(b);
  for (size_t i = d.data_begin; i < d.lines.size(); ++i) line(d.lines[i]);
}

}  // namespace

uint32_t series_colour(size_t i) {
  static constexpr uint32_t palette[] = {0x1f77b4, 0xd62728, 0x2ca02c, 0xff7f0e, 0x9467bd,
                                         0x8c564b, 0xe377c2, 0x7f7f7f, 0xbcbd22, 0x17becf};
  return palette[i % std::size(palette)];
}

std::string css_colour(uint32_t rgb) {
  return fmt::format("#{:06x}", rgb & 0xffffff);
}

std::vector<double> log_ticks(double lo, double hi) {
  std::vector<double> ticks;
  if (!(lo > 0) || !(hi >= lo) || !std::isfinite(hi)) return ticks;
  const int k0 = int(std::floor(std::log10(lo))), k1 = int(std::ceil(std::log10(hi)));
  int decades_inside = 0;
  for (int k = k0; k <= k1; ++k)
    decades_inside += std::pow(10.0, k) >= lo && std::pow(10.0, k) <= hi;
  const bool fine = decades_inside < 3;
  for (int k = k0; k <= k1; ++k)
    for (double m : {1.0, 2.0, 5.0}) {
      if (m != 1.0 && !fine) continue;
      const double v = m * std::pow(10.0, k);
      // A little slack: the range ends are often exact decades computed through log10/pow.
      if (v >= lo * (1 - 1e-9) && v <= hi * (1 + 1e-9)) ticks.push_back(v);
    }
  return ticks;
}

std::vector<double> log_minor_ticks(double lo, double hi) {
  std::vector<double> ticks;
  if (!(lo > 0) || !(hi >= lo) || !std::isfinite(hi)) return ticks;
  const int k0 = int(std::floor(std::log10(lo))), k1 = int(std::ceil(std::log10(hi)));
  for (int k = k0; k <= k1; ++k)
    for (int m = 1; m <= 9; ++m) {
      const double v = m * std::pow(10.0, k);
      if (v >= lo && v <= hi) ticks.push_back(v);
    }
  return ticks;
}

std::string tick_label(double v) {
  if (v >= 1e-3 && v < 1e5) return fmt::format("{:g}", v);
  const int k = int(std::floor(std::log10(v) + 1e-9));
  const double m = v / std::pow(10.0, k);
  const long mi = std::lround(m);
  return std::abs(m - double(mi)) < 1e-6 ? fmt::format("{}e{}", mi, k)
                                         : fmt::format("{:.2g}e{}", m, k);
}

std::vector<BandPoint> repeat_band(
    const std::vector<std::vector<std::pair<double, double>>>& curves, int grid_points) {
  const std::vector<LogCurve> logs = log_curves(curves);
  std::vector<BandPoint> band;
  if (logs.empty() || grid_points < 1) return band;
  std::vector<double> grid;
  double lo = logs[0].p.front().first, hi = logs[0].p.back().first;
  for (const auto& lc : logs) {
    lo = std::min(lo, lc.p.front().first);
    hi = std::max(hi, lc.p.back().first);
    grid.push_back(lc.p.front().first);
    grid.push_back(lc.p.back().first);
  }
  for (int g = 0; g < grid_points; ++g)
    grid.push_back(grid_points == 1 ? lo : lo + (hi - lo) * g / (grid_points - 1));
  std::sort(grid.begin(), grid.end());
  // Grid points closer than this are one (an end of a curve and an even step that nearly meet).
  const double merge = 1e-9 * std::max(1.0, hi - lo);
  std::vector<double> ys;
  double last = -HUGE_VAL;
  for (const double lx : grid) {
    if (lx - last <= merge) continue;
    last = lx;
    ys.clear();
    for (const auto& lc : logs)
      if (lx >= lc.p.front().first && lx <= lc.p.back().first) ys.push_back(lc.y_at(lx));
    if (ys.empty()) continue;
    std::sort(ys.begin(), ys.end());
    const size_t m = ys.size() / 2;
    const double median = ys.size() % 2 ? ys[m] : 0.5 * (ys[m - 1] + ys[m]);
    band.push_back({std::pow(10.0, lx), std::pow(10.0, median), std::pow(10.0, ys.front()),
                    std::pow(10.0, ys.back()), int(ys.size())});
  }
  return band;
}

std::string side_by_side_png(const std::vector<const Image*>& images,
                             const std::vector<std::string>& captions, float exposure_stops) {
  if (images.empty()) fail("side by side: no images");
  if (captions.size() != images.size())
    fail("side by side: {} captions for {} images", captions.size(), images.size());
  const int w = images.front()->width(), h = images.front()->height();
  for (const Image* im : images)
    if (im->width() != w || im->height() != h)
      fail("side by side: an image is {}x{}, not {}x{} like the first", im->width(), im->height(),
           w, h);
  // About 60 characters across the image at most, never under 10 pixels: a 1920-pixel render
  // gets 80-pixel text, which stays readable when the whole row is shrunk to a page's width.
  const double scale = std::clamp(std::floor(w / 200.0), 1.0, 8.0);
  const double font_px = 10 * scale, pad = 5 * scale;
  // Each caption's lines ('\n'), the first bold, word-wrapped to the image's width by pango.
  std::vector<std::vector<std::pair<std::string, bool>>> lines(images.size());
  double band = 0;
  for (size_t i = 0; i < captions.size(); ++i) {
    double height = 0;
    size_t start = 0;
    for (bool first = true; start <= captions[i].size(); first = false) {
      size_t end = captions[i].find('\n', start);
      if (end == std::string::npos) end = captions[i].size();
      const std::string line = captions[i].substr(start, end - start);
      if (!line.empty()) {
        lines[i].emplace_back(line, first);
        height += wrapped_text_height(line, w, font_px, first);
      }
      start = end + 1;
    }
    band = std::max(band, height);
  }
  const int n = int(images.size());
  Canvas c(n * w + (n - 1) * kSideBySideGap, h + (band > 0 ? int(std::ceil(2 * pad + band)) : 0));
  const float exposure = std::exp2(exposure_stops);
  for (int i = 0; i < n; ++i) {
    const Image& im = *images[size_t(i)];
    const int x0 = i * (w + kSideBySideGap);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const Rgb v = im.at(x, y);
        c.set_pixel(x0 + x, y, to_srgb8(v.x, exposure), to_srgb8(v.y, exposure),
                    to_srgb8(v.z, exposure));
      }
    double y = h + pad;
    for (const auto& [text, bold] : lines[size_t(i)])
      y += c.text(x0, y, w, text, font_px, bold, kTextColour);
  }
  return c.png();
}

std::string plot_png(const LogLogPlot& plot) {
  return svg_to_png(plot_svg(plot));
}

std::string plot_svg(const LogLogPlot& plot) {
  if (plot.width < 200 || plot.height < 150)
    fail("plot size {}x{} is too small", plot.width, plot.height);
  const Drawing d = layout(plot);
  std::string s = fmt::format(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" viewBox=\"0 0 {0} {1}\" width=\"{0}\" "
      "height=\"{1}\" font-family=\"{2}\" font-size=\"{3}\" role=\"img\">\n<style>.pt:hover "
      "{{ fill-opacity: 1 }}</style>\n<rect width=\"100%\" height=\"100%\" fill=\"#fff\"/>\n",
      d.width, d.height, kFigureFontFamily, kFontSize);
  auto line = [&](const Polyline& line) {
    s += "<polyline fill=\"none\" stroke-linejoin=\"round\" stroke-linecap=\"round\" points=\"";
    for (const auto& p : line.points) s += fmt::format("{:.1f},{:.1f} ", p.x, p.y);
    s += fmt::format("\" stroke=\"{}\" stroke-width=\"{}\"/>\n", css_colour(line.colour),
                     line.width);
  };
  auto band = [&](const Band& b) {
    s += "<polygon class=\"band\" points=\"";
    for (const auto& p : b.upper) s += fmt::format("{:.1f},{:.1f} ", p.x, p.y);
    for (auto p = b.lower.rbegin(); p != b.lower.rend(); ++p)
      s += fmt::format("{:.1f},{:.1f} ", p->x, p->y);
    s += fmt::format("\" fill=\"{}\" fill-opacity=\"{}\" stroke=\"none\"/>\n", css_colour(b.colour),
                     b.opacity);
  };
  for_each_shape(d, line, band);
  for (const auto& l : d.labels) {
    const char* anchor = l.anchor == Anchor::Start    ? "start"
                         : l.anchor == Anchor::Middle ? "middle"
                                                      : "end";
    // The baseline 0.36 em below the middle centres DejaVu Sans' digits and capitals (cap height
    // 0.73 em) on l.y; not dominant-baseline, which librsvg does not follow.
    const double baseline = 0.36 * l.size;
    s += fmt::format("<text x=\"{:.1f}\" y=\"{:.1f}\" text-anchor=\"{}\" fill=\"{}\"",
                     l.vertical ? l.x + baseline : l.x, l.vertical ? l.y : l.y + baseline, anchor,
                     css_colour(l.colour));
    if (l.size != kFontSize) s += fmt::format(" font-size=\"{:.2f}\"", l.size);
    if (l.vertical)
      s += fmt::format(" transform=\"rotate(-90 {:.1f} {:.1f})\"", l.x + baseline, l.y);
    if (l.bold) s += " font-weight=\"bold\"";
    s += ">" + escape_markup(l.text);
    if (!l.full.empty()) s += "<title>" + escape_markup(l.full) + "</title>";
    s += "</text>\n";
  }
  for (const Marker& m : d.markers)
    s += fmt::format(
        "<circle class=\"pt\" cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"4\" fill=\"{}\" "
        "fill-opacity=\"0\"><title>{}</title></circle>\n",
        m.x, m.y, css_colour(m.colour), escape_markup(m.text));
  return s + "</svg>";
}

}  // namespace rll
