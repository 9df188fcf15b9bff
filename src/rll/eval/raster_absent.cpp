// eval/raster.h where rll was built without librsvg and pango (cmake -DRLL_FIGURES=OFF): text is
// measured by an estimate of DejaVu Sans's widths, so that the report's SVG (drawn by the browser)
// still lays out, and the PNG figures are refused with the reason.
#include <cmath>

#include "rll/core/error.h"
#include "rll/eval/raster.h"

namespace rll {

namespace {

[[noreturn]] void no_figures() {
  fail(
      "this rll was built without librsvg and pango (cmake -DRLL_FIGURES=OFF), so it draws no PNG "
      "figures: install librsvg2-dev and libpango1.0-dev and re-run cmake with -DRLL_FIGURES=ON");
}

// DejaVu Sans's mean advance is about 0.6 em (0.66 em bold); counting UTF-8 lead bytes counts
// characters.
double estimated_width(const std::string& text, double font_px, bool bold) {
  size_t chars = 0;
  for (unsigned char c : text) chars += (c & 0xc0) != 0x80;
  return double(chars) * font_px * (bold ? 0.66 : 0.6);
}

}  // namespace

bool figures_built() {
  return false;
}

double text_width(const std::string& text, double font_px, bool bold) {
  return estimated_width(text, font_px, bold);
}

double wrapped_text_height(const std::string& text, double width, double font_px, bool bold) {
  const double line = 1.17 * font_px;
  if (width <= 0) return line;
  return line * std::max(1.0, std::ceil(estimated_width(text, font_px, bold) / width));
}

std::string svg_to_png(const std::string&) {
  no_figures();
}

struct Canvas::Cairo {};

Canvas::Canvas(int width, int height) : m_w(width), m_h(height) {
  no_figures();
}
Canvas::~Canvas() = default;
void Canvas::set_pixel(int, int, uint8_t, uint8_t, uint8_t) {
  no_figures();
}
double Canvas::text(double, double, double, const std::string&, double, bool, uint32_t) {
  no_figures();
}
std::string Canvas::png() const {
  no_figures();
}

}  // namespace rll
