// Appended to a copy of a compare report by test_compare.cpp: drives the report's controls the
// way a user would and records the outcome in <body data-selftest="ok" | "fail: ...">.
(function () {
  'use strict';
  var root = document.getElementById('report');
  var tries = 0;
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
    document.getElementById('reset-view').click();
    for (var k = 0; k < views.length; ++k)
      if (checksum(views[k]) !== sums[k]) return fail('view ' + k + ' did not return to the full image');
    document.body.dataset.selftest = 'ok';
  }
  run();
})();
