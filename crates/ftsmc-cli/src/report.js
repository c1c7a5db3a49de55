// The 3-D replay of report.html (crates/ftsmc-cli/src/html.rs): plain
// JavaScript on a <canvas>, no library. Orthographic view of the world frame
// (z up) turned by a yaw and an elevation (drag to rotate, wheel to zoom);
// the path flown up to the slider's time, the reference dashed, and the
// vehicle as a "+" of four arms rotated by R = Rz(psi) Ry(theta) Rx(phi)
// (paper Eq. 1), front arm red, its thrust axis blue.
(function () {
  'use strict';
  var dataEl = document.getElementById('replay-data');
  var canvas = document.getElementById('replay-canvas');
  if (!dataEl || !canvas) { document.body.setAttribute('data-replay', 'none'); return; }
  var runs = JSON.parse(dataEl.textContent);
  var ctx = canvas.getContext('2d');
  var select = document.getElementById('replay-run');
  var slider = document.getElementById('replay-time');
  var label = document.getElementById('replay-label');
  var play = document.getElementById('replay-play');
  var view = { yaw: -0.9, elev: 0.45, zoom: 1.0 };
  var state = { run: 0, frame: 0, playing: false, timer: null };

  runs.forEach(function (r, i) {
    var o = document.createElement('option');
    o.value = String(i);
    o.textContent = r.name;
    select.appendChild(o);
  });

  function finite(p) { return p && p[0] !== null && p[1] !== null && p[2] !== null; }

  function bounds(r) {
    var lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
    [r.p, r.r || []].forEach(function (pts) {
      pts.forEach(function (p) {
        if (!finite(p)) return;
        for (var k = 0; k < 3; k++) { lo[k] = Math.min(lo[k], p[k]); hi[k] = Math.max(hi[k], p[k]); }
      });
    });
    for (var k = 0; k < 3; k++) {
      if (!isFinite(lo[k])) { lo[k] = -1; hi[k] = 1; }
      if (hi[k] - lo[k] < 0.2) { var c = (hi[k] + lo[k]) / 2; lo[k] = c - 0.1; hi[k] = c + 0.1; }
    }
    return { lo: lo, hi: hi };
  }

  function rotation(a) {
    var cf = Math.cos(a[0]), sf = Math.sin(a[0]), ct = Math.cos(a[1]), st = Math.sin(a[1]);
    var cp = Math.cos(a[2]), sp = Math.sin(a[2]);
    return [[cp * ct, cp * st * sf - sp * cf, cp * st * cf + sp * sf],
            [sp * ct, sp * st * sf + cp * cf, sp * st * cf - cp * sf],
            [-st, ct * sf, ct * cf]];
  }

  // World point -> canvas point (and depth, larger is nearer the viewer).
  function projector(b) {
    var c = [0, 1, 2].map(function (k) { return (b.lo[k] + b.hi[k]) / 2; });
    var span = Math.max(b.hi[0] - b.lo[0], b.hi[1] - b.lo[1], b.hi[2] - b.lo[2]);
    var s = 0.62 * Math.min(canvas.width, canvas.height) / span * view.zoom;
    var cy = Math.cos(view.yaw), sy = Math.sin(view.yaw), ce = Math.cos(view.elev), se = Math.sin(view.elev);
    return function (p) {
      var x = p[0] - c[0], y = p[1] - c[1], z = p[2] - c[2];
      var u = cy * x - sy * y;            // screen right
      var d = sy * x + cy * y;            // into the screen before tilting
      var v = ce * z - se * d;            // screen up
      var depth = se * z + ce * d;
      return [canvas.width / 2 + s * u, canvas.height / 2 - s * v, depth];
    };
  }

  function line(proj, pts, color, width, dash) {
    ctx.strokeStyle = color; ctx.lineWidth = width; ctx.setLineDash(dash || []);
    ctx.beginPath();
    var pen = false;
    pts.forEach(function (p) {
      if (!finite(p)) { pen = false; return; }
      var q = proj(p);
      if (pen) ctx.lineTo(q[0], q[1]); else ctx.moveTo(q[0], q[1]);
      pen = true;
    });
    ctx.stroke();
    ctx.setLineDash([]);
  }

  function tickValues(lo, hi) {
    var step = Math.pow(10, Math.floor(Math.log10((hi - lo) / 4)));
    if ((hi - lo) / step > 8) step *= 2.5;
    if ((hi - lo) / step > 8) step *= 2;
    var out = [];
    for (var v = Math.ceil(lo / step) * step; v <= hi + 1e-9; v += step) out.push(Math.abs(v) < 1e-12 ? 0 : v);
    return out;
  }

  function box(proj, b) {
    // The floor grid (z = lo) and the vertical edges: the depth cue.
    ctx.font = '12px sans-serif';
    ctx.fillStyle = '#555';
    var lo = b.lo, hi = b.hi;
    tickValues(lo[0], hi[0]).forEach(function (x) {
      line(proj, [[x, lo[1], lo[2]], [x, hi[1], lo[2]]], '#e3e3e3', 1);
      var q = proj([x, lo[1], lo[2]]); ctx.fillText(x.toFixed(2), q[0] - 12, q[1] + 14);
    });
    tickValues(lo[1], hi[1]).forEach(function (y) {
      line(proj, [[lo[0], y, lo[2]], [hi[0], y, lo[2]]], '#e3e3e3', 1);
      var q = proj([hi[0], y, lo[2]]); ctx.fillText(y.toFixed(2), q[0] + 4, q[1] + 4);
    });
    tickValues(lo[2], hi[2]).forEach(function (z) {
      line(proj, [[lo[0], hi[1], z], [hi[0], hi[1], z]], '#efefef', 1);
      var q = proj([lo[0], hi[1], z]); ctx.fillText(z.toFixed(2), q[0] - 40, q[1] + 4);
    });
    [[lo[0], lo[1]], [hi[0], lo[1]], [lo[0], hi[1]], [hi[0], hi[1]]].forEach(function (c) {
      line(proj, [[c[0], c[1], lo[2]], [c[0], c[1], hi[2]]], '#cfcfcf', 1);
    });
    var ax = proj([hi[0], lo[1], lo[2]]), ay = proj([hi[0], hi[1], lo[2]]), az = proj([lo[0], hi[1], hi[2]]);
    ctx.fillStyle = '#222'; ctx.font = '14px sans-serif';
    ctx.fillText('x (m)', ax[0] + 6, ax[1] + 28);
    ctx.fillText('y (m)', ay[0] + 24, ay[1] + 18);
    ctx.fillText('z (m)', az[0] - 40, az[1] - 10);
  }

  function draw() {
    var r = runs[state.run];
    var b = bounds(r);
    var proj = projector(b);
    ctx.clearRect(0, 0, canvas.width, canvas.height);
    ctx.fillStyle = '#fff'; ctx.fillRect(0, 0, canvas.width, canvas.height);
    box(proj, b);
    var k = Math.min(state.frame, r.t.length - 1);
    line(proj, r.p, 'rgba(31,119,180,0.22)', 1.5);         // the whole flight, faint
    line(proj, r.p.slice(0, k + 1), '#1f77b4', 2.2);       // flown so far
    if (r.r) line(proj, r.r, '#000', 1.6, [7, 5]);         // reference on top, dashed
    if (r.r && finite(r.r[k])) {                           // the set-point now: a black ring
      var rq = proj(r.r[k]);
      ctx.strokeStyle = '#000'; ctx.lineWidth = 2; ctx.beginPath(); ctx.arc(rq[0], rq[1], 9, 0, 2 * Math.PI); ctx.stroke();
    }
    var p = r.p[k], a = r.a[k];
    if (finite(p) && finite(a)) {
      var R = rotation(a);
      var span = Math.max(b.hi[0] - b.lo[0], b.hi[1] - b.lo[1], b.hi[2] - b.lo[2]);
      var arm = 0.06 * span;
      var body = [[arm, 0, 0], [0, arm, 0], [-arm, 0, 0], [0, -arm, 0], [0, 0, 0.7 * arm]];
      var world = body.map(function (v) {
        return [0, 1, 2].map(function (i) { return p[i] + R[i][0] * v[0] + R[i][1] * v[1] + R[i][2] * v[2]; });
      });
      // The shadow on the floor: where the vehicle is over the ground.
      var shadow = [p[0], p[1], b.lo[2]];
      var sq = proj(shadow);
      ctx.fillStyle = 'rgba(0,0,0,0.18)'; ctx.beginPath(); ctx.arc(sq[0], sq[1], 6, 0, 2 * Math.PI); ctx.fill();
      line(proj, [p, shadow], 'rgba(0,0,0,0.15)', 1, [3, 3]);
      for (var i = 0; i < 4; i++) {
        line(proj, [p, world[i]], i === 0 ? '#d62728' : '#222', 3.5);
        var q = proj(world[i]);
        ctx.fillStyle = i === 0 ? '#d62728' : '#222';
        ctx.beginPath(); ctx.arc(q[0], q[1], 5, 0, 2 * Math.PI); ctx.fill();
      }
      line(proj, [p, world[4]], '#1f77b4', 2.5);
    }
    var t = r.t[k];
    label.textContent = 't = ' + (t === null ? '—' : t.toFixed(2)) + ' s of ' + r.t[r.t.length - 1].toFixed(2) + ' s';
    slider.value = String(Math.round(1000 * k / Math.max(1, r.t.length - 1)));
  }

  function setRun(i) {
    state.run = i;
    state.frame = runs[i].t.length - 1;
    draw();
  }

  select.addEventListener('change', function () { setRun(Number(select.value)); });
  slider.addEventListener('input', function () {
    var r = runs[state.run];
    state.frame = Math.round(Number(slider.value) / 1000 * (r.t.length - 1));
    draw();
  });
  play.addEventListener('click', function () {
    if (state.playing) {
      clearInterval(state.timer); state.playing = false; play.textContent = 'play'; return;
    }
    var r = runs[state.run];
    if (state.frame >= r.t.length - 1) state.frame = 0;
    state.playing = true; play.textContent = 'pause';
    state.timer = setInterval(function () {
      var n = runs[state.run].t.length;
      state.frame += 1;
      if (state.frame >= n - 1) { state.frame = n - 1; clearInterval(state.timer); state.playing = false; play.textContent = 'play'; }
      draw();
    }, 40);
  });
  var drag = null;
  canvas.addEventListener('pointerdown', function (e) { drag = [e.clientX, e.clientY]; canvas.setPointerCapture(e.pointerId); });
  canvas.addEventListener('pointerup', function () { drag = null; });
  canvas.addEventListener('pointermove', function (e) {
    if (!drag) return;
    view.yaw -= (e.clientX - drag[0]) * 0.01;
    view.elev = Math.max(-1.5, Math.min(1.5, view.elev + (e.clientY - drag[1]) * 0.01));
    drag = [e.clientX, e.clientY];
    draw();
  });
  canvas.addEventListener('wheel', function (e) {
    e.preventDefault();
    view.zoom = Math.max(0.3, Math.min(6, view.zoom * (e.deltaY < 0 ? 1.1 : 1 / 1.1)));
    draw();
  }, { passive: false });
  if (runs.length > 0) setRun(0);
  // A link can open the replay at a time: report.html#t=12.5 (s).
  var at = /[#&]t=([0-9.]+)/.exec(window.location.hash);
  if (at && runs.length > 0) {
    var r0 = runs[0], want = Number(at[1]), best = 0;
    for (var i = 0; i < r0.t.length; i++) { if (r0.t[i] !== null && r0.t[i] <= want) best = i; }
    state.frame = best;
    draw();
  }
  document.body.setAttribute('data-replay', 'ready');
})();

// Where the first table, figure and the replay sit on the page (CSS px),
// for the browser test's screenshot check.
(function () {
  'use strict';
  function place(el) {
    if (!el) return null;
    var r = el.getBoundingClientRect();
    return [Math.round(r.left + window.scrollX), Math.round(r.top + window.scrollY), Math.round(r.width), Math.round(r.height)];
  }
  document.body.setAttribute('data-layout', JSON.stringify({
    table: place(document.querySelector('table')),
    figure: place(document.querySelector('figure svg')),
    replay: place(document.getElementById('replay-canvas'))
  }));
})();
