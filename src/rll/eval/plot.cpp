#include "rll/eval/plot.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <tuple>

#include "rll/core/error.h"
#include "rll/core/image.h"
#include "rll/eval/encode.h"

// stb_easy_font is all static functions, some of which plot.cpp does not call.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#pragma GCC diagnostic ignored "-Wsign-compare"
#include <stb/stb_easy_font.h>
#pragma GCC diagnostic pop

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

// stb_easy_font draws glyphs about 7 units tall; the PNG scales them up by this factor, and the
// SVG uses a font size that takes about the same width.
constexpr double kTextScale = 2.0;
constexpr double kSvgFontSize = 13.0;

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
  double scale = kTextScale;  // stb_easy_font units to pixels (PNG)
};

// The whole plot as primitives in pixel coordinates, y down: what both back ends draw, in this
// order: lines before data_begin (grid, frame), bands, the other lines, labels.
struct Drawing {
  int width = 0, height = 0;
  std::vector<Polyline> lines;
  size_t data_begin = 0;
  std::vector<Band> bands;
  std::vector<Label> labels;
};

double text_width(const std::string& text) {
  std::string copy = text;
  return stb_easy_font_width(copy.data()) * kTextScale;
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

  double legend_width = 0;
  for (const auto& s : plot.series) legend_width = std::max(legend_width, text_width(s.name));
  const double left = 78, top = note.empty() ? 40 : 56, bottom = 56;
  const double right = std::min(0.4 * plot.width, 44 + legend_width + 16);
  LogAxis ax, ay;
  std::tie(ax.lo, ax.hi) = log_range(xs, 0.1, 10);
  std::tie(ay.lo, ay.hi) = log_range(ys, 1e-3, 1);
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
    d.labels.push_back({tick_label(t), x, ay.p0 + 16, Anchor::Middle, false, kTextColour});
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
  if (xs.empty())
    d.labels.push_back({"no data", 0.5 * (ax.p0 + ax.p1), 0.5 * (ay.p0 + ay.p1), Anchor::Middle,
                        false, kTextColour});

  // Titles and legend.
  d.labels.push_back(
      {plot.title, 0.5 * (ax.p0 + ax.p1), 20, Anchor::Middle, false, kTextColour, true});
  if (!note.empty())
    d.labels.push_back({note, 0.5 * (ax.p0 + ax.p1), 38, Anchor::Middle, false, kNoteColour});
  d.labels.push_back({plot.x_label, 0.5 * (ax.p0 + ax.p1), plot.height - 16.0, Anchor::Middle,
                      false, kTextColour});
  d.labels.push_back({plot.y_label, 18, 0.5 * (ay.p0 + ay.p1), Anchor::Middle, true, kTextColour});
  double ly = top + 10;
  for (size_t i = 0; i < plot.series.size(); ++i) {
    const PlotSeries& s = plot.series[i];
    const double lx = ax.p1 + 14;
    if (banded[i])
      d.bands.push_back(
          {{{lx, ly - 6}, {lx + 24, ly - 6}}, {{lx, ly + 6}, {lx + 24, ly + 6}}, s.colour, 0.2});
    d.lines.push_back({{{lx, ly}, {lx + 24, ly}}, s.colour, 3});
    d.labels.push_back({s.name, lx + 30, ly, Anchor::Start, false, kTextColour});
    ly += 22;
  }
  return d;
}

// ---- PNG back end ----

class Raster {
 public:
  Raster(int w, int h)
      : m_w(w), m_h(h), m_rgb(size_t(w) * h * 3, 255), m_cover(size_t(w) * h, 0.f) {}

  uint8_t* pixel(int x, int y) { return &m_rgb[(size_t(y) * m_w + x) * 3]; }
  // Text is drawn only at x0 <= x < x1 (captions of neighbouring images must not run together).
  void clip_text(int x0, int x1) {
    m_clip0 = std::max(0, x0);
    m_clip1 = std::min(m_w, x1);
  }

  // A translucent band: per pixel column, four sub-columns each add the vertical overlap of
  // the pixel with the band there, which anti-aliases both edges.
  void band(const Band& b) {
    const size_t n = std::min(b.upper.size(), b.lower.size());
    if (n < 2) return;
    const double xa = b.upper.front().x, xb = b.upper[n - 1].x;
    const int x0 = std::max(0, int(std::floor(xa))), x1 = std::min(m_w - 1, int(std::ceil(xb)));
    int y_min = m_h, y_max = -1;
    size_t k = 0;
    for (int x = x0; x <= x1; ++x)
      for (int sub = 0; sub < 4; ++sub) {
        const double sx = x + (sub + 0.5) / 4;
        if (sx < xa || sx > xb) continue;
        while (k + 2 < n && b.upper[k + 1].x < sx) ++k;
        const double dx = b.upper[k + 1].x - b.upper[k].x;
        const double t = dx > 0 ? std::clamp((sx - b.upper[k].x) / dx, 0.0, 1.0) : 0.0;
        const double ua = b.upper[k].y + t * (b.upper[k + 1].y - b.upper[k].y);
        const double la = b.lower[k].y + t * (b.lower[k + 1].y - b.lower[k].y);
        const double ya = std::max(0.0, std::min(ua, la)),
                     yb = std::min(double(m_h), std::max(ua, la));
        for (int y = int(std::floor(ya)); y < int(std::ceil(yb)); ++y) {
          const double overlap = std::min(yb, y + 1.0) - std::max(ya, double(y));
          if (overlap > 0) m_cover[size_t(y) * m_w + x] += float(overlap / 4);
          y_min = std::min(y_min, y);
          y_max = std::max(y_max, y);
        }
      }
    for (int y = std::max(0, y_min); y <= y_max; ++y)
      for (int x = x0; x <= x1; ++x) {
        float& c = m_cover[size_t(y) * m_w + x];
        if (c > 0) blend(x, y, b.colour, float(b.opacity) * std::min(c, 1.0f));
        c = 0;
      }
  }

