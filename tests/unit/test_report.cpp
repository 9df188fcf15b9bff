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

TEST(ReportHtml, CellChartDataIsEmbeddedForItsSampler) {
  Fixture f;
  CellChart c;
  c.sampler = "oracle";
  c.stride = 2;
  c.columns = 2;
  c.rows = 2;
  c.probe_cell = {0, -1, 0, -1};
  CellChartCell cell;
  cell.cell = 7;
  cell.level = -3;
  cell.has_cut = true;
  cell.begin = {0, 2};
  cell.end = {2, 3};
  cell.learnt = {0.25f, 0.75f};
  cell.tree = {0.5f, 0.123456f};
  c.cells = {cell};
  f.r.cell_charts = {c};
  const std::string html = report_html(f.r);
  EXPECT_NE(html.find("<div id=\"cell-chart\""), std::string::npos);
  EXPECT_EQ(count(html, "class=\"cell-data\""), 1u);
  EXPECT_NE(html.find("\"entry\":1"), std::string::npos);  // oracle is the second entry
  EXPECT_NE(html.find("\"learnt\":[0.25,0.75]"), std::string::npos);
  EXPECT_NE(html.find("\"tree\":[0.5,0.1235]"), std::string::npos);  // 4 significant digits
  EXPECT_NE(html.find("\"probes\":[0,-1,0,-1]"), std::string::npos);
  EXPECT_EQ(html.find("\"oracle\":["), std::string::npos);

  // Past 24 clusters, the others are summed in one row: 30 clusters of 1/30 each.
  CellChartCell many;
  for (uint32_t k = 0; k < 30; ++k) {
    many.begin.push_back(k);
    many.end.push_back(k + 1);
    many.learnt.push_back(k == 29 ? 0.5f : 0.5f / 29);
    many.tree.push_back(1.0f / 30);
  }
  f.r.cell_charts[0].cells = {many};
  f.r.cell_charts[0].probe_cell = {0, 0, 0, 0};
  const std::string summed = report_html(f.r);
  EXPECT_NE(summed.find("\"rest\":{\"count\":6,\"learnt\":0.1034,\"tree\":0.2}"),
            std::string::npos)
      << summed.substr(summed.find("cell-data"), 600);
  EXPECT_NE(summed.find("\"b\":[0,1,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16,17,18,19,20,21,22,29]"),
            std::string::npos);  // the largest, 29, and the first 23 of the equal others

  // A name cannot end the data's script element; a chart of no entry is left out.
  f.r.entries[1].name = c.sampler = "a</script>b";
  f.r.cell_charts = {c};
  const std::string escaped = report_html(f.r);
  EXPECT_NE(escaped.find("a<\\/script>b"), std::string::npos);
  EXPECT_EQ(escaped.find("\"a</script>b"), std::string::npos);
  f.r.cell_charts[0].sampler = "rll";
  EXPECT_EQ(report_html(f.r).find("id=\"cell-chart\""), std::string::npos);
}
