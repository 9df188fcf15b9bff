// Appended to a copy of a compare report by test_compare.cpp: drives the report's controls the
// way a user would (exposure, zoom, flip with the reference) and checks the layout (the colour
// scale's labels, the repeat labels, the convergence plot's text inside its picture and clear of
// each other), clicks a pixel of a learning sampler's image where the report has a cell chart and
// reads its bars (and again through its cell-id map, where compare measured the diagnostics),
// flips every diagnostics map with the reference and back; records the outcome in the body's
// data-selftest attribute, "ok" or "fail: why", data-cell-chart "checked" when a chart was checked
// and data-diagnostics the number of diagnostics maps flipped. (Not spelled out as markup here: this
// text is in the dumped DOM too.)
(function () {
  'use strict';
  var root = document.getElementById('report');
  var tries = 0;
  var errors = [];
  window.addEventListener('error', function (ev) { errors.push(ev.message); });
  window.addEventListener('unhandledrejection', function (ev) { errors.push(String(ev.reason)); });
  function fail(msg) { document.body.dataset.selftest = 'fail: ' + msg; }
  function checksum(c) {
    var d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data, h = 0;
    for (var i = 0; i < d.length; ++i) h = (h * 31 + d[i]) | 0;
    return h;
  }
  function brightness(c) {
    var d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data, s = 0;
    for (var i = 0; i < d.length; i += 4) s += d[i] + d[i + 1] + d[i + 2];
    return s;
  }
  function overlap(a, b) {
    return a.left < b.right && b.left < a.right && a.top < b.bottom && b.top < a.bottom;
  }
  function describe(r) {
    return '[' + [r.left, r.top, r.right, r.bottom].map(Math.round).join(', ') + ']';
  }
  // The colour scale's end labels: on one line each, inside the page, clear of every view.
  function checkLegend(views) {
    var page = document.documentElement;
    var ids = ['scale-min', 'scale-max'], rects = [];
    for (var i = 0; i < ids.length; ++i) {
      var el = document.getElementById(ids[i]);
      if (!el) return 'no #' + ids[i];
      var r = el.getBoundingClientRect(), lines = el.getClientRects().length;
      var lineHeight = parseFloat(getComputedStyle(el).fontSize) * 1.6;
      if (!(r.width > 0 && r.height > 0)) return '#' + ids[i] + ' is not shown';
      if (lines !== 1 || r.height > lineHeight) return '#' + ids[i] + ' wraps: ' + describe(r);
      if (r.left < 0 || r.top < 0 || r.right > page.clientWidth || r.bottom > page.scrollHeight)
        return '#' + ids[i] + ' ' + describe(r) + ' is outside the page, ' + page.clientWidth + ' wide';
      for (var k = 0; k < views.length; ++k)
        if (overlap(r, views[k].getBoundingClientRect()))
          return '#' + ids[i] + ' ' + describe(r) + ' overlaps view ' + k + ' ' + describe(views[k].getBoundingClientRect());
      rects.push(r);
    }
    if (overlap(rects[0], rects[1])) return 'the scale labels overlap each other';
    return '';
  }
  // Every text of the convergence plot lies inside the plot's picture (nothing cut at its edge)
  // and overlaps no other text.
  function checkPlot() {
    var svg = document.querySelector('.plot svg');
    if (!svg) return 'no convergence plot';
    var box = svg.getBoundingClientRect();
    var texts = Array.prototype.slice.call(svg.querySelectorAll('text'));
    if (texts.length < 6) return 'the plot has ' + texts.length + ' texts';
    var rects = texts.map(function (t) { return t.getBoundingClientRect(); });
    for (var i = 0; i < rects.length; ++i) {
      var r = rects[i];
      if (!(r.width > 0)) return 'plot text "' + texts[i].textContent + '" is not shown';
      if (r.left < box.left - 0.5 || r.right > box.right + 0.5 || r.top < box.top - 0.5 || r.bottom > box.bottom + 0.5)
        return 'plot text "' + texts[i].textContent + '" ' + describe(r) + ' is cut by the plot\'s edge ' + describe(box);
      for (var k = 0; k < i; ++k)
        if (overlap(r, rects[k]) && Math.min(r.right, rects[k].right) - Math.max(r.left, rects[k].left) > 1 &&
            Math.min(r.bottom, rects[k].bottom) - Math.max(r.top, rects[k].top) > 1)
          return 'plot texts "' + texts[i].textContent + '" and "' + texts[k].textContent + '" overlap';
    }
    var points = svg.querySelectorAll('circle.pt title');
    if (points.length < 2 || !/relMSE/.test(points[0].textContent)) return 'the plot\'s points do not name their values';
    return '';
  }
  // Clicks the first probed pixel that has a cell, in the chart's own image, and reads the bars:
  // one per cluster shown and kind, and one for the others' sum, the learnt ones (and the
  // oracle's) summing to 1, the values those of the report's data.
  function checkCellChart(prefix) {
    var el = document.querySelector('script.cell-data');
    if (!el) return '';
    var d = JSON.parse(el.textContent);
    var view = document.querySelector('canvas.view[data-source="' + prefix + d.entry + '"]');
    if (!view) return prefix === 'image-' ? 'no view of the charted image' : '';
    var probe = -1;
    for (var i = 0; i < d.probes.length && probe < 0; ++i) if (d.probes[i] >= 0) probe = i;
    if (probe < 0) return 'the chart has no probe with a cell';
    var W = view.width, H = view.height;
    var x = Math.min(W - 1, (probe % d.columns) * d.stride + Math.floor(d.stride / 2));
    var y = Math.min(H - 1, Math.floor(probe / d.columns) * d.stride + Math.floor(d.stride / 2));
    var box = document.getElementById('cell-chart');
    box.dataset.cell = '';  // (a chart shown by an earlier click is not taken for this one's)
    var r = view.getBoundingClientRect();
    view.dispatchEvent(new MouseEvent('click', { clientX: r.left + (x + 0.5) / W * r.width,
                                                 clientY: r.top + (y + 0.5) / H * r.height, bubbles: true }));
    var cell = d.cells[d.probes[probe]];
    if (box.dataset.cell !== String(cell.id))
      return 'clicking pixel (' + x + ', ' + y + ') showed cell "' + box.dataset.cell + '", not ' + cell.id;
    var kinds = d.oracle ? ['learnt', 'tree', 'oracle'] : ['learnt', 'tree'];
    for (var k = 0; k < kinds.length; ++k) {
      var bars = box.querySelectorAll('rect.bar[data-kind="' + kinds[k] + '"]');
      var rows = cell.learnt.length + (cell.rest ? 1 : 0);
      if (bars.length !== rows) return kinds[k] + ': ' + bars.length + ' bars for ' + rows + ' rows';
      var sum = 0, data = cell.rest ? cell.rest[kinds[k]] : 0;
      for (var b = 0; b < bars.length; ++b) sum += Number(bars[b].dataset.value);
      for (var c = 0; c < cell[kinds[k]].length; ++c) data += cell[kinds[k]][c];
      if (Math.abs(sum - data) > 1e-6) return kinds[k] + ' bars sum to ' + sum + ', the data to ' + data;
      if (kinds[k] !== 'tree' && Math.abs(sum - 1) > 0.01) return 'the ' + kinds[k] + ' bars sum to ' + sum;
      if (!(bars[0].getBoundingClientRect().width > 0) && sum > 0) return 'a ' + kinds[k] + ' bar is not drawn';
    }
    document.body.dataset.cellChart = 'checked';
    return '';
  }
  // The diagnostics maps (compare --aov): each view shows its own picture, which its flip button
  // turns into the reference's (same zoom and exposure) and back; the maps are not all alike.
  function checkDiagnostics(views) {
    var maps = Array.prototype.filter.call(views, function (c) { return /^aov-/.test(c.dataset.source); });
    if (!maps.length) return '';
    var ref = checksum(views[0]), pictures = {};
    for (var i = 0; i < maps.length; ++i) {
      var c = maps[i], own = checksum(c), b = flipButton(c);
      if (!b) return 'diagnostics map ' + c.dataset.source + ' has no flip button';
      if (own === ref) return 'diagnostics map ' + c.dataset.source + ' shows the reference before the flip';
      b.click();
      if (checksum(c) !== ref) return 'the flip button did not show the reference in ' + c.dataset.source;
      if (!c.closest('figure').classList.contains('flipped')) return 'flipped map ' + c.dataset.source + ' is not marked';
      b.click();
      if (checksum(c) !== own) return 'flipping ' + c.dataset.source + ' back did not restore its map';
      pictures[own] = true;
    }
    if (Object.keys(pictures).length < 2) return 'every diagnostics map shows the same picture';
    document.body.dataset.diagnostics = String(maps.length);
    return '';
  }
  function flipButton(view) { return view.closest('figure').querySelector('button.flip'); }
  function pressF() {
    document.dispatchEvent(new KeyboardEvent('keydown', { key: 'f', bubbles: true, cancelable: true }));
  }
  // Flips, with the views zoomed: a flipped view shows the reference's pixels exactly (same zoom,
  // pan and exposure), and flipping back restores its own.
  function checkFlip(views) {
    if (flipButton(views[0])) return 'the reference view has a flip button';
    var ref = checksum(views[0]), own = checksum(views[1]);
    if (own === ref) return 'view 1 already shows the reference before the flip';
    flipButton(views[1]).click();
    if (checksum(views[1]) !== ref) return 'the flip button did not show the reference in view 1';
    if (!views[1].closest('figure').classList.contains('flipped')) return 'a flipped view is not marked';
    if (checksum(views[2]) === ref) return 'flipping view 1 flipped view 2 too';
    flipButton(views[1]).click();
    if (checksum(views[1]) !== own) return 'flipping view 1 back did not restore its image';
    var sums = Array.prototype.map.call(views, checksum);
    pressF();
    for (var i = 1; i < views.length; ++i)
      if (checksum(views[i]) !== ref) return 'F did not flip view ' + i + ' with the reference';
    pressF();
    for (var k = 0; k < views.length; ++k)
      if (checksum(views[k]) !== sums[k]) return 'a second F did not flip view ' + k + ' back';
    return '';
  }
  function run() {
    if (root.dataset.ready !== '1') {
      if (++tries > 500) return fail('the report never became ready');
      return setTimeout(run, 10);
    }
    var views = document.querySelectorAll('canvas.view');
    if (views.length < 3) return fail('expected the reference, images and error maps, found ' + views.length + ' views');
    var exposure = document.getElementById('exposure');
    var before = brightness(views[0]);
    if (!(before > 0)) return fail('the reference view is black');
    exposure.value = String(Number(exposure.value) + 2);
    exposure.dispatchEvent(new Event('input'));
    var after = brightness(views[0]);
    if (!(after > before)) return fail('a higher exposure did not brighten the image: ' + before + ' -> ' + after);

    var sums = Array.prototype.map.call(views, checksum);
    var r = views[1].getBoundingClientRect();
    views[1].dispatchEvent(new WheelEvent('wheel', { deltaY: -100, clientX: r.left + r.width / 4,
                                                    clientY: r.top + r.height / 4, bubbles: true, cancelable: true }));
    if (document.getElementById('zoom-value').textContent === '1.00x') return fail('the wheel did not zoom');
    for (var i = 0; i < views.length; ++i)
      if (checksum(views[i]) === sums[i]) return fail('view ' + i + ' did not follow the zoom');
    var flip = checkFlip(views);
    if (flip) return fail(flip);
    document.getElementById('reset-view').click();
    for (var k = 0; k < views.length; ++k)
      if (checksum(views[k]) !== sums[k]) return fail('view ' + k + ' did not return to the full image');
    var legend = checkLegend(views);
    if (legend) return fail(legend);
    var plot = checkPlot();
    if (plot) return fail(plot);
    var diagnostics = checkDiagnostics(views);
    if (diagnostics) return fail(diagnostics);
    var chart = checkCellChart('aov-cell-') || checkCellChart('image-');
    if (chart) return fail(chart);
    // Every sampler's image and map says which repeat it shows (the comparison has 2 repeats).
    var captions = document.querySelectorAll('figure canvas.view:not([data-source="reference"])');
    for (var j = 0; j < captions.length; ++j) {
      var label = captions[j].closest('figure').querySelector('figcaption .repeat');
      if (!label || !/repeat/.test(label.textContent))
        return fail('view ' + captions[j].dataset.source + ' does not say which repeat it shows');
    }
    if (errors.length) return fail('script errors: ' + errors.join('; '));
    document.body.dataset.selftest = 'ok';
  }
  run();
})();