  // Anti-aliased thick polyline: coverage from the distance to the nearest segment, taken as a
  // maximum over segments so that joints are not blended twice.
  void polyline(const Polyline& line) {
    const double r = 0.5 * line.width;
    int bx0 = m_w, by0 = m_h, bx1 = -1, by1 = -1;
    for (size_t i = 0; i + 1 < line.points.size(); ++i) {
      const Point a = line.points[i], b = line.points[i + 1];
      const int x0 = std::max(0, int(std::floor(std::min(a.x, b.x) - r - 1)));
      const int x1 = std::min(m_w - 1, int(std::ceil(std::max(a.x, b.x) + r + 1)));
      const int y0 = std::max(0, int(std::floor(std::min(a.y, b.y) - r - 1)));
      const int y1 = std::min(m_h - 1, int(std::ceil(std::max(a.y, b.y) + r + 1)));
      const double dx = b.x - a.x, dy = b.y - a.y, len2 = dx * dx + dy * dy;
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) {
          const double px = x + 0.5 - a.x, py = y + 0.5 - a.y;
          const double t = len2 > 0 ? std::clamp((px * dx + py * dy) / len2, 0.0, 1.0) : 0.0;
          const double ex = px - t * dx, ey = py - t * dy;
          const float cover = float(std::clamp(r + 0.5 - std::sqrt(ex * ex + ey * ey), 0.0, 1.0));
          float& c = m_cover[size_t(y) * m_w + x];
          c = std::max(c, cover);
        }
      bx0 = std::min(bx0, x0);
      by0 = std::min(by0, y0);
      bx1 = std::max(bx1, x1);
      by1 = std::max(by1, y1);
    }
    for (int y = by0; y <= by1; ++y)
      for (int x = bx0; x <= bx1; ++x) {
        float& c = m_cover[size_t(y) * m_w + x];
        if (c > 0) blend(x, y, line.colour, c);
        c = 0;
      }
  }

  void label(const Label& l) {
    if (l.text.empty()) return;
    std::string text = l.text;
    std::vector<char> buffer(text.size() * 300 + 64);
    const int quads =
        stb_easy_font_print(0, 0, text.data(), nullptr, buffer.data(), int(buffer.size()));
    const double scale = l.scale;
    const double w = stb_easy_font_width(text.data()) * scale;
    const double h = 7 * scale;  // cap height of the font
    const double bold_offset = std::max(1.0, std::round(scale / 2));
    const double offset = l.anchor == Anchor::Start    ? 0
                          : l.anchor == Anchor::Middle ? -0.5 * w
                                                       : -w;
    for (int q = 0; q < quads; ++q) {
      // Each quad is axis-aligned: vertices 0 and 2 are opposite corners (16 bytes a vertex).
      float v0[2], v2[2];
      std::memcpy(v0, buffer.data() + size_t(q) * 64, sizeof v0);
      std::memcpy(v2, buffer.data() + size_t(q) * 64 + 32, sizeof v2);
      for (int pass = 0; pass < (l.bold ? 2 : 1); ++pass) {
        // Glyph space (u right along the text, v down) scaled, then placed at the anchor.
        const double u0 = offset + std::min(v0[0], v2[0]) * scale + pass * bold_offset;
        const double u1 = offset + std::max(v0[0], v2[0]) * scale + pass * bold_offset;
        const double w0 = std::min(v0[1], v2[1]) * scale - 0.5 * h;
        const double w1 = std::max(v0[1], v2[1]) * scale - 0.5 * h;
        if (!l.vertical)
          fill(l.x + u0, l.y + w0, l.x + u1, l.y + w1, l.colour);
        else
          fill(l.x + w0, l.y - u1, l.x + w1, l.y - u0, l.colour);
      }
    }
  }

  std::string png() const { return png_bytes(m_rgb, m_w, m_h, 3); }

 private:
  void blend(int x, int y, uint32_t colour, float a) {
    uint8_t* p = &m_rgb[(size_t(y) * m_w + x) * 3];
    const int c[3] = {int(colour >> 16) & 255, int(colour >> 8) & 255, int(colour) & 255};
    for (int k = 0; k < 3; ++k) p[k] = uint8_t(std::lround(p[k] + a * (c[k] - p[k])));
  }
  void fill(double x0, double y0, double x1, double y1, uint32_t colour) {
    const int ix0 = std::max(m_clip0, int(std::lround(x0)));
    const int ix1 = std::min(m_clip1, int(std::lround(x1)));
    const int iy0 = std::max(0, int(std::lround(y0))), iy1 = std::min(m_h, int(std::lround(y1)));
    for (int y = iy0; y < iy1; ++y)
      for (int x = ix0; x < ix1; ++x) blend(x, y, colour, 1.0f);
  }

  int m_w, m_h;
  int m_clip0 = 0, m_clip1 = m_w;
  std::vector<uint8_t> m_rgb;
  std::vector<float> m_cover;
};

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
  // About 60 characters across the image at most, never smaller than the font's own pixels: a
  // 1920-pixel render gets 8x text (56 pixels tall), which stays readable when the whole row is
  // shrunk to a page's width.
  const double scale = std::clamp(std::floor(w / 200.0), 1.0, 8.0);
  const double line_height = 12 * scale, pad = 5 * scale;
  auto width_of = [&](const std::string& t) {
    std::string copy = t;
    return stb_easy_font_width(copy.data()) * scale;
  };
  // Word wrap to the image's width; a word wider than that is cut at the column's edge.
  std::vector<std::vector<std::pair<std::string, bool>>> lines(images.size());  // text, bold
  size_t most_lines = 0;
  for (size_t i = 0; i < captions.size(); ++i) {
    size_t start = 0;
    for (bool first = true; start <= captions[i].size(); first = false) {
      size_t end = captions[i].find('\n', start);
      if (end == std::string::npos) end = captions[i].size();
      std::string line;
      size_t at = start;
      while (at < end) {
        size_t space = captions[i].find(' ', at);
        if (space == std::string::npos || space > end) space = end;
        const std::string word = captions[i].substr(at, space - at);
        const std::string joined = line.empty() ? word : line + " " + word;
        if (!line.empty() && width_of(joined) > w) {
          lines[i].emplace_back(line, first);
          line = word;
        } else {
          line = joined;
        }
        at = space + 1;
      }
      if (!line.empty()) lines[i].emplace_back(line, first);
      start = end + 1;
    }
    most_lines = std::max(most_lines, lines[i].size());
  }
  const int n = int(images.size());
  const int band = most_lines ? int(std::ceil(2 * pad + most_lines * line_height)) : 0;
  Raster r(n * w + (n - 1) * kSideBySideGap, h + band);
  const float exposure = std::exp2(exposure_stops);
  for (int i = 0; i < n; ++i) {
    const Image& im = *images[size_t(i)];
    const int x0 = i * (w + kSideBySideGap);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        uint8_t* p = r.pixel(x0 + x, y);
        for (int k = 0; k < 3; ++k) p[k] = to_srgb8(im.at(x, y)[k], exposure);
      }
    r.clip_text(x0, x0 + w);
    double y = h + pad + 0.5 * line_height;
    for (const auto& [text, bold] : lines[size_t(i)]) {
      Label l{text, double(x0), y, Anchor::Start, false, kTextColour, bold, scale};
      r.label(l);
      y += line_height;
    }
  }
  return r.png();
}

