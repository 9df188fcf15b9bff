// rll's figures: repeats reduced to a median line over a min..max band on a common log grid, and
// the side-by-side picture with a caption band under every image.
#include <gtest/gtest.h>
#include <stb/stb_image.h>

#include <cmath>
#include <memory>

#include "rll/core/error.h"
#include "rll/core/image.h"
#include "rll/eval/plot.h"
#include "rll/eval/raster.h"

using namespace rll;

namespace {

using Curve = std::vector<std::pair<double, double>>;

struct Decoded {
  int w = 0, h = 0;
  std::unique_ptr<unsigned char, void (*)(void*)> px{nullptr, stbi_image_free};
  const unsigned char* at(int x, int y) const { return px.get() + 3 * (size_t(y) * w + x); }
};

Decoded decode(const std::string& png) {
  Decoded d;
  int n = 0;
  d.px.reset(stbi_load_from_memory(reinterpret_cast<const unsigned char*>(png.data()),
                                   int(png.size()), &d.w, &d.h, &n, 3));
  return d;
}

// Relative closeness: the band's values go through log10 and pow.
void expect_rel(double actual, double expected) {
  EXPECT_NEAR(actual, expected, 1e-9 * std::abs(expected)) << "expected " << expected;
}

}  // namespace

TEST(PlotBand, TwoCurvesOnOneRangeGiveGeometricMedianMinAndMax) {
  // y = 1/x and y = 4/x from x = 1 to 100: at x = 10 the values are 0.1 and 0.4, interpolated
  // on log axes; the median of two is their geometric mean, 0.2.
  const std::vector<Curve> curves = {{{1, 1}, {100, 0.01}}, {{1, 4}, {100, 0.04}}};
  const auto band = repeat_band(curves, 3);
  ASSERT_EQ(band.size(), 3u);
  const double x[] = {1, 10, 100}, lo[] = {1, 0.1, 0.01};
  for (size_t i = 0; i < 3; ++i) {
    expect_rel(band[i].x, x[i]);
    expect_rel(band[i].lo, lo[i]);
    expect_rel(band[i].hi, 4 * lo[i]);
    expect_rel(band[i].median, 2 * lo[i]);
    EXPECT_EQ(band[i].count, 2);
  }
}

TEST(PlotBand, CurvesCountOnlyInsideTheirOwnRange) {
  // A spans 1..100, C spans 10..1000; the grid holds both curves' ends and 3 even log steps
  // (1, 10^1.5, 1000).
  const std::vector<Curve> curves = {{{1, 1}, {100, 0.01}}, {{10, 1}, {1000, 0.001}}};
  const auto band = repeat_band(curves, 3);
  ASSERT_EQ(band.size(), 5u);
  const double x[] = {1, 10, std::pow(10, 1.5), 100, 1000};
  const int count[] = {1, 2, 2, 2, 1};
  for (size_t i = 0; i < 5; ++i) {
    expect_rel(band[i].x, x[i]);
    EXPECT_EQ(band[i].count, count[i]) << "at x = " << x[i];
  }
  expect_rel(band[0].median, 1);  // A alone: no extrapolation of C below its start
  // At 10: A = 0.1, C = 1 (its first point).
  expect_rel(band[1].lo, 0.1);
  expect_rel(band[1].hi, 1);
  expect_rel(band[1].median, std::sqrt(0.1));
  // At 10^1.5: A = 10^-1.5, C = 10^-0.75.
  expect_rel(band[2].lo, std::pow(10, -1.5));
  expect_rel(band[2].hi, std::pow(10, -0.75));
  expect_rel(band[4].median, 0.001);  // C alone
}

TEST(PlotBand, OddCountTakesTheMiddleCurveAndSkipsUnusablePoints) {
  // Constant curves 1, 2 and 8; unsorted points and points off the log axes are tolerated.
  const std::vector<Curve> curves = {{{10, 1}, {1, 1}},
                                     {{1, 2}, {0, 5}, {10, 2}, {5, -1}},
                                     {{1, 8}, {10, 8}},
                                     {{3, 100}}};  // one point: no range, left out
  const auto band = repeat_band(curves, 4);
  ASSERT_EQ(band.size(), 4u);
  for (const auto& p : band) {
    expect_rel(p.median, 2);
    expect_rel(p.lo, 1);
    expect_rel(p.hi, 8);
    EXPECT_EQ(p.count, 3);
  }
  EXPECT_TRUE(repeat_band({{{1, 1}}, {{2, 2}}}, 8).empty());
  EXPECT_TRUE(repeat_band({}, 8).empty());
}

namespace {
LogLogPlot band_plot(size_t repeats) {
  LogLogPlot p;
  p.title = "relMSE against time";
  p.x_label = "seconds";
  p.y_label = "relMSE";
  PlotSeries s{"power", series_colour(0), {}};
  // y = k/x for k from 1 to 100: a band two decades tall.
  for (size_t r = 0; r < repeats; ++r) {
    const double k = std::pow(100.0, repeats > 1 ? double(r) / double(repeats - 1) : 0.0);
    s.curves.push_back({{0.01, k * 100}, {0.1, k * 10}, {1, k}});
  }
  p.series.push_back(s);
  return p;
}

size_t count(const std::string& text, const std::string& part) {
  size_t n = 0;
  for (size_t at = 0; (at = text.find(part, at)) != std::string::npos; ++at) ++n;
  return n;
}
}  // namespace

