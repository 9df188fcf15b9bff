#include <gtest/gtest.h>
#include <stb/stb_image.h>

#include <cmath>

#include "rll/core/error.h"
#include "rll/eval/plot.h"
#include "rll/eval/raster.h"
#include "rll/eval/report.h"

using namespace rll;

TEST(Plot, LogTicks) {
  EXPECT_EQ(log_ticks(1e-4, 1), (std::vector<double>{1e-4, 1e-3, 1e-2, 1e-1, 1}));
  // Fewer than three decades inside: 2x and 5x are labelled too.
  const auto t = log_ticks(0.05, 3);
  ASSERT_EQ(t.size(), 6u);
  const double expected[] = {0.05, 0.1, 0.2, 0.5, 1, 2};
  for (size_t i = 0; i < t.size(); ++i) EXPECT_NEAR(t[i], expected[i], 1e-12);
  EXPECT_TRUE(log_ticks(0, 1).empty());
  EXPECT_EQ(log_minor_ticks(1, 10).size(), 10u);  // 1..9 and 10
}

TEST(Plot, TickLabels) {
  EXPECT_EQ(tick_label(0.01), "0.01");
  EXPECT_EQ(tick_label(1), "1");
  EXPECT_EQ(tick_label(200), "200");
  EXPECT_EQ(tick_label(1e-5), "1e-5");
  EXPECT_EQ(tick_label(2e6), "2e6");
}

namespace {
LogLogPlot two_series() {
  LogLogPlot p;
  p.title = "relMSE <against> time";
  p.x_label = "seconds";
  p.y_label = "relMSE";
  p.series.push_back({"power", series_colour(0), {{{0.1, 1.0}, {1, 0.1}, {10, 0.01}}}});
  p.series.push_back(
      {"rll", series_colour(1), {{{0.1, 0.5}, {1, 0.05}}, {{0.2, 0.3}, {0, 5}, {2, 0.03}}}});
  return p;
}
}  // namespace

TEST(Plot, PngHasTheSizeAndEverySeriesColour) {
  if (!figures_built()) GTEST_SKIP() << "built with -DRLL_FIGURES=OFF: no PNG figures";
  const LogLogPlot p = two_series();
  const std::string png = plot_png(p);
  int w = 0, h = 0, n = 0;
  unsigned char* px = stbi_load_from_memory(reinterpret_cast<const unsigned char*>(png.data()),
                                            int(png.size()), &w, &h, &n, 3);
  ASSERT_NE(px, nullptr);
  EXPECT_EQ(w, p.width);
  EXPECT_EQ(h, p.height);
  for (const auto& s : p.series) {
    const int r = int(s.colour >> 16), g = int(s.colour >> 8) & 255, b = int(s.colour) & 255;
    int hits = 0;
    for (int i = 0; i < w * h; ++i)
      hits += px[3 * i] == r && px[3 * i + 1] == g && px[3 * i + 2] == b;
    EXPECT_GT(hits, 200) << s.name;  // the curves, at least two pixels wide, and the legend
  }
  int dark = 0;  // text and axes
  for (int i = 0; i < w * h; ++i)
    dark += px[3 * i] < 80 && px[3 * i + 1] < 80 && px[3 * i + 2] < 80;
  EXPECT_GT(dark, 1000);
  stbi_image_free(px);
}

TEST(Plot, SvgHasCurvesLegendAndEscapedText) {
  const std::string svg = plot_svg(two_series());
  EXPECT_EQ(svg.rfind("<svg", 0), 0u);
  EXPECT_NE(svg.find(">power</text>"), std::string::npos);
  EXPECT_NE(svg.find(">rll</text>"), std::string::npos);
  EXPECT_NE(svg.find("relMSE &lt;against&gt; time"), std::string::npos);
  size_t curves = 0;
  for (size_t at = 0;
       (at = svg.find("stroke=\"" + css_colour(series_colour(1)) + "\"", at)) != std::string::npos;
       ++at)
    ++curves;
  // The median of the two repeats, the first's start and the second's end (thin, outside the
  // range both cover) and the legend swatch.
  EXPECT_EQ(curves, 4u);
  LogLogPlot tiny;
  tiny.width = tiny.height = 10;
  EXPECT_THROW(plot_svg(tiny), Error);
}

TEST(Plot, SvgPointsNameTheirValuesOnHover) {
  const std::string svg = plot_svg(two_series());
  EXPECT_NE(svg.find("<title>power: seconds 0.1, relMSE 1</title>"), std::string::npos) << svg;
  EXPECT_NE(svg.find("<title>rll (repeat 2): seconds 2, relMSE 0.03</title>"), std::string::npos);
  // Every usable point once: 3 of power, 2 + 2 of rll's repeats (the point at x = 0 is off the
  // log axes).
  size_t points = 0;
  for (size_t at = 0; (at = svg.find("<circle class=\"pt\"", at)) != std::string::npos; ++at)
    ++points;
  EXPECT_EQ(points, 7u);
}