std::string plot_png(const LogLogPlot& plot) {
  if (plot.width < 200 || plot.height < 150)
    fail("plot size {}x{} is too small", plot.width, plot.height);
  const Drawing d = layout(plot);
  Raster r(d.width, d.height);
  for_each_shape(
      d, [&](const Polyline& l) { r.polyline(l); }, [&](const Band& b) { r.band(b); });
  for (const auto& label : d.labels) r.label(label);
  return r.png();
}

std::string plot_svg(const LogLogPlot& plot) {
  if (plot.width < 200 || plot.height < 150)
    fail("plot size {}x{} is too small", plot.width, plot.height);
  const Drawing d = layout(plot);
  std::string s = fmt::format(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" viewBox=\"0 0 {0} {1}\" width=\"{0}\" "
      "height=\"{1}\" font-family=\"sans-serif\" font-size=\"{2}\" role=\"img\">\n<rect "
      "width=\"100%\" height=\"100%\" fill=\"#fff\"/>\n",
      d.width, d.height, kSvgFontSize);
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
    s += fmt::format(
        "<text x=\"{:.1f}\" y=\"{:.1f}\" text-anchor=\"{}\" dominant-baseline=\"central\" "
        "fill=\"{}\"",
        l.x, l.y, anchor, css_colour(l.colour));
    if (l.vertical) s += fmt::format(" transform=\"rotate(-90 {:.1f} {:.1f})\"", l.x, l.y);
    if (l.bold) s += " font-weight=\"bold\"";
    s += ">" + escape_markup(l.text) + "</text>\n";
  }
  return s + "</svg>";
}

}  // namespace rll
