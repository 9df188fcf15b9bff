// Pictures with text, drawn by Debian's libraries: SVG rasterized by librsvg, text laid out and
// drawn by pango on cairo, in DejaVu Sans (fonts-dejavu-core) with fontconfig's fallback for any
// glyph it lacks. The only file that includes them.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

namespace rll {

// The font family of every figure, as CSS and SVG name it (the browser falls back to its own
// sans-serif where DejaVu Sans is missing).
inline constexpr const char* kFigureFontFamily = "DejaVu Sans, Verdana, sans-serif";

// False where rll was built without librsvg and pango (cmake -DRLL_FIGURES=OFF, the GPU machine,
// which reaches no package registry): text is then measured by an estimate, and svg_to_png and
// Canvas throw rll::Error saying why.
bool figures_built();

// Width in pixels of one line of text in the figure font at `font_px` pixels.
double text_width(const std::string& text, double font_px, bool bold = false);

// Height in pixels of `text` word-wrapped (and cut inside words longer than a line) to `width`
// pixels, in the figure font at `font_px` pixels.
double wrapped_text_height(const std::string& text, double width, double font_px, bool bold);

// An SVG document rasterized at the size its width and height attributes give (in pixels), on
// white; the contents of a PNG file. Throws rll::Error where librsvg cannot read it.
std::string svg_to_png(const std::string& svg);

// A white RGB picture to set pixels and draw text on; encoded as PNG at the end.
class Canvas {
 public:
  Canvas(int width, int height);
  ~Canvas();
  Canvas(const Canvas&) = delete;
  Canvas& operator=(const Canvas&) = delete;
  int width() const { return m_w; }
  int height() const { return m_h; }
  void set_pixel(int x, int y, uint8_t r, uint8_t g, uint8_t b);
  // Draws `text` word-wrapped to [x, x + width) with its top at y, clipped to that column;
  // returns the height it took (wrapped_text_height).
  double text(double x, double y, double width, const std::string& text, double font_px, bool bold,
              uint32_t colour);
  std::string png() const;

 private:
  struct Cairo;
  int m_w, m_h;
  std::unique_ptr<Cairo> m_c;
};

}  // namespace rll