TEST(Plot, PngLeavesItsBorderWhiteWithLongTexts) {
  if (!figures_built()) GTEST_SKIP() << "built with -DRLL_FIGURES=OFF: no PNG figures";
  // A title and names far wider than their room are set smaller and then cut with an ellipsis,
  // never cut by the edge: the outermost 2 pixels stay white.
  LogLogPlot p = two_series();
  p.title = std::string(200, 'W');
  p.series[0].name = std::string(80, 'm');
  p.y_label = std::string(120, 'M');
  const std::string png = plot_png(p);
  int w = 0, h = 0, n = 0;
  unsigned char* px = stbi_load_from_memory(reinterpret_cast<const unsigned char*>(png.data()),
                                            int(png.size()), &w, &h, &n, 3);
  ASSERT_NE(px, nullptr);
  int marked = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      if (x >= 2 && y >= 2 && x < w - 2 && y < h - 2) continue;
      const unsigned char* q = px + 3 * (size_t(y) * w + x);
      marked += q[0] < 250 || q[1] < 250 || q[2] < 250;
    }
  EXPECT_EQ(marked, 0);
  stbi_image_free(px);
  // The cut title keeps its whole text for the reader, on hover.
  const std::string svg = plot_svg(p);
  EXPECT_NE(svg.find("\u2026<title>" + p.title + "</title></text>"), std::string::npos);
}

TEST(Plot, EveryGlyphHasWidth) {
  if (!figures_built()) GTEST_SKIP() << "built with -DRLL_FIGURES=OFF: no PNG figures";
  // The figure font draws every printable ASCII character and the non-ASCII ones captions use.
  for (char c = '!'; c <= '~'; ++c) EXPECT_GT(text_width(std::string(1, c), 13), 2.0) << c;
  EXPECT_GT(text_width("\u00b5s \u2013 \u00b2", 13), 20.0);
  // "w" is not "u": the bitmap font this replaced drew them alike.
  EXPECT_GT(text_width("w", 13), text_width("u", 13));
}

TEST(Plot, EmptyPlotStillDraws) {
  if (!figures_built()) GTEST_SKIP() << "built with -DRLL_FIGURES=OFF: no PNG figures";
  LogLogPlot p;
  p.series.push_back({"none", series_colour(0), {{{0, 0}}}});
  EXPECT_NE(plot_svg(p).find("no data"), std::string::npos);
  EXPECT_FALSE(plot_png(p).empty());
}

TEST(Report, RgbeRoundTripsWithinItsPrecision) {
  Image img(6, 1);
  img[0] = Rgb(1.0f, 0.5f, 0.25f);
  img[1] = Rgb(1000.0f, 3.0f, 0.0f);
  img[2] = Rgb(1e-6f, 2e-6f, 3e-6f);
  img[3] = Rgb(0.0f);
  img[4] = Rgb(-1.0f, NAN, INFINITY);
  img[5] = Rgb(0.3f, 0.3f, 0.3f);
  std::vector<uint8_t> m, e;
  encode_rgbe(img, m, e);
  ASSERT_EQ(m.size(), 18u);
  ASSERT_EQ(e.size(), 6u);
  auto decode = [&](size_t i, int c) {
    return e[i] ? (m[3 * i + c] + 0.5) * std::ldexp(1.0, e[i] - 136) : 0.0;
  };
  for (size_t i : {0u, 1u, 2u, 5u}) {
    const double largest = std::max({img[i].x, img[i].y, img[i].z});
    for (int c = 0; c < 3; ++c)  // 8-bit mantissa relative to the largest channel
      EXPECT_NEAR(decode(i, c), img[i][c], largest / 128) << "pixel " << i << " channel " << c;
  }
  EXPECT_EQ(e[3], 0);
  EXPECT_EQ(decode(4, 0), 0.0);  // negative
  EXPECT_EQ(decode(4, 1), 0.0);  // NaN
}

TEST(Report, HtmlIsSelfContainedAndHasTheTable) {
  Image ref(4, 3, Rgb(0.5f)), a(4, 3, Rgb(0.4f)), b(4, 3, Rgb(0.6f));
  std::vector<float> ea(12, 0.01f), eb(12, 0.02f);
  Report r;
  r.title = "compare <scene>";
  r.facts = {{"budget", "1 s"}};
  r.warnings = {"a warning"};
  r.reference = &ref;
  r.entries = {{"power", "relMSE 1", 0x1f77b4, &a, &ea, ""},
               {"r<l>l", "relMSE 2", 0xd62728, &b, &eb, ""}};
  r.table = {{"sampler", "relMSE"}, {"power", "1"}, {"r<l>l", "2"}};
  r.plot_svg = "<svg id=\"plot\"></svg>";
  const std::string html = report_html(r);
  EXPECT_EQ(html.rfind("<!DOCTYPE html>", 0), 0u);
  EXPECT_NE(html.find("<table id=\"summary\">"), std::string::npos);
  EXPECT_NE(html.find("compare &lt;scene&gt;"), std::string::npos);
  EXPECT_NE(html.find("r&lt;l&gt;l"), std::string::npos);
  EXPECT_EQ(html.find("r<l>l"), std::string::npos);
  EXPECT_NE(html.find("<svg id=\"plot\"></svg>"), std::string::npos);
  EXPECT_NE(html.find("a warning"), std::string::npos);
  // Nothing is fetched: every image is a data URI (3 HDR images x 2 parts, 2 error maps and
  // the colour bar), and no other URL is referenced.
  size_t images = 0;
  for (size_t at = 0; (at = html.find("src=\"data:image/png;base64,", at)) != std::string::npos;
       ++at)
    ++images;
  EXPECT_EQ(images, 9u);
  EXPECT_EQ(html.find("src=\"http"), std::string::npos);
  EXPECT_EQ(html.find("href="), std::string::npos);

  Image wrong(2, 2);
  r.entries[0].image = &wrong;
  EXPECT_THROW(report_html(r), Error);
}