TEST(PlotBand, SvgDrawsRepeatsAsOneMedianLineOverABand) {
  const std::string colour = css_colour(series_colour(0));
  const std::string three = plot_svg(band_plot(3));
  // The median and the legend swatch; not one line per repeat.
  EXPECT_EQ(count(three, "stroke=\"" + colour + "\""), 2u);
  EXPECT_EQ(count(three, "<polygon class=\"band\""), 2u);  // the band and its legend swatch
  EXPECT_NE(three.find("fill=\"" + colour + "\" fill-opacity=\"0.2\""), std::string::npos);
  EXPECT_NE(three.find("median of 3 repeats"), std::string::npos);
  const std::string one = plot_svg(band_plot(1));
  EXPECT_EQ(count(one, "<polygon"), 0u);
  EXPECT_EQ(count(one, "stroke=\"" + colour + "\""), 2u);  // its curve and the legend swatch
  EXPECT_EQ(one.find("median of"), std::string::npos);
}

TEST(PlotBand, PngFillsTheBandTranslucently) {
  if (!figures_built()) GTEST_SKIP() << "built with -DRLL_FIGURES=OFF: no PNG figures";
  // The band's inside is the series colour at 20% over white: (31, 119, 180) -> (210, 228, 240).
  auto tinted = [](const std::string& png) {
    const Decoded d = decode(png);
    EXPECT_NE(d.px, nullptr);
    size_t n = 0;
    for (int y = 0; y < d.h; ++y)
      for (int x = 0; x < d.w; ++x) {
        const unsigned char* p = d.at(x, y);
        n += std::abs(p[0] - 210) <= 1 && std::abs(p[1] - 228) <= 1 && std::abs(p[2] - 240) <= 1;
      }
    return n;
  };
  EXPECT_GT(tinted(plot_png(band_plot(3))), 20000u);
  EXPECT_LT(tinted(plot_png(band_plot(1))), 500u);
}

TEST(SideBySide, CaptionsAddALegibleBandUnderTheImages) {
  if (!figures_built()) GTEST_SKIP() << "built with -DRLL_FIGURES=OFF: no PNG figures";
  Image a(60, 40, Rgb(0.2f)), b(60, 40, Rgb(0.8f, 0.1f, 0.1f));
  const std::string png =
      side_by_side_png({&a, &b}, {"power\nrelMSE 1.23e-02, 64 spp", "reference"}, 1.0f);
  const Decoded d = decode(png);
  ASSERT_NE(d.px, nullptr);
  EXPECT_EQ(d.w, 2 * 60 + kSideBySideGap);
  EXPECT_GT(d.h, 40 + 2 * 7);  // room for two lines of text at least
  // The images keep their pixels, tone-mapped with the exposure (+1 stop).
  EXPECT_EQ(d.at(30, 20)[0], to_srgb8(0.2f, 2.0f));
  EXPECT_EQ(d.at(64 + 30, 20)[0], to_srgb8(0.8f, 2.0f));
  EXPECT_EQ(d.at(64 + 30, 20)[1], to_srgb8(0.1f, 2.0f));
  // The gap is white; each caption band holds dark text on white, inside its own column.
  EXPECT_EQ(d.at(61, 20)[0], 255);
  size_t dark[2] = {0, 0}, white = 0;
  for (int y = 40; y < d.h; ++y)
    for (int x = 0; x < d.w; ++x) {
      const unsigned char* p = d.at(x, y);
      const bool is_dark = p[0] < 80 && p[1] < 80 && p[2] < 80;
      if (is_dark && x < 60) ++dark[0];
      if (is_dark && x >= 64) ++dark[1];
      EXPECT_FALSE(is_dark && x >= 60 && x < 64) << "text in the gap at " << x << ", " << y;
      white += p[0] == 255 && p[1] == 255 && p[2] == 255;
    }
  EXPECT_GT(dark[0], 60u);
  EXPECT_GT(dark[1], 20u);
  EXPECT_GT(dark[0], dark[1]);  // more text under the first image
  EXPECT_GT(white, size_t(d.w * (d.h - 40)) / 2);
}

TEST(SideBySide, TextGrowsWithTheImage) {
  if (!figures_built()) GTEST_SKIP() << "built with -DRLL_FIGURES=OFF: no PNG figures";
  Image small(100, 50, Rgb(0.5f)), large(1600, 800, Rgb(0.5f));
  const Decoded s = decode(side_by_side_png({&small}, {"power"}, 0));
  const Decoded l = decode(side_by_side_png({&large}, {"power"}, 0));
  ASSERT_NE(s.px, nullptr);
  ASSERT_NE(l.px, nullptr);
  EXPECT_EQ(s.w, 100);
  const int band_s = s.h - 50, band_l = l.h - 800;
  EXPECT_GT(band_s, 0);
  EXPECT_GE(band_l, 6 * band_s);  // 8x text against 1x
}

TEST(SideBySide, RejectsMismatchedInput) {
  Image a(10, 10), b(12, 10);
  EXPECT_THROW(side_by_side_png({&a, &b}, {"a", "b"}, 0), Error);
  EXPECT_THROW(side_by_side_png({&a}, {"a", "b"}, 0), Error);
  EXPECT_THROW(side_by_side_png({}, {}, 0), Error);
}
