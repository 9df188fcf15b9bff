#include "rll/eval/raster.h"

#include <librsvg/rsvg.h>
#include <pango/pangocairo.h>

#include <cmath>
#include <cstring>
#include <vector>

#include "rll/core/error.h"
#include "rll/core/encode.h"

namespace rll {

bool figures_built() {
  return true;
}

namespace {

// The family pango asks fontconfig for; fontconfig substitutes per glyph where it lacks one.
constexpr const char* kPangoFamily = "DejaVu Sans";

// Grey anti-aliasing without hinting: the same glyph widths at every size and on every surface,
// so that what text_width measures is what Canvas::text and librsvg draw.
void set_font_options(cairo_t* cr) {
  cairo_font_options_t* o = cairo_font_options_create();
  cairo_font_options_set_antialias(o, CAIRO_ANTIALIAS_GRAY);
  cairo_font_options_set_hint_style(o, CAIRO_HINT_STYLE_NONE);
  cairo_font_options_set_hint_metrics(o, CAIRO_HINT_METRICS_OFF);
  cairo_set_font_options(cr, o);
  cairo_font_options_destroy(o);
}

// A layout of `text` for cr; width > 0 wraps it there (words, then characters).
PangoLayout* make_layout(cairo_t* cr, const std::string& text, double font_px, bool bold,
                         double width) {
  PangoLayout* layout = pango_cairo_create_layout(cr);
  PangoFontDescription* font = pango_font_description_new();
  pango_font_description_set_family(font, kPangoFamily);
  pango_font_description_set_absolute_size(font, font_px * PANGO_SCALE);
  pango_font_description_set_weight(font, bold ? PANGO_WEIGHT_BOLD : PANGO_WEIGHT_NORMAL);
  pango_layout_set_font_description(layout, font);
  pango_font_description_free(font);
  if (width > 0) {
    pango_layout_set_width(layout, int(std::floor(width * PANGO_SCALE)));
    pango_layout_set_wrap(layout, PANGO_WRAP_WORD_CHAR);
    // A word cut at a line's end gets no hyphen: "1.786e+00" must not read "1.786e-" "+00".
    PangoAttrList* attrs = pango_attr_list_new();
    pango_attr_list_insert(attrs, pango_attr_insert_hyphens_new(FALSE));
    pango_layout_set_attributes(layout, attrs);
    pango_attr_list_unref(attrs);
  }
  pango_layout_set_text(layout, text.data(), int(text.size()));
  return layout;
}

// A context on a 1x1 surface, for measuring.
struct Measure {
  cairo_surface_t* surface = cairo_image_surface_create(CAIRO_FORMAT_RGB24, 1, 1);
  cairo_t* cr = cairo_create(surface);
  Measure() { set_font_options(cr); }
  ~Measure() {
    cairo_destroy(cr);
    cairo_surface_destroy(surface);
  }
};

PangoRectangle logical_extents(const std::string& text, double font_px, bool bold, double width) {
  Measure m;
  PangoLayout* layout = make_layout(m.cr, text, font_px, bold, width);
  PangoRectangle ink, logical;
  pango_layout_get_extents(layout, &ink, &logical);
  g_object_unref(layout);
  return logical;
}

// The RGB bytes of an RGB24 surface.
std::string surface_png(cairo_surface_t* s) {
  cairo_surface_flush(s);
  const int w = cairo_image_surface_get_width(s), h = cairo_image_surface_get_height(s);
  const int stride = cairo_image_surface_get_stride(s);
  const unsigned char* data = cairo_image_surface_get_data(s);
  std::vector<uint8_t> rgb(size_t(w) * h * 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      uint32_t p;
      std::memcpy(&p, data + size_t(y) * stride + 4 * size_t(x), 4);
      uint8_t* o = &rgb[(size_t(y) * w + x) * 3];
      o[0] = uint8_t(p >> 16);
      o[1] = uint8_t(p >> 8);
      o[2] = uint8_t(p);
    }
  return png_bytes(rgb, w, h, 3);
}

}  // namespace

double text_width(const std::string& text, double font_px, bool bold) {
  return double(logical_extents(text, font_px, bold, 0).width) / PANGO_SCALE;
}

double wrapped_text_height(const std::string& text, double width, double font_px, bool bold) {
  return double(logical_extents(text, font_px, bold, width).height) / PANGO_SCALE;
}

std::string svg_to_png(const std::string& svg) {
  GError* error = nullptr;
  RsvgHandle* handle = rsvg_handle_new_from_data(reinterpret_cast<const guint8*>(svg.data()),
                                                 gsize(svg.size()), &error);
  if (!handle) {
    const std::string why = error ? error->message : "unknown error";
    if (error) g_error_free(error);
    fail("cannot read an SVG figure: {}", why);
  }
  gdouble w = 0, h = 0;
  if (!rsvg_handle_get_intrinsic_size_in_pixels(handle, &w, &h) || !(w >= 1) || !(h >= 1) ||
      w > 16384 || h > 16384) {
    g_object_unref(handle);
    fail("an SVG figure has no size in pixels (or one over 16384)");
  }
  cairo_surface_t* surface =
      cairo_image_surface_create(CAIRO_FORMAT_RGB24, int(std::ceil(w)), int(std::ceil(h)));
  cairo_t* cr = cairo_create(surface);
  set_font_options(cr);
  cairo_set_source_rgb(cr, 1, 1, 1);
  cairo_paint(cr);
  const RsvgRectangle viewport{0, 0, w, h};
  const bool ok = rsvg_handle_render_document(handle, cr, &viewport, &error);
  cairo_destroy(cr);
  g_object_unref(handle);
  std::string png;
  if (ok) png = surface_png(surface);
  cairo_surface_destroy(surface);
  if (!ok) {
    const std::string why = error ? error->message : "unknown error";
    if (error) g_error_free(error);
    fail("cannot draw an SVG figure: {}", why);
  }
  return png;
}

struct Canvas::Cairo {
  cairo_surface_t* surface = nullptr;
  cairo_t* cr = nullptr;
};

Canvas::Canvas(int width, int height) : m_w(width), m_h(height), m_c(new Cairo) {
  if (width < 1 || height < 1 || width > 65536 || height > 65536)
    fail("a picture of {}x{} pixels cannot be drawn", width, height);
  m_c->surface = cairo_image_surface_create(CAIRO_FORMAT_RGB24, width, height);
  if (cairo_surface_status(m_c->surface) != CAIRO_STATUS_SUCCESS) {
    cairo_surface_destroy(m_c->surface);
    fail("cannot make a picture of {}x{} pixels", width, height);
  }
  m_c->cr = cairo_create(m_c->surface);
  set_font_options(m_c->cr);
  cairo_set_source_rgb(m_c->cr, 1, 1, 1);
  cairo_paint(m_c->cr);
  cairo_surface_flush(m_c->surface);
}

Canvas::~Canvas() {
  cairo_destroy(m_c->cr);
  cairo_surface_destroy(m_c->surface);
}

void Canvas::set_pixel(int x, int y, uint8_t r, uint8_t g, uint8_t b) {
  if (x < 0 || y < 0 || x >= m_w || y >= m_h) return;
  unsigned char* data = cairo_image_surface_get_data(m_c->surface);
  const uint32_t p = uint32_t(r) << 16 | uint32_t(g) << 8 | b;
  std::memcpy(data + size_t(y) * cairo_image_surface_get_stride(m_c->surface) + 4 * size_t(x), &p,
              4);
}

double Canvas::text(double x, double y, double width, const std::string& text, double font_px,
                    bool bold, uint32_t colour) {
  cairo_t* cr = m_c->cr;
  cairo_surface_mark_dirty(m_c->surface);  // set_pixel wrote behind cairo's back
  PangoLayout* layout = make_layout(cr, text, font_px, bold, width);
  PangoRectangle ink, logical;
  pango_layout_get_extents(layout, &ink, &logical);
  const double height = double(logical.height) / PANGO_SCALE;
  cairo_save(cr);
  cairo_rectangle(cr, x, y, width, height);
  cairo_clip(cr);
  cairo_set_source_rgb(cr, ((colour >> 16) & 255) / 255.0, ((colour >> 8) & 255) / 255.0,
                       (colour & 255) / 255.0);
  cairo_move_to(cr, x, y);
  pango_cairo_show_layout(cr, layout);
  cairo_restore(cr);
  g_object_unref(layout);
  cairo_surface_flush(m_c->surface);
  return height;
}

std::string Canvas::png() const {
  return surface_png(m_c->surface);
}

}  // namespace rll
