#include "rll/eval/report.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>

#include "rll/core/error.h"
#include "rll/core/encode.h"
#include "rll/eval/metrics.h"
#include "rll/eval/plot.h"
#include "rll/render/aov.h"

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

// A number in few characters: "4.6e-6", "0.046", "12".
std::string short_number(double v) {
  std::string t = fmt::format("{:.2g}", v);
  const size_t e = t.find('e');
  if (e == std::string::npos) return t;
  std::string mantissa = t.substr(0, e), exponent = t.substr(e + 1);
  const bool negative = exponent[0] == '-';
  exponent = exponent.substr(1);
  exponent.erase(0, std::min(exponent.find_first_not_of('0'), exponent.size() - 1));
  return mantissa + "e" + (negative ? "-" : "") + exponent;
}

// "1040", "42", "3.5", "0.12": whole numbers from 10 up, where more digits mislead.
std::string ratio_text(double r) {
  return r >= 10 ? fmt::format("{:.0f}", r) : fmt::format("{:.2g}", r);
}

std::string seconds_text(double s) {
  if (s < 1e-3) return fmt::format("{:.3g} µs", s * 1e6);
  if (s < 1) return fmt::format("{:.3g} ms", s * 1e3);
  return fmt::format("{:.3g} s", s);
}

// The bar spans the figure's width with its end labels under its ends, on one line each: beside
// the bar they would need room the column does not have (they wrapped, or ran into the next map).
// The labels' ids are `id`-min and `id`-max.
std::string colour_bar(float lo, float hi, const std::string& id = "scale",
                       const std::string& note = "log scale") {
  const int n = 256;
  std::vector<uint8_t> px(size_t(n) * 3);
  for (int i = 0; i < n; ++i) {
    const Rgb8 c = colour_scale(float(i) / (n - 1));
    px[3 * i] = c.r;
    px[3 * i + 1] = c.g;
    px[3 * i + 2] = c.b;
  }
  return fmt::format(
      "<div class=\"bar\"><img alt=\"colour scale\" src=\"{0}\"><div class=\"bar-labels\"><span "
      "id=\"{3}-min\">{1}</span><span class=\"bar-note\">{4}</span><span "
      "id=\"{3}-max\">{2}</span></div></div>",
      png_uri(png_bytes(px, n, 1, 3)), short_number(lo), short_number(hi), id, note);
}

// How a diagnostic is coloured: on colour_scale from lo to hi, linearly or logarithmically, one
// scale shared by every sampler's map of it (the cell ids get a colour each instead).
struct AovScale {
  float lo = 0, hi = 1;
  bool log = false;
};

AovScale aov_scale(const Report& r, const std::string& channel) {
  if (channel == "aov.visible") return {0, 1, false};  // a share
  float hi = 0, least = std::numeric_limits<float>::infinity();
  for (const ReportEntry& e : r.entries)
    if (e.aovs)
      for (const auto& [name, values] : *e.aovs)
        if (name == channel)
          for (float v : values)
            if (std::isfinite(v)) {
              hi = std::max(hi, v);
              if (v > 0) least = std::min(least, v);
            }
  if (!(hi > 0)) hi = 1;
  if (channel == "aov.entropy") return {0, hi, false};  // bits, from 0 (one cluster)
  // Probabilities and reward counts span decades: over at most four of them.
  float lo = std::max(least, hi * 1e-4f);
  if (!(lo < hi)) lo = hi * 0.1f;
  return {lo, hi, true};
}

// The grey of a pixel where a diagnostic measured nothing (NaN; no cell).
constexpr Rgb8 kNothingMeasured{64, 64, 64};

std::vector<uint8_t> aov_colours(const std::vector<float>& values, bool cells,
                                 const AovScale& s) {
  std::vector<uint8_t> rgb(3 * values.size());
  const double log_lo = std::log(double(s.lo)), log_hi = std::log(double(s.hi));
  for (size_t i = 0; i < values.size(); ++i) {
    const float v = values[i];
    Rgb8 c = kNothingMeasured;
    if (cells && v >= 0) {
      const Rgb f = cell_colour(v);
      c = {uint8_t(f.x * 255 + 0.5f), uint8_t(f.y * 255 + 0.5f), uint8_t(f.z * 255 + 0.5f)};
    } else if (!cells && std::isfinite(v)) {
      const double t = s.log ? (v > 0 ? (std::log(double(v)) - log_lo) / (log_hi - log_lo) : 0)
                             : (double(v) - s.lo) / (double(s.hi) - s.lo);
      c = colour_scale(float(std::clamp(t, 0.0, 1.0)));
    }
    rgb[3 * i] = c.r;
    rgb[3 * i + 1] = c.g;
    rgb[3 * i + 2] = c.b;
  }
  return rgb;
}

