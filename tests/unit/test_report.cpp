// The report's markup for what a reader must find: which repeat each image shows, the samplers'
// parameters and setup times, a flip control per view, and the colour scale's end labels.
#include <gtest/gtest.h>

#include "rll/core/image.h"
#include "rll/eval/report.h"

using namespace rll;

namespace {

size_t count(const std::string& text, const std::string& part) {
  size_t n = 0;
  for (size_t at = 0; (at = text.find(part, at)) != std::string::npos; ++at) ++n;
  return n;
}

struct Fixture {
  Image ref{4, 3, Rgb(0.5f)}, a{4, 3, Rgb(0.4f)}, b{4, 3, Rgb(0.6f)};
  std::vector<float> ea = std::vector<float>(12, 0.01f), eb = std::vector<float>(12, 0.02f);
  Report r;
  Fixture() {
    r.title = "compare";
    r.reference = &ref;
    r.entries = {{"power", "relMSE 1", 0x1f77b4, &a, &ea, "repeat 2 of 3, seed 2"},
                 {"oracle", "relMSE 2", 0xd62728, &b, &eb, ""}};
    r.table = {{"sampler", "relMSE"}, {"power", "1"}, {"oracle", "2"}};
  }
};

}  // namespace

TEST(ReportHtml, ImagesAndMapsSayWhichRepeatTheyShow) {
  Fixture f;
  const std::string html = report_html(f.r);
  // Under the image and under its error map.
  EXPECT_EQ(count(html, "<span class=\"repeat\">(repeat 2 of 3, seed 2)</span>"), 2u);
  EXPECT_EQ(count(html, "<span class=\"repeat\">"), 2u);  // none for an empty label
}

TEST(ReportHtml, EveryViewButTheReferenceHasAFlipButton) {
  Fixture f;
  const std::string html = report_html(f.r);
  EXPECT_EQ(count(html, "<canvas class=\"view\""), 5u);  // reference, 2 images, 2 maps
  EXPECT_EQ(count(html, "<button class=\"flip\""), 4u);
  EXPECT_NE(html.find("id=\"flip-all\""), std::string::npos);
}

TEST(ReportHtml, ColourScaleLabelsItsEnds) {
  Fixture f;
  const std::string html = report_html(f.r);
  // Four decades up to the 99th percentile of the maps, 0.02.
  EXPECT_NE(html.find("<span id=\"scale-min\">2e-6</span>"), std::string::npos);
  EXPECT_NE(html.find("<span id=\"scale-max\">0.02</span>"), std::string::npos);
}

TEST(ReportHtml, SamplersSectionHasParametersAndSetupTime) {
  Fixture f;
  f.r.samplers = {{"power", "", -1, -1}, {"oracle", "{\n  \"cells\": <64>\n}", 41.6, 0.04}};
  const std::string html = report_html(f.r);
  ASSERT_NE(html.find("<table id=\"samplers\""), std::string::npos);
  EXPECT_NE(html.find("<pre>{\n  &quot;cells&quot;: &lt;64&gt;\n}</pre>"), std::string::npos);
  // A setup 1040 times the render is called out.
  EXPECT_NE(html.find("<span class=\"costly\">41.6 s</span>"), std::string::npos);
  EXPECT_NE(html.find("1040x the render time"), std::string::npos);
  EXPECT_NE(html.find("<pre>(none)</pre>"), std::string::npos);
  EXPECT_NE(html.find("<span class=\"swatch\" style=\"background:#d62728\"></span>oracle</td>"),
            std::string::npos);
  // No section without samplers.
  f.r.samplers.clear();
  EXPECT_EQ(report_html(f.r).find("id=\"samplers\""), std::string::npos);
}

TEST(ReportHtml, WideTablesScrollInsideTheirBox) {
  Fixture f;
  const std::string html = report_html(f.r);
  EXPECT_NE(html.find("<div class=\"table-wrap\">\n<table id=\"summary\">"), std::string::npos);
}
