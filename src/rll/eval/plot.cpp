#include "rll/eval/plot.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <tuple>

#include "rll/core/error.h"
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

enum class Anchor { Start, Middle, End };

struct Label {
  std::string text;
  double x = 0, y = 0;  // the anchor point; y is the middle of the text's height
  Anchor anchor = Anchor::Start;
  bool vertical = false;  // rotated 90 degrees counter-clockwise (reads bottom to top)
  uint32_t colour = 0;
  bool bold = false;
};

// The whole plot as primitives in pixel coordinates, y down: what both back ends draw.
struct Drawing {
  int width = 0, height = 0;
  std::vector<Polyline> lines;
  std::vector<Label> labels;
};

// stb_easy_font draws glyphs about 7 units tall; the PNG scales them up by this factor, and the
// SVG uses a font size that takes about the same width.
constexpr double kTextScale = 2.0;
constexpr double kSvgFontSize = 13.0;

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

Drawing layout(const LogLogPlot& plot) {
  Drawing d;
  d.width = plot.width;
  d.height = plot.height;
  std::vector<double> xs, ys;
  for (const auto& s : plot.series)
    for (const auto& c : s.curves)
      for (const auto& [x, y] : c)
        if (x > 0 && y > 0 && std::isfinite(x) && std::isfinite(y)) {
          xs.push_back(x);
          ys.push_back(y);
        }

  double legend_width = 0;
  for (const auto& s : plot.series) legend_width = std::max(legend_width, text_width(s.name));
  const double left = 78, top = 40, bottom = 56;
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

  // Data, clipped to the frame by construction (the ranges cover every point).
  for (const auto& s : plot.series)
    for (const auto& c : s.curves) {
      Polyline line{{}, s.colour, 2.0};
      for (const auto& [x, y] : c)
        if (x > 0 && y > 0 && std::isfinite(x) && std::isfinite(y))
          line.points.push_back({ax.map(x), ay.map(y)});
      if (line.points.size() == 1) line.points.push_back(line.points[0]);  // a dot
      if (!line.points.empty()) d.lines.push_back(std::move(line));
    }
  if (xs.empty())
    d.labels.push_back({"no data", 0.5 * (ax.p0 + ax.p1), 0.5 * (ay.p0 + ay.p1), Anchor::Middle,
                        false, kTextColour});

  // Titles and legend.
  d.labels.push_back(
      {plot.title, 0.5 * (ax.p0 + ax.p1), top / 2, Anchor::Middle, false, kTextColour, true});
  d.labels.push_back({plot.x_label, 0.5 * (ax.p0 + ax.p1), plot.height - 16.0, Anchor::Middle,
                      false, kTextColour});
  d.labels.push_back({plot.y_label, 18, 0.5 * (ay.p0 + ay.p1), Anchor::Middle, true, kTextColour});
  double ly = top + 10;
  for (const auto& s : plot.series) {
    const double lx = ax.p1 + 14;
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
    const double w = stb_easy_font_width(text.data()) * kTextScale;
    const double h = 7 * kTextScale;  // cap height of the font
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
        const double u0 = offset + std::min(v0[0], v2[0]) * kTextScale + pass;
        const double u1 = offset + std::max(v0[0], v2[0]) * kTextScale + pass;
        const double w0 = std::min(v0[1], v2[1]) * kTextScale - 0.5 * h;
        const double w1 = std::max(v0[1], v2[1]) * kTextScale - 0.5 * h;
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
    const int ix0 = std::max(0, int(std::lround(x0))), ix1 = std::min(m_w, int(std::lround(x1)));
    const int iy0 = std::max(0, int(std::lround(y0))), iy1 = std::min(m_h, int(std::lround(y1)));
    for (int y = iy0; y < iy1; ++y)
      for (int x = ix0; x < ix1; ++x) blend(x, y, colour, 1.0f);
  }

  int m_w, m_h;
  std::vector<uint8_t> m_rgb;
  std::vector<float> m_cover;
};

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

std::string plot_png(const LogLogPlot& plot) {
  if (plot.width < 200 || plot.height < 150)
    fail("plot size {}x{} is too small", plot.width, plot.height);
  const Drawing d = layout(plot);
  Raster r(d.width, d.height);
  for (const auto& line : d.lines) r.polyline(line);
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
  for (const auto& line : d.lines) {
    s += "<polyline fill=\"none\" stroke-linejoin=\"round\" stroke-linecap=\"round\" points=\"";
    for (const auto& p : line.points) s += fmt::format("{:.1f},{:.1f} ", p.x, p.y);
    s += fmt::format("\" stroke=\"{}\" stroke-width=\"{}\"/>\n", css_colour(line.colour),
                     line.width);
  }
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
