#include "rll/eval/report.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "rll/core/error.h"
#include "rll/eval/encode.h"
#include "rll/eval/metrics.h"
#include "rll/eval/plot.h"

namespace rll {

namespace {

std::string png_uri(const std::string& png) {
  return "data:image/png;base64," + base64(png);
}

// Two hidden <img> holding one HDR image as RGBE; the script finds them by data-hdr.
std::string hdr_images(const std::string& id, const Image& image) {
  std::vector<uint8_t> m, e;
  encode_rgbe(image, m, e);
  return fmt::format(
      "<img alt=\"\" data-hdr=\"{0}\" data-part=\"m\" src=\"{1}\">\n<img alt=\"\" data-hdr=\"{0}\" "
      "data-part=\"e\" src=\"{2}\">\n",
      id, png_uri(png_bytes(m, image.width(), image.height(), 3)),
      png_uri(png_bytes(e, image.width(), image.height(), 1)));
}

// The colour range of the error maps: up to the largest 99th percentile of the maps, over four
// decades, so that all maps share one scale.
std::pair<float, float> error_range(const Report& r) {
  double hi = 0;
  for (const auto& e : r.entries)
    if (e.error) hi = std::max(hi, quantile(*e.error, 0.99));
  if (!(hi > 0)) hi = 1;
  return {float(hi * 1e-4), float(hi)};
}

std::string colour_bar(float lo, float hi) {
  const int n = 256;
  std::vector<uint8_t> px(size_t(n) * 3);
  for (int i = 0; i < n; ++i) {
    const Rgb8 c = colour_scale(float(i) / (n - 1));
    px[3 * i] = c.r;
    px[3 * i + 1] = c.g;
    px[3 * i + 2] = c.b;
  }
  return fmt::format(
      "<div class=\"bar\"><span>{:.2g}</span><img alt=\"colour scale\" "
      "src=\"{}\"><span>{:.2g}</span></div>",
      lo, png_uri(png_bytes(px, n, 1, 3)), hi);
}

// Zoom/pan state shared by every view, the exposure slider and the RGBE decoder.
constexpr const char* kScript = R"JS(
(function () {
  'use strict';
  var root = document.getElementById('report');
  var W = Number(root.dataset.width), H = Number(root.dataset.height);
  var view = { zoom: 1, cx: W / 2, cy: H / 2 };
  var hdr = {};      // id -> Float32Array of linear RGB
  var sources = {};  // id -> canvas (tone-mapped image or error map) drawn by the views
  var canvases = Array.prototype.slice.call(document.querySelectorAll('canvas.view'));
  var exposure = document.getElementById('exposure');
  var exposureValue = document.getElementById('exposure-value');
  var zoomValue = document.getElementById('zoom-value');

  function loaded(img) {
    if (img.complete && img.naturalWidth > 0) return Promise.resolve(img);
    return new Promise(function (resolve, reject) {
      img.addEventListener('load', function () { resolve(img); });
      img.addEventListener('error', function () { reject(new Error('cannot decode an embedded image')); });
    });
  }
  function pixels(img) {
    var c = document.createElement('canvas');
    c.width = W; c.height = H;
    var g = c.getContext('2d', { willReadFrequently: true });
    g.drawImage(img, 0, 0);
    return g.getImageData(0, 0, W, H).data;
  }
  function decode(m, e) {
    var out = new Float32Array(W * H * 3);
    for (var i = 0; i < W * H; ++i) {
      var x = e[4 * i];
      if (x === 0) continue;
      var f = Math.pow(2, x - 136);
      out[3 * i] = (m[4 * i] + 0.5) * f;
      out[3 * i + 1] = (m[4 * i + 1] + 0.5) * f;
      out[3 * i + 2] = (m[4 * i + 2] + 0.5) * f;
    }
    return out;
  }
  function srgb8(v) {
    if (!(v > 0)) return 0;
    if (v >= 1) return 255;
    var s = v <= 0.0031308 ? 12.92 * v : 1.055 * Math.pow(v, 1 / 2.4) - 0.055;
    return Math.round(s * 255);
  }
  function canvasFor(id) {
    if (!sources[id]) {
      var c = document.createElement('canvas');
      c.width = W; c.height = H;
      sources[id] = c;
    }
    return sources[id];
  }
  function tonemap() {
    var scale = Math.pow(2, Number(exposure.value));
    exposureValue.textContent = (exposure.value > 0 ? '+' : '') + Number(exposure.value).toFixed(2) + ' stops';
    Object.keys(hdr).forEach(function (id) {
      var g = canvasFor(id).getContext('2d');
      var out = g.createImageData(W, H), d = out.data, v = hdr[id];
      for (var i = 0; i < W * H; ++i) {
        d[4 * i] = srgb8(v[3 * i] * scale);
        d[4 * i + 1] = srgb8(v[3 * i + 1] * scale);
        d[4 * i + 2] = srgb8(v[3 * i + 2] * scale);
        d[4 * i + 3] = 255;
      }
      g.putImageData(out, 0, 0);
    });
    draw();
  }
  function clampView() {
    view.zoom = Math.min(64, Math.max(1, view.zoom));
    var hw = W / (2 * view.zoom), hh = H / (2 * view.zoom);
    view.cx = Math.min(W - hw, Math.max(hw, view.cx));
    view.cy = Math.min(H - hh, Math.max(hh, view.cy));
  }
  function draw() {
    clampView();
    zoomValue.textContent = view.zoom.toFixed(view.zoom < 10 ? 2 : 1) + 'x';
    canvases.forEach(function (c) {
      var src = sources[c.dataset.source];
      var g = c.getContext('2d');
      g.setTransform(1, 0, 0, 1, 0, 0);
      g.fillStyle = '#000';
      g.fillRect(0, 0, W, H);
      if (!src) return;
      g.imageSmoothingEnabled = false;
      g.setTransform(view.zoom, 0, 0, view.zoom, W / 2 - view.zoom * view.cx, H / 2 - view.zoom * view.cy);
      g.drawImage(src, 0, 0);
    });
  }
  // Image coordinates of a mouse event over a canvas.
  function imagePoint(c, ev) {
    var r = c.getBoundingClientRect();
    var px = (ev.clientX - r.left) / r.width * W, py = (ev.clientY - r.top) / r.height * H;
    return { px: px, py: py, x: view.cx + (px - W / 2) / view.zoom, y: view.cy + (py - H / 2) / view.zoom };
  }
  canvases.forEach(function (c) {
    c.addEventListener('wheel', function (ev) {
      ev.preventDefault();
      var p = imagePoint(c, ev);
      view.zoom *= ev.deltaY < 0 ? 1.25 : 0.8;
      clampView();
      view.cx = p.x - (p.px - W / 2) / view.zoom;  // keep the point under the mouse in place
      view.cy = p.y - (p.py - H / 2) / view.zoom;
      draw();
    }, { passive: false });
    var drag = null;
    c.addEventListener('pointerdown', function (ev) {
      drag = { x: ev.clientX, y: ev.clientY, cx: view.cx, cy: view.cy };
      c.setPointerCapture(ev.pointerId);
    });
    c.addEventListener('pointermove', function (ev) {
      if (!drag) return;
      var r = c.getBoundingClientRect();
      view.cx = drag.cx - (ev.clientX - drag.x) / r.width * W / view.zoom;
      view.cy = drag.cy - (ev.clientY - drag.y) / r.height * H / view.zoom;
      draw();
    });
    c.addEventListener('pointerup', function () { drag = null; });
    c.addEventListener('dblclick', function () { view = { zoom: 1, cx: W / 2, cy: H / 2 }; draw(); });
  });
  document.getElementById('reset-view').addEventListener('click', function () {
    view = { zoom: 1, cx: W / 2, cy: H / 2 };
    draw();
  });
  exposure.addEventListener('input', tonemap);

  var parts = {};
  Array.prototype.forEach.call(document.querySelectorAll('img[data-hdr]'), function (img) {
    (parts[img.dataset.hdr] = parts[img.dataset.hdr] || {})[img.dataset.part] = img;
  });
  var jobs = Object.keys(parts).map(function (id) {
    return Promise.all([loaded(parts[id].m), loaded(parts[id].e)]).then(function (imgs) {
      hdr[id] = decode(pixels(imgs[0]), pixels(imgs[1]));
    });
  });
  Array.prototype.forEach.call(document.querySelectorAll('img[data-map]'), function (img) {
    jobs.push(loaded(img).then(function () {
      canvasFor(img.dataset.map).getContext('2d').drawImage(img, 0, 0);
    }));
  });
  Promise.all(jobs).then(function () {
    tonemap();
    root.dataset.ready = '1';
  }).catch(function (err) {
    document.getElementById('status').textContent = 'The images could not be shown: ' + err.message;
    throw err;
  });
})();
)JS";

constexpr const char* kStyle = R"CSS(
body { font-family: system-ui, sans-serif; margin: 1.5em; color: #222; background: #fafafa; }
h1 { font-size: 1.4em; } h2 { font-size: 1.15em; margin-top: 1.6em; }
dl.facts { display: grid; grid-template-columns: max-content auto; gap: 0.2em 1em; }
dl.facts dt { font-weight: 600; } dl.facts dd { margin: 0; }
.warning { color: #a33; }
table { border-collapse: collapse; font-variant-numeric: tabular-nums; }
th, td { padding: 0.3em 0.8em; border-bottom: 1px solid #ddd; text-align: right; }
th:first-child, td:first-child { text-align: left; }
.swatch { display: inline-block; width: 0.8em; height: 0.8em; margin-right: 0.4em; border-radius: 2px; }
.controls { display: flex; gap: 1.5em; align-items: center; flex-wrap: wrap; margin: 1em 0; }
.grid { display: flex; flex-wrap: wrap; gap: 12px; }
figure { margin: 0; }
figcaption { font-size: 0.85em; margin-top: 0.3em; }
canvas.view { display: block; image-rendering: pixelated; cursor: grab; background: #000; touch-action: none; }
.bar { display: flex; align-items: center; gap: 0.5em; font-size: 0.85em; margin-top: 0.6em; }
.bar img { width: 256px; height: 14px; image-rendering: pixelated; }
.hidden { display: none; }
)CSS";

}  // namespace

void encode_rgbe(const Image& image, std::vector<uint8_t>& mantissas,
                 std::vector<uint8_t>& exponents) {
  mantissas.assign(image.pixel_count() * 3, 0);
  exponents.assign(image.pixel_count(), 0);
  for (size_t i = 0; i < image.pixel_count(); ++i) {
    float c[3];
    for (int k = 0; k < 3; ++k) {
      const float v = image[i][k];
      c[k] = v > 0 && std::isfinite(v) ? v : 0.0f;
    }
    const float v = std::max({c[0], c[1], c[2]});
    int e = 0;
    const float m = std::frexp(v, &e);  // v = m 2^e, m in [0.5, 1)
    if (v < 1e-32f || e < -127) continue;
    if (e > 127) {  // beyond the format: the largest value it holds
      for (int k = 0; k < 3; ++k) mantissas[3 * i + k] = c[k] > 0 ? 255 : 0;
      exponents[i] = 255;
      continue;
    }
    const float scale = m * 256.0f / v;
    for (int k = 0; k < 3; ++k) mantissas[3 * i + k] = uint8_t(std::min(255.0f, c[k] * scale));
    exponents[i] = uint8_t(e + 128);
  }
}

std::string report_html(const Report& r) {
  if (!r.reference) fail("a report needs a reference image");
  const int w = r.reference->width(), h = r.reference->height();
  for (const auto& e : r.entries)
    if (!e.image || e.image->width() != w || e.image->height() != h)
      fail("report: the image of '{}' is not {}x{} like the reference", e.name, w, h);
  // Small images are shown enlarged, large ones shrunk to fit three to a row.
  const int display_w = w < 256 ? 256 : std::min(w, 420);
  const int display_h = int(std::lround(double(display_w) * h / w));

  std::string s;
  s += "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n";
  s += "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n";
  s += "<title>" + escape_markup(r.title) + "</title>\n<style>" + kStyle + "</style>\n</head>\n";
  s += fmt::format("<body>\n<div id=\"report\" data-width=\"{}\" data-height=\"{}\">\n", w, h);
  s += "<h1>" + escape_markup(r.title) + "</h1>\n<dl class=\"facts\">\n";
  for (const auto& [k, v] : r.facts)
    s += "<dt>" + escape_markup(k) + "</dt><dd>" + escape_markup(v) + "</dd>\n";
  s += "</dl>\n";
  for (const auto& warning : r.warnings)
    s += "<p class=\"warning\">" + escape_markup(warning) + "</p>\n";

  s += "<h2>Summary</h2>\n<table id=\"summary\">\n";
  for (size_t row = 0; row < r.table.size(); ++row) {
    s += row == 0 ? "<thead><tr>" : (row == 1 ? "<tbody><tr>" : "<tr>");
    for (size_t c = 0; c < r.table[row].size(); ++c) {
      std::string cell = escape_markup(r.table[row][c]);
      if (row > 0 && c == 0 && row - 1 < r.entries.size())
        cell = fmt::format("<span class=\"swatch\" style=\"background:{}\"></span>",
                           css_colour(r.entries[row - 1].colour)) +
               cell;
      s += (row == 0 ? "<th>" : "<td>") + cell + (row == 0 ? "</th>" : "</td>");
    }
    s += row == 0 ? "</tr></thead>\n" : "</tr>\n";
  }
  if (r.table.size() > 1) s += "</tbody>\n";
  s += "</table>\n";

  s += "<h2>Images</h2>\n<div class=\"controls\">\n";
  s += fmt::format(
      "<label>Exposure <input id=\"exposure\" type=\"range\" min=\"-10\" max=\"10\" step=\"0.25\" "
      "value=\"{}\"></label> <span id=\"exposure-value\"></span>\n",
      r.exposure);
  s += "<span>Zoom <span id=\"zoom-value\">1x</span> (wheel to zoom, drag to pan, double-click to "
       "reset)</span>\n";
  s += "<button id=\"reset-view\" type=\"button\">Reset view</button>\n<span "
       "id=\"status\"></span>\n</div>\n";

  auto figure = [&](const std::string& source, const std::string& title,
                    const std::string& caption) {
    return fmt::format(
        "<figure><canvas class=\"view\" data-source=\"{}\" width=\"{}\" height=\"{}\" "
        "style=\"width:{}px;height:{}px\"></canvas><figcaption><b>{}</b> "
        "{}</figcaption></figure>\n",
        source, w, h, display_w, display_h, escape_markup(title), escape_markup(caption));
  };
  std::string data = hdr_images("reference", *r.reference);
  s += "<div class=\"grid\">\n" + figure("reference", "reference", r.reference_caption);
  for (size_t i = 0; i < r.entries.size(); ++i) {
    const std::string id = fmt::format("image-{}", i);
    s += figure(id, r.entries[i].name, r.entries[i].caption);
    data += hdr_images(id, *r.entries[i].image);
  }
  s += "</div>\n";

  // The maps sit under their images; the colour scale takes the reference's place.
  const auto [lo, hi] = error_range(r);
  bool any_error = false;
  std::string maps = fmt::format(
      "<div class=\"grid\">\n<figure style=\"width:{}px\"><p>Per pixel (x - ref)&sup2; / "
      "(ref&sup2; + 0.01), averaged over channels, on a logarithmic colour scale shared by all "
      "maps:</p>{}</figure>\n",
      display_w, colour_bar(lo, hi));
  for (size_t i = 0; i < r.entries.size(); ++i) {
    if (!r.entries[i].error) continue;
    any_error = true;
    const std::string id = fmt::format("error-{}", i);
    maps += figure(id, r.entries[i].name, "");
    data += fmt::format("<img alt=\"\" data-map=\"{}\" src=\"{}\">\n", id,
                        png_uri(png_bytes(false_colour(*r.entries[i].error, lo, hi), w, h, 3)));
  }
  if (any_error) {
    s += "<h2>Relative error</h2>\n" + maps + "</div>\n";
  }

  if (!r.plot_svg.empty())
    s += "<h2>Convergence</h2>\n<div class=\"plot\">" + r.plot_svg + "</div>\n";
  s += "<div class=\"hidden\">\n" + data + "</div>\n</div>\n";
  s += std::string("<script>") + kScript + "</script>\n</body>\n</html>\n";
  return s;
}

}  // namespace rll
