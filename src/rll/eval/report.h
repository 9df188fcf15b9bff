// The HTML report of a comparison: one self-contained file (images embedded as data URIs, inline
// CSS, JS and SVG) with the images side by side under an exposure slider, synchronized zoom and
// pan, a flip of any view with the reference, false-colour relative-error maps, the table, the
// samplers' parameters and setup times, the convergence plot (inline SVG, its points naming their
// values on hover), the per-pixel diagnostics when compare measured them (`--aov`: the cell id in
// false colour, the probability of the light chosen, the cell's entropy, the visible-sample ratio,
// the rewards; each a view like the error maps, flippable with the reference) and, for a learning
// sampler, the cell chart: clicking a pixel of its image (or its map or diagnostics) shows the
// learnt probabilities of the clusters of the cell there beside the light tree's and the oracle's.
//
// Exposure: each image is embedded losslessly as RGBE (Ward's shared-exponent format) split into
// two PNGs, one RGB with the mantissas and one grey with the exponents, which the page decodes
// into floats once and tone-maps again whenever the slider moves. That keeps highlights beyond
// the initial exposure recoverable at 4 bytes a pixel. (One RGBA PNG would not do: canvases
// premultiply alpha, which destroys the mantissas.)
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "rll/core/image.h"
#include "rll/eval/cell_chart.h"

namespace rll {

struct ReportEntry {
  std::string name;     // sampler name
  std::string caption;  // e.g. "relMSE 1.2e-02, 64 spp, 1.0 s"
  uint32_t colour = 0;  // 0xRRGGBB, as in the plot
  const Image* image = nullptr;
  const std::vector<float>* error = nullptr;  // relative_error_map of the image, or null
  std::string repeat_label;  // which repeat the image is, e.g. "repeat 1 of 3, seed 1"; or empty
  // The image's diagnostics (resolve_aovs in render/aov.h: channel "aov.<name>", one value a
  // pixel), or null.
  const std::vector<std::pair<std::string, std::vector<float>>>* aovs = nullptr;
};

// One sampler's setup, for the report's samplers section.
struct ReportSampler {
  std::string name;
  // Its parameters as text shown preformatted: pretty JSON, or one "key = value" a line.
  std::string params;
  double setup_seconds = -1;   // median precomputation (building trees, caches); < 0: unknown
  double render_seconds = -1;  // median render time, to set the setup against; < 0: unknown
};

struct Report {
  std::string title;
  std::vector<std::pair<std::string, std::string>> facts;  // label, value: scene, budget...
  std::vector<std::string> warnings;
  const Image* reference = nullptr;
  std::string reference_caption;
  std::vector<ReportEntry> entries;
  std::vector<std::vector<std::string>> table;  // header row first; one row per entry, in order
  std::vector<ReportSampler> samplers;          // matched to entries by name for the colour
  std::string plot_svg;                         // an <svg> element, or empty
  std::string frame_plot_svg;          // error against frame (compare --every-frame), or empty
  std::vector<CellChart> cell_charts;  // matched to entries by sampler name
  float exposure = 0;                  // initial exposure, stops
};

// The report as one HTML document. Throws rll::Error if an image's size differs from the
// reference's.
std::string report_html(const Report& report);

// RGBE encoding of an image: mantissas (RGB, 3 bytes a pixel) and exponents (1 byte a pixel,
// 0 for black); a channel decodes as (m + 0.5) * 2^(e - 136). Negative and non-finite values
// encode as 0.
void encode_rgbe(const Image& image, std::vector<uint8_t>& mantissas,
                 std::vector<uint8_t>& exponents);

}  // namespace rll