// The clusters a cell's chart shows one by one; the others are summed in one row.
constexpr size_t kChartClusters = 24;

// A probability in few digits, for the chart's data: 4 significant digits.
double rounded(float v) {
  return std::stod(fmt::format("{:.4g}", v));
}

// A cell chart as the page's script reads it, in a JSON script element ("</" escaped so that no
// name can end the element).
std::string cell_chart_data(const CellChart& c, size_t entry, const std::vector<ReportEntry>& all) {
  // The bars in the colours of the samplers they stand for, where those are in the comparison.
  auto colour_of = [&](const std::string& name, uint32_t otherwise) {
    for (const ReportEntry& e : all)
      if (e.name == name) return css_colour(e.colour);
    return css_colour(otherwise);
  };
  const nlohmann::json colours = {{"learnt", css_colour(all[entry].colour)},
                                  {"tree", colour_of("tree", 0x7f7f7f)},
                                  {"oracle", colour_of("oracle", 0x2ca02c)}};
  nlohmann::json cells = nlohmann::json::array();
  for (const CellChartCell& cell : c.cells) {
    // The kChartClusters clusters whose largest probability is largest, in cut order, and the
    // others' sums: what the chart draws, in at most about 1 kB a cell.
    const size_t n = cell.learnt.size();
    auto largest = [&](size_t k) {
      return std::max({cell.learnt[k], cell.tree[k], c.has_oracle ? cell.oracle[k] : 0.0f});
    };
    std::vector<size_t> order(n);
    for (size_t k = 0; k < n; ++k) order[k] = k;
    std::stable_sort(order.begin(), order.end(),
                     [&](size_t a, size_t b) { return largest(a) > largest(b); });
    std::vector<bool> shown(n, false);
    for (size_t i = 0; i < std::min(n, kChartClusters); ++i) shown[order[i]] = true;
    nlohmann::json j = {{"id", cell.cell}, {"level", cell.level}, {"cut", cell.has_cut}};
    nlohmann::json rest = {{"count", 0}, {"learnt", 0.0}, {"tree", 0.0}};
    if (c.has_oracle) rest["oracle"] = 0.0;
    for (const char* key : {"b", "e", "learnt", "tree", "oracle"}) j[key] = nlohmann::json::array();
    for (size_t k = 0; k < n; ++k) {
      if (!shown[k]) {
        rest["count"] = rest["count"].get<int>() + 1;
        rest["learnt"] = rest["learnt"].get<double>() + cell.learnt[k];
        rest["tree"] = rest["tree"].get<double>() + cell.tree[k];
        if (c.has_oracle) rest["oracle"] = rest["oracle"].get<double>() + cell.oracle[k];
        continue;
      }
      j["b"].push_back(cell.begin[k]);
      j["e"].push_back(cell.end[k]);
      j["learnt"].push_back(rounded(cell.learnt[k]));
      j["tree"].push_back(rounded(cell.tree[k]));
      if (c.has_oracle) j["oracle"].push_back(rounded(cell.oracle[k]));
    }
    if (!c.has_oracle) j.erase("oracle");
    if (rest["count"].get<int>() > 0) {
      for (const char* key : {"learnt", "tree", "oracle"})
        if (rest.contains(key)) rest[key] = rounded(float(rest[key].get<double>()));
      j["rest"] = std::move(rest);
    }
    cells.push_back(std::move(j));
  }
  const nlohmann::json d = {{"sampler", c.sampler}, {"entry", entry},
                            {"stride", c.stride},   {"columns", c.columns},
                            {"rows", c.rows},       {"probes", c.probe_cell},
                            {"oracle", c.has_oracle}, {"colours", colours},
                            {"cells", std::move(cells)}};
  std::string text = d.dump();
  for (size_t at = 0; (at = text.find("</", at)) != std::string::npos; at += 3)
    text.replace(at, 2, "<\\/");
  return "<script type=\"application/json\" class=\"cell-data\">" + text + "</script>\n";
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
      var src = sources[c.dataset.flipped === '1' ? 'reference' : c.dataset.source];
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

  // Flip: a view shows the reference in place of its own image, with the same zoom, pan and
  // exposure, so that differences show as the picture changing under the eye.
  var flippable = canvases.filter(function (c) { return c.dataset.source !== 'reference'; });
  var flipAll = document.getElementById('flip-all');
  function setFlipped(c, on) {
    c.dataset.flipped = on ? '1' : '0';
    var fig = c.closest('figure');
    fig.classList.toggle('flipped', on);
    var b = fig.querySelector('button.flip');
    if (b) b.setAttribute('aria-pressed', on ? 'true' : 'false');
  }
  function allFlipped() {
    return flippable.length > 0 && flippable.every(function (c) { return c.dataset.flipped === '1'; });
  }
  function toggleAll() {
    var on = !allFlipped();
    flippable.forEach(function (c) { setFlipped(c, on); });
    flipAll.setAttribute('aria-pressed', on ? 'true' : 'false');
    draw();
  }
  Array.prototype.forEach.call(document.querySelectorAll('button.flip'), function (b) {
    b.addEventListener('click', function () {
      var c = b.closest('figure').querySelector('canvas.view');
      setFlipped(c, c.dataset.flipped !== '1');
      flipAll.setAttribute('aria-pressed', allFlipped() ? 'true' : 'false');
      draw();
    });
  });
  flipAll.addEventListener('click', toggleAll);
  document.addEventListener('keydown', function (ev) {
    if ((ev.key !== 'f' && ev.key !== 'F') || ev.ctrlKey || ev.metaKey || ev.altKey || ev.repeat) return;
    var t = ev.target;
    if (t && (t.tagName === 'TEXTAREA' || (t.tagName === 'INPUT' && t.type !== 'range'))) return;
    ev.preventDefault();
    toggleAll();
  });

  // The cell chart: a click (not the end of a drag) on a learning sampler's image or error map
  // shows, for the cell at that pixel, each cluster's learnt probability beside the light
  // tree's and the oracle's, as bars.
  var charts = {};
  Array.prototype.forEach.call(document.querySelectorAll('script.cell-data'), function (el) {
    var d = JSON.parse(el.textContent);
    charts['image-' + d.entry] = d;
    charts['error-' + d.entry] = d;
    canvases.forEach(function (c) {  // and its diagnostics: aov-<name>-<entry>
      var m = /^aov-[a-z]+-(\d+)$/.exec(c.dataset.source);
      if (m && Number(m[1]) === d.entry) charts[c.dataset.source] = d;
    });
  });
  var chartBox = document.getElementById('cell-chart');
  var SVG = 'http://www.w3.org/2000/svg';
  function svgElement(name, attrs, parent) {
    var e = document.createElementNS(SVG, name);
    Object.keys(attrs).forEach(function (k) { e.setAttribute(k, attrs[k]); });
    if (parent) parent.appendChild(e);
    return e;
  }
  function percent(v) { return (100 * v).toPrecision(3) + '%'; }
  function showCell(d, x, y) {
    var probe = d.probes[Math.floor(y / d.stride) * d.columns + Math.floor(x / d.stride)];
    chartBox.textContent = '';
    chartBox.dataset.pixel = x + ',' + y;
    var head = document.createElement('p');
    chartBox.appendChild(head);
    if (probe === undefined || probe < 0) {
      chartBox.dataset.cell = '';
      head.textContent = d.sampler + ', pixel (' + x + ', ' + y + '): no cell (the camera ray leaves ' +
        'the scene, or meets a surface that takes no light sample, or the table holds no cell there)';
      return;
    }
    var c = d.cells[probe];
    chartBox.dataset.cell = String(c.id);
    var px = Math.min(W - 1, Math.floor(x / d.stride) * d.stride + Math.floor(d.stride / 2));
    var py = Math.min(H - 1, Math.floor(y / d.stride) * d.stride + Math.floor(d.stride / 2));
    head.textContent = d.sampler + ', pixel (' + x + ', ' + y + ')' +
      (px !== x || py !== y ? ', probed at (' + px + ', ' + py + ')' : '') + ': cell ' + c.id + ', level ' + c.level +
      ', ' + (c.learnt.length + (c.rest ? c.rest.count : 0)) + ' clusters' +
      (c.cut ? '' : ' (no cut learnt yet: the cell samples like the light tree)');
    var kinds = [{ key: 'learnt', name: d.sampler + ' (learnt)', colour: d.colours.learnt },
                 { key: 'tree', name: 'light tree (prior)', colour: d.colours.tree }];
    if (d.oracle) kinds.push({ key: 'oracle', name: 'oracle', colour: d.colours.oracle });
    // The clusters by the largest of their probabilities, then the others' sums as one row.
    var order = c.learnt.map(function (v, i) { return i; });
    function largest(i) { return Math.max.apply(null, kinds.map(function (k) { return c[k.key][i]; })); }
    order.sort(function (a, b) { return largest(b) - largest(a) || a - b; });
    var rows = order.map(function (i) {
      return { label: c.e[i] - c.b[i] === 1 ? 'light ' + c.b[i] : 'lights ' + c.b[i] + '\u2013' + (c.e[i] - 1),
               values: kinds.map(function (k) { return c[k.key][i]; }) };
    });
    if (c.rest)
      rows.push({ label: c.rest.count + ' other clusters', values: kinds.map(function (k) { return c.rest[k.key]; }) });
    var most = 0;
    rows.forEach(function (r) { r.values.forEach(function (v) { most = Math.max(most, v); }); });
    var barH = 11, rowH = kinds.length * barH + 7, labelW = 140, barW = 320, top = 30;
    var svg = svgElement('svg', { class: 'cell-bars', width: labelW + barW + 70, height: top + rows.length * rowH + 20,
                                  'font-size': 12 });
    kinds.forEach(function (k, i) {
      svgElement('rect', { x: labelW + i * 130, y: 6, width: 12, height: 12, fill: k.colour }, svg);
      svgElement('text', { x: labelW + i * 130 + 16, y: 16 }, svg).textContent = k.name;
    });
    rows.forEach(function (r, ri) {
      var y = top + ri * rowH;
      svgElement('text', { x: labelW - 6, y: y + kinds.length * barH / 2 + 4, 'text-anchor': 'end' }, svg).textContent = r.label;
      r.values.forEach(function (v, ki) {
        var width = most > 0 ? v / most * barW : 0;
        var bar = svgElement('rect', { class: 'bar', 'data-kind': kinds[ki].key, 'data-row': ri, 'data-value': v,
                                       x: labelW, y: y + ki * barH, width: width, height: barH - 1,
                                       fill: kinds[ki].colour }, svg);
        svgElement('title', {}, bar).textContent = r.label + ', ' + kinds[ki].name + ': ' + percent(v);
        if (ki === 0 || v > 0)
          svgElement('text', { x: labelW + width + 4, y: y + ki * barH + barH - 2, 'font-size': 9, fill: '#555' }, svg)
            .textContent = percent(v);
      });
    });
    var axisY = top + rows.length * rowH;
    svgElement('line', { x1: labelW, y1: top - 2, x2: labelW, y2: axisY, stroke: '#333' }, svg);
    svgElement('text', { x: labelW + barW, y: axisY + 14, 'text-anchor': 'end', fill: '#555' }, svg)
      .textContent = 'bar length: probability, the longest ' + percent(most);
    chartBox.appendChild(svg);
  }
  var pressedAt = null;
  canvases.forEach(function (c) {
    c.addEventListener('pointerdown', function (ev) { pressedAt = { x: ev.clientX, y: ev.clientY }; });
    c.addEventListener('click', function (ev) {
      var d = charts[c.dataset.source];
      if (!d || !chartBox) return;
      if (pressedAt && Math.abs(ev.clientX - pressedAt.x) + Math.abs(ev.clientY - pressedAt.y) > 4) return;
      var p = imagePoint(c, ev), x = Math.floor(p.x), y = Math.floor(p.y);
      if (x < 0 || y < 0 || x >= W || y >= H) return;
      showCell(d, x, y);
    });
  });

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
/* Wide tables scroll inside their box, the header row and the sampler column staying in view. */
.table-wrap { overflow: auto; max-width: 100%; max-height: 80vh; width: fit-content;
  border: 1px solid #ddd; background: #fff; }
table { border-collapse: separate; border-spacing: 0; font-variant-numeric: tabular-nums; }
th, td { padding: 0.3em 0.8em; border-bottom: 1px solid #ddd; text-align: right; }
td { white-space: nowrap; }
th { vertical-align: bottom; background: #f0f0f0; position: sticky; top: 0; z-index: 1; }
th:first-child, td:first-child { text-align: left; position: sticky; left: 0; }
td:first-child { background: #fff; }
th:first-child { z-index: 2; }
table.samplers td { text-align: left; vertical-align: top; white-space: normal; }
table.samplers td.setup { text-align: right; white-space: nowrap; }
table.samplers pre { margin: 0; font-size: 0.85em; white-space: pre-wrap; }
.costly { color: #a33; font-weight: 600; }
.note { color: #666; font-size: 0.85em; }
.swatch { display: inline-block; width: 0.8em; height: 0.8em; margin-right: 0.4em; border-radius: 2px; }
.controls { display: flex; gap: 1.5em; align-items: center; flex-wrap: wrap; margin: 1em 0; }
.grid { display: flex; flex-wrap: wrap; gap: 12px; align-items: flex-start; }
figure { margin: 0; }
figcaption { font-size: 0.85em; margin-top: 0.3em; }
figcaption .repeat { color: #555; }
figcaption button.flip { float: right; font-size: 0.9em; padding: 0 0.4em; }
button[aria-pressed="true"] { background: #ffe2a8; }
.flip-note { display: none; color: #b35c00; font-weight: 600; }
figure.flipped .flip-note { display: inline; }
figure.flipped canvas.view { outline: 3px solid #e69f00; }
canvas.view { display: block; image-rendering: pixelated; cursor: grab; background: #000; touch-action: none; }
.bar { font-size: 0.85em; margin-top: 0.6em; }
.bar img { display: block; width: 100%; height: 14px; image-rendering: pixelated; }
.bar-labels { display: flex; justify-content: space-between; gap: 0.5em; white-space: nowrap; margin-top: 0.2em; }
.bar-note { color: #666; }
.legend p { margin: 0; font-size: 0.9em; }
.hidden { display: none; }
.plot svg { max-width: 100%; height: auto; }
.cell-chart svg { font-family: DejaVu Sans, Verdana, sans-serif; }
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
  auto swatch = [](const ReportEntry& e) {
    return fmt::format("<span class=\"swatch\" style=\"background:{}\"></span>",
                       css_colour(e.colour));
  };
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

  s += "<h2>Summary</h2>\n<div class=\"table-wrap\">\n<table id=\"summary\">\n";
  for (size_t row = 0; row < r.table.size(); ++row) {
    s += row == 0 ? "<thead><tr>" : (row == 1 ? "<tbody><tr>" : "<tr>");
    for (size_t c = 0; c < r.table[row].size(); ++c) {
      std::string cell = escape_markup(r.table[row][c]);
      if (row > 0 && c == 0 && row - 1 < r.entries.size()) cell = swatch(r.entries[row - 1]) + cell;
      s += (row == 0 ? "<th>" : "<td>") + cell + (row == 0 ? "</th>" : "</td>");
    }
    s += row == 0 ? "</tr></thead>\n" : "</tr>\n";
  }
  if (r.table.size() > 1) s += "</tbody>\n";
  s += "</table>\n</div>\n";

  if (!r.samplers.empty()) {
    s += "<h2>Samplers</h2>\n<div class=\"table-wrap\">\n<table id=\"samplers\" "
         "class=\"samplers\">\n<thead><tr><th>sampler</th><th>setup</th><th>parameters</th></tr>"
         "</thead>\n<tbody>\n";
    for (const ReportSampler& rs : r.samplers) {
      std::string name = escape_markup(rs.name);
      for (const auto& e : r.entries)
        if (e.name == rs.name) {
          name = swatch(e) + name;
          break;
        }
      std::string setup = "&ndash;";
      if (rs.setup_seconds >= 0) {
        setup = escape_markup(seconds_text(rs.setup_seconds));
        if (rs.render_seconds > 0) {
          // A setup that costs more than the render it serves changes which sampler is cheaper;
          // it is set in red so that a reader of the table cannot miss it.
          const double ratio = rs.setup_seconds / rs.render_seconds;
          if (ratio >= 1) setup = "<span class=\"costly\">" + setup + "</span>";
          setup += "<br><span class=\"note\">" +
                   escape_markup(ratio >= 0.01 ? ratio_text(ratio) + "x the render time"
                                               : "under 1% of the render time") +
                   "</span>";
        }
      }
      s += "<tr><td>" + name + "</td><td class=\"setup\">" + setup + "</td><td><pre>" +
           escape_markup(rs.params.empty() ? "(none)" : rs.params) + "</pre></td></tr>\n";
    }
    s += "</tbody>\n</table>\n</div>\n";
  }

  s += "<h2>Images</h2>\n<div class=\"controls\">\n";
  s += fmt::format(
      "<label>Exposure <input id=\"exposure\" type=\"range\" min=\"-10\" max=\"10\" step=\"0.25\" "
      "value=\"{}\"></label> <span id=\"exposure-value\"></span>\n",
      r.exposure);
  s += "<span>Zoom <span id=\"zoom-value\">1x</span> (wheel to zoom, drag to pan, double-click to "
       "reset)</span>\n";
  s += "<button id=\"reset-view\" type=\"button\">Reset view</button>\n";
  s += "<button id=\"flip-all\" type=\"button\" aria-pressed=\"false\" title=\"Show the reference "
       "in every view, same zoom and exposure; again to flip back\">Flip all with the reference "
       "(F)</button>\n<span id=\"status\"></span>\n</div>\n";

  // One view: its canvas, and under it the name, which repeat it shows, a button that flips it
  // with the reference (all but the reference's own view) and the caption.
  auto figure = [&](const std::string& source, const std::string& title,
                    const std::string& repeat_label, const std::string& caption) {
    const bool flippable = source != "reference";
    std::string f = fmt::format(
        "<figure style=\"width:{}px\"><canvas class=\"view\" data-source=\"{}\" "
        "data-flipped=\"0\" width=\"{}\" height=\"{}\" style=\"width:{}px;height:{}px\"></canvas>"
        "<figcaption>",
        display_w, source, w, h, display_w, display_h);
    if (flippable)
      f += "<button class=\"flip\" type=\"button\" aria-pressed=\"false\" title=\"Show the "
           "reference here (F flips all)\">&#8644; reference</button>";
    f += "<b>" + escape_markup(title) + "</b>";
    if (!repeat_label.empty())
      f += " <span class=\"repeat\">(" + escape_markup(repeat_label) + ")</span>";
    if (flippable) f += " <span class=\"flip-note\">showing the reference</span>";
    if (!caption.empty()) f += "<br>" + escape_markup(caption);
    return f + "</figcaption></figure>\n";
  };
  std::string data = hdr_images("reference", *r.reference);
  s += "<div class=\"grid\">\n" + figure("reference", "reference", "", r.reference_caption);
  for (size_t i = 0; i < r.entries.size(); ++i) {
    const ReportEntry& e = r.entries[i];
    const std::string id = fmt::format("image-{}", i);
    s += figure(id, e.name, e.repeat_label, e.caption);
    data += hdr_images(id, *e.image);
  }
  s += "</div>\n";

  // The cell chart, under the images it reads its clicks from.
  std::string chart_data;
  std::vector<std::string> charted;
  for (const CellChart& c : r.cell_charts)
    for (size_t i = 0; i < r.entries.size(); ++i)
      if (r.entries[i].name == c.sampler) {
        chart_data += cell_chart_data(c, i, r.entries);
        charted.push_back(c.sampler);
        break;
      }
  if (!charted.empty()) {
    std::string names;
    for (size_t i = 0; i < charted.size(); ++i)
      names += (i == 0 ? "" : i + 1 == charted.size() ? " or " : ", ") + escape_markup(charted[i]);
    s += "<h2>What the cells learnt</h2>\n<p class=\"note\">Click a pixel of the " + names +
         " image (or its error map or diagnostics): the chart shows, for the cell that the pixel's first hit falls "
         "in, the probability of each cluster of the cell's cut as its baked table holds it "
         "(learnt), as the light tree gives it there (the prior: the chance that a descent from "
         "the root reaches the cluster), and as the oracle gives it, when it ran; tree and oracle "
         "at the cell's first probed point.</p>\n";
    for (const CellChart& c : r.cell_charts) {
      std::string line =
          c.stride == 1 ? "every pixel probed" : fmt::format("one pixel in {0}x{0} probed", c.stride);
      line = fmt::format("{}: {}, {} cells", c.sampler, line, c.cells.size());
      if (!c.note.empty()) line += "; " + c.note;
      s += "<p class=\"note\">" + escape_markup(line) + "</p>\n";
    }
    s += "<div id=\"cell-chart\" class=\"cell-chart\"><p>No pixel chosen yet.</p></div>\n" +
         chart_data;
  }

  // The maps sit under their images; the colour scale takes the reference's place.
  const auto [lo, hi] = error_range(r);
  bool any_error = false;
  std::string maps = fmt::format(
      "<div class=\"grid\">\n<figure class=\"legend\" style=\"width:{}px\"><p>Per pixel (x - "
      "ref)&sup2; / (ref&sup2; + 0.01), averaged over channels, on a logarithmic colour scale "
      "shared by all maps:</p>{}</figure>\n",
      display_w, colour_bar(lo, hi));
  for (size_t i = 0; i < r.entries.size(); ++i) {
    const ReportEntry& e = r.entries[i];
    if (!e.error) continue;
    any_error = true;
    const std::string id = fmt::format("error-{}", i);
    maps += figure(id, e.name, e.repeat_label, "");
    data += fmt::format("<img alt=\"\" data-map=\"{}\" src=\"{}\">\n", id,
                        png_uri(png_bytes(false_colour(*e.error, lo, hi), w, h, 3)));
  }
  if (any_error) {
    s += "<h2>Relative error</h2>\n" + maps + "</div>\n";
  }

  // The diagnostics, one row per kind: its legend in the reference's place, then each sampler's
  // map of it, a view like the error maps (zoom, pan, flip with the reference).
  std::string diagnostics;
  for (const AovInfo& a : aov_list()) {
    const std::string channel = std::string("aov.") + a.name;
    std::string row;
    for (size_t i = 0; i < r.entries.size(); ++i) {
      const ReportEntry& e = r.entries[i];
      if (!e.aovs) continue;
      for (const auto& [name, values] : *e.aovs) {
        // A map that measured nothing (a sampler without cells has no cell, entropy or rewards)
        // is left out.
        const bool measured = std::any_of(values.begin(), values.end(), [&](float v) {
          return std::isfinite(v) && (a.kind != Aov::Cell || v >= 0);
        });
        if (name != channel || !measured) continue;
        if (values.size() != size_t(w) * h)
          fail("report: diagnostic {} of {} has {} values for {}x{} pixels", a.name, e.name,
               values.size(), w, h);
        const std::string id = fmt::format("aov-{}-{}", a.name, i);
        row += figure(id, e.name, e.repeat_label, "");
        data += fmt::format("<img alt=\"\" data-map=\"{}\" src=\"{}\">\n", id,
                            png_uri(png_bytes(aov_colours(values, a.kind == Aov::Cell,
                                                          aov_scale(r, channel)),
                                              w, h, 3)));
      }
    }
    if (row.empty()) continue;
    std::string legend;
    if (a.kind == Aov::Cell) {
      legend = "<p class=\"note\">one colour per cell, neighbours unrelated; grey: no cell</p>";
    } else {
      const AovScale sc = aov_scale(r, channel);
      legend = colour_bar(sc.lo, sc.hi, std::string("aov-") + a.name + "-scale",
                          sc.log ? "log scale" : "linear") +
               "<p class=\"note\">grey: nothing measured</p>";
    }
    diagnostics += fmt::format(
        "<div class=\"grid\">\n<figure class=\"legend\" style=\"width:{}px\"><p><b>{}</b>: "
        "{}</p>{}</figure>\n",
        display_w, a.name, escape_markup(a.meaning), legend);
    diagnostics += row + "</div>\n";
  }
  if (!diagnostics.empty())
    s += "<h2>Diagnostics</h2>\n<p class=\"note\">Per pixel at the camera vertex (the first "
         "surface a path hits), as <code>rll render --aov</code> measures them, in the runs of "
         "the first repeat: flip a map with the reference to see where its structure lies in the "
         "picture.</p>\n" +
         diagnostics;

  if (!r.plot_svg.empty())
    s += "<h2>Convergence</h2>\n<div class=\"plot\">" + r.plot_svg + "</div>\n";
  if (!r.frame_plot_svg.empty())
    s += "<h2>Error per frame</h2>\n<div class=\"plot\">" + r.frame_plot_svg + "</div>\n";
  s += "<div class=\"hidden\">\n" + data + "</div>\n</div>\n";
  s += std::string("<script>") + kScript + "</script>\n</body>\n</html>\n";
  return s;
}

}  // namespace rll
