/* The 3-D plan page: unpacks plotly.js, draws the scene from one copy of its geometry moved by
 * link poses, and drives the time (slider, step buttons, playback speed, #t= / #step=).
 * window.sdarViewer exposes the state (t, step, playing, speed) and the controls. */
(function () {
  'use strict';
  function $(id) { return document.getElementById(id); }

  function banner(html) {
    var b = $('sdar-banner');
    b.innerHTML = html;
    b.hidden = false;
    return b;
  }

  function decode(spec) {  // a plotly.js typed-array spec {dtype, bdata} -> a typed array
    var s = atob(spec.bdata), u = new Uint8Array(s.length);
    for (var i = 0; i < s.length; i++) u[i] = s.charCodeAt(i);
    if (spec.dtype === 'f4') return new Float32Array(u.buffer);
    if (spec.dtype === 'i4') return new Int32Array(u.buffer);
    return u;
  }

  // -- poses: [x, y, z, qx, qy, qz, qw] ---------------------------------------------------------
  function lerpPose(a, ia, b, ib, w) {
    var out = new Array(7), dot = 0, n = 0, i;
    for (i = 0; i < 3; i++) out[i] = a[ia + i] + w * (b[ib + i] - a[ia + i]);
    for (i = 3; i < 7; i++) dot += a[ia + i] * b[ib + i];
    var s = dot < 0 ? -1 : 1;
    for (i = 3; i < 7; i++) { out[i] = (1 - w) * a[ia + i] + w * s * b[ib + i]; n += out[i] * out[i]; }
    n = Math.sqrt(n) || 1;
    for (i = 3; i < 7; i++) out[i] /= n;
    return out;
  }

  function matrix(p) {  // rotation (row major) then translation
    var x = p[3], y = p[4], z = p[5], w = p[6];
    return [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w),
      2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w),
      2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y), p[0], p[1], p[2]];
  }

  function compose(a, b) {  // the pose a * b
    var m = matrix(a), ax = a[3], ay = a[4], az = a[5], aw = a[6];
    var bx = b[3], by = b[4], bz = b[5], bw = b[6];
    return [m[0] * b[0] + m[1] * b[1] + m[2] * b[2] + m[9],
      m[3] * b[0] + m[4] * b[1] + m[5] * b[2] + m[10],
      m[6] * b[0] + m[7] * b[1] + m[8] * b[2] + m[11],
      aw * bx + ax * bw + ay * bz - az * by,
      aw * by - ax * bz + ay * bw + az * bx,
      aw * bz + ax * by - ay * bx + az * bw,
      aw * bw - ax * bx - ay * by - az * bz];
  }

  function place(m, local, v, X, Y, Z, o) {  // local vertex v moved by matrix m into slot o
    var x = local[3 * v], y = local[3 * v + 1], z = local[3 * v + 2];
    X[o] = m[0] * x + m[1] * y + m[2] * z + m[9];
    Y[o] = m[3] * x + m[4] * y + m[5] * z + m[10];
    Z[o] = m[6] * x + m[7] * y + m[8] * z + m[11];
  }

  function fmt(t) { return t.toFixed(2); }

  function start() {
    var D = JSON.parse($('sdar-data').textContent);
    var T = D.times, t0 = D.t0, t1 = D.t1, steps = D.steps, events = D.events;
    var gd = $('sdar-viewer'), gj = $('sdar-joints');
    var fig = D.figure, data = fig.data, layout = fig.layout;
    var arms = D.arms.map(function (a) {
      return { name: a.name, colour: a.colour, L: a.links.length, local: decode(a.local),
        vlink: decode(a.vlink), poses: decode(a.poses), tcp: decode(a.tcp),
        closure: decode(a.closure) };
    });
    var objLocal = decode(D.objectLocal);
    var state = { t: t0, step: -1, playing: false, speed: 1 };
    var rev = 0;

    function frameAt(t) {
      var n = T.length;
      if (n === 1 || t <= T[0]) return [0, 0, 0];
      if (t >= T[n - 1]) return [n - 1, n - 1, 0];
      var lo = 0, hi = n - 1;
      while (hi - lo > 1) { var mid = (lo + hi) >> 1; if (T[mid] <= t) lo = mid; else hi = mid; }
      return [lo, hi, (t - T[lo]) / (T[hi] - T[lo])];
    }

    function stepAt(t) {
      var k = -1;
      for (var i = 0; i < steps.length; i++) if (steps[i].t_start <= t + 1e-9) k = i;
      return k;
    }

    function holdAt(obj, t) {
      var h = obj.holds[0];
      for (var i = 1; i < obj.holds.length; i++) if (obj.holds[i][0] <= t + 1e-12) h = obj.holds[i];
      return h;
    }

    function render(t) {
      var f = frameAt(t), k0 = f[0], k1 = f[1], w = f[2];
      var tcp = [], closed = [], holding = [[], []];
      arms.forEach(function (arm, a) {
        var L = arm.L, mats = [], m = arm.vlink.length;
        for (var j = 0; j < L; j++) {
          mats.push(matrix(lerpPose(arm.poses, 7 * (k0 * L + j), arm.poses, 7 * (k1 * L + j), w)));
        }
        var X = new Float32Array(m), Y = new Float32Array(m), Z = new Float32Array(m);
        for (var v = 0; v < m; v++) place(mats[arm.vlink[v]], arm.local, v, X, Y, Z, v);
        var trace = data[D.traces.arms[a]];
        trace.x = X; trace.y = Y; trace.z = Z;
        tcp.push(lerpPose(arm.tcp, 7 * k0, arm.tcp, 7 * k1, w));
        closed.push(arm.closure[k0] + w * (arm.closure[k1] - arm.closure[k0]) > 0.5);
      });
      var n = D.objects.length, OX = new Float32Array(8 * n), OY = new Float32Array(8 * n),
        OZ = new Float32Array(8 * n), lx = [], ly = [], lz = [], lt = [];
      var moving = state.step >= 0 && t <= steps[state.step].t_end ? steps[state.step].objects : [];
      D.objects.forEach(function (obj, b) {
        var h = holdAt(obj, t), pose = h[1] >= 0 ? compose(tcp[h[1]], h[2]) : h[2];
        var m = matrix(pose);
        for (var v = 0; v < 8; v++) place(m, objLocal, 8 * b + v, OX, OY, OZ, 8 * b + v);
        if (h[1] >= 0) holding[h[1]].push(obj.name);
        if (h[1] >= 0 || moving.indexOf(obj.name) >= 0) {
          var r = Math.max(obj.size[0], obj.size[1]) / 2 + 0.1;  // held: in front, clear of the gripper
          lx.push(pose[0]); ly.push(pose[1] - (h[1] >= 0 ? r : 0));
          lz.push(pose[2] + (h[1] >= 0 ? -0.04 : obj.size[2] / 2 + 0.03));
          lt.push(h[1] >= 0 ? '<b>' + obj.name + '</b> (' + arms[h[1]].name + ')' : obj.name);
        }
      });
      var o = data[D.traces.objects];
      o.x = OX; o.y = OY; o.z = OZ;
      var lab = data[D.traces.labels];
      lab.x = lx; lab.y = ly; lab.z = lz; lab.text = lt;
      hud(t, closed, holding);
      layout.datarevision = ++rev;
      var done = [Plotly.react(gd, data, layout)];
      if (D.joints) done.push(Plotly.relayout(gj, { 'shapes[0].x0': t, 'shapes[0].x1': t }));
      return Promise.all(done);
    }

    function hud(t, closed, holding) {
      $('sdar-hud-time').textContent = T.length > 1 ? 't = ' + fmt(t) + ' s of ' + fmt(t1) + ' s'
        : 'start (arms at home)';
      var k = state.step, text = '';
      if (steps.length) {
        if (k < 0) text = 'before step 1';
        else if (t <= steps[k].t_end + 1e-9) text = 'step ' + (k + 1) + ' of ' + steps.length + ': ' + steps[k].label;
        else text = 'after step ' + (k + 1) + ' of ' + steps.length + ' (gripper)';
      }
      $('sdar-hud-step').textContent = text;
      $('sdar-hud-arms').innerHTML = arms.map(function (arm, a) {
        var held = holding[a].length ? ', holding <b>' + holding[a].join(', ') + '</b>' : '';
        return '<div><span class="arm" style="color:' + arm.colour + '">' + arm.name +
          '</span>: gripper <span class="' + (closed[a] ? 'closed">closed' : 'open">open') +
          '</span>' + held + '</div>';
      }).join('');
    }

    // -- rendering at most one frame at a time ----------------------------------------------
    var busy = false, wanted = null;
    function pump() {
      if (wanted === null) { busy = false; return; }
      busy = true;
      var t = wanted;
      wanted = null;
      render(t).then(pump, function (e) { busy = false; console.error(e); });
    }
    function request(t) { wanted = t; if (!busy) pump(); }
    function whenDrawn() {  // resolves once every requested time is drawn
      return new Promise(function (resolve) {
        (function wait() { if (busy || wanted !== null) setTimeout(wait, 5); else resolve(); })();
      });
    }

    function publish() {
      document.body.setAttribute('data-sdar-t', state.t.toFixed(3));
      document.body.setAttribute('data-sdar-step', String(state.step));
      document.body.setAttribute('data-sdar-playing', String(state.playing));
      document.body.setAttribute('data-sdar-speed', String(state.speed));
    }

    function setTime(t) {
      t = Math.min(t1, Math.max(t0, Number(t)));
      if (!isFinite(t)) return;
      state.t = t;
      state.step = stepAt(t);
      var slider = $('sdar-slider');
      if (document.activeElement !== slider || state.playing) slider.value = String(t);
      $('sdar-clock').textContent = fmt(t) + ' / ' + fmt(t1) + ' s';
      var bands = document.querySelectorAll('.sdar-step');
      for (var i = 0; i < bands.length; i++) bands[i].classList.toggle('current', i === state.step);
      publish();
      request(t);
    }

    function nextStep() {
      for (var i = 0; i < steps.length; i++) {
        if (steps[i].t_start > state.t + 1e-6) { setTime(steps[i].t_start); return; }
      }
      setTime(t1);
    }
    function prevStep() {
      var target = t0;
      for (var i = 0; i < steps.length; i++) if (steps[i].t_start < state.t - 1e-6) target = steps[i].t_start;
      setTime(target);
    }

    var last = 0;
    function tick(now) {
      if (!state.playing) return;
      var dt = Math.min(0.25, (now - last) / 1000);
      last = now;
      var t = state.t + dt * state.speed;
      if (t >= t1) { setTime(t1); pause(); return; }
      setTime(t);
      requestAnimationFrame(tick);
    }
    function play() {
      if (state.playing) return;
      if (state.t >= t1 - 1e-6) setTime(t0);
      state.playing = true;
      $('sdar-play').innerHTML = '&#x275A;&#x275A; pause';
      last = performance.now();
      publish();
      requestAnimationFrame(tick);
    }
    function pause() {
      state.playing = false;
      $('sdar-play').innerHTML = '&#x25B6; play';
      publish();
    }
    function setSpeed(s) {
      s = Number(s);
      if (isFinite(s) && s > 0) { state.speed = s; $('sdar-speed').value = String(s); publish(); }
    }

    // -- the time line: steps, events, the violation ------------------------------------------
    function at(t) {  // a position on the slider's track (the thumb's centre at time t)
      var f = t1 > t0 ? (t - t0) / (t1 - t0) : 0;
      return 'calc(var(--thumb) / 2 + (100% - var(--thumb)) * ' + f.toFixed(5) + ')';
    }
    function timeline() {
      var slider = $('sdar-slider');
      slider.min = String(t0); slider.max = String(t1); slider.value = String(t0);
      slider.addEventListener('input', function () { setTime(parseFloat(slider.value)); });
      var row = $('sdar-steps');
      steps.forEach(function (s, i) {
        var el = document.createElement('div');
        el.className = 'sdar-step' + (i % 2 ? ' odd' : '') + (s.kind ? ' ' + s.kind.replace(/[^a-z0-9-]/gi, '') : '');
        el.style.left = at(s.t_start);
        el.style.width = 'calc((100% - var(--thumb)) * ' + ((s.t_end - s.t_start) / (t1 - t0)).toFixed(5) + ')';
        el.textContent = (i + 1) + ' ' + s.label;
        el.title = 'step ' + (i + 1) + ': ' + s.label + ' (' + fmt(s.t_start) + '-' + fmt(s.t_end) + ' s)';
        el.addEventListener('click', function () { setTime(s.t_start); });
        row.appendChild(el);
      });
      var evs = $('sdar-events');
      events.forEach(function (e) {
        var el = document.createElement('span');
        el.className = 'sdar-at sdar-ev ' + e.type;
        el.style.left = at(e.t);
        el.style.color = arms[e.arm].colour;
        el.textContent = e.type === 'grasp' ? '\u25BC' : '\u25B2';
        el.title = fmt(e.t) + ' s: ' + arms[e.arm].name + ' ' + (e.type === 'grasp' ? 'grasps ' : 'releases ') + e.object;
        el.addEventListener('click', function () { setTime(e.t); });
        evs.appendChild(el);
      });
      var v = D.violation;
      if (v) {
        var mark = document.createElement('span');
        mark.id = 'sdar-violation-mark';
        mark.className = 'sdar-at sdar-ev sdar-violation';
        mark.style.left = at(v.t);
        mark.textContent = '\u2716';
        mark.title = fmt(v.t) + ' s: ' + v.kind + ': ' + v.message;
        mark.addEventListener('click', function () { setTime(v.t); });
        evs.appendChild(mark);
        var line = document.createElement('div');
        line.className = 'sdar-vline';
        line.style.left = at(v.t);
        $('sdar-timeline').appendChild(line);
      }
      $('sdar-prev').addEventListener('click', prevStep);
      $('sdar-next').addEventListener('click', nextStep);
      $('sdar-play').addEventListener('click', function () { if (state.playing) pause(); else play(); });
      $('sdar-speed').addEventListener('change', function () { setSpeed($('sdar-speed').value); });
      document.addEventListener('keydown', function (ev) {
        var tag = ev.target && ev.target.tagName;
        if (tag === 'SELECT' || tag === 'INPUT' || tag === 'BUTTON') return;
        if (ev.key === ' ') { if (state.playing) pause(); else play(); ev.preventDefault(); }
        else if (ev.key === 'ArrowRight') nextStep();
        else if (ev.key === 'ArrowLeft') prevStep();
      });
      $('sdar-controls').hidden = false;
    }

    function verdict() {
      var v = D.violation, el = $('sdar-verdict');
      if (v) {
        el.textContent = '\u2716 invalid (sdar validate)';
        el.className = 'bad';
        var b = banner('<b>sdar validate: invalid at t = ' + fmt(v.t) + ' s</b> &mdash; ' +
          v.kind + ': <span id="sdar-violation-text"></span><button type="button" id="sdar-goto">show</button>');
        $('sdar-violation-text').textContent = v.message;
        $('sdar-goto').addEventListener('click', function () { setTime(v.t); });
        b.setAttribute('data-kind', v.kind);
      } else if (D.validated) {
        el.textContent = '\u2714 valid (sdar validate)';
        el.className = 'ok';
      }
    }

    function initial() {
      var h = window.location.hash, m = /[#&]t=([-0-9.eE]+)/.exec(h), s = /[#&]step=(\d+)/.exec(h);
      if (m) return parseFloat(m[1]);
      if (s && steps.length) return steps[Math.min(steps.length, Math.max(1, parseInt(s[1], 10))) - 1].t_start;
      return t0;
    }

    window.sdarViewer = {
      get t() { return state.t; },
      get step() { return state.step; },
      get playing() { return state.playing; },
      get speed() { return state.speed; },
      steps: steps, events: events, violation: D.violation,
      setTime: setTime, play: play, pause: pause, nextStep: nextStep, prevStep: prevStep,
      setSpeed: setSpeed, whenDrawn: whenDrawn
    };
    verdict();
    $('sdar-joints-pane').hidden = !D.joints;
    var config = { displaylogo: false, responsive: true };
    var ready = [Plotly.newPlot(gd, data, layout, config)];
    if (D.joints) {
      var xs = decode(D.joints.x);
      D.joints.data.forEach(function (trace) { trace.x = xs; });
      ready.push(Plotly.newPlot(gj, D.joints.data, D.joints.layout,
        { displaylogo: false, responsive: true, displayModeBar: false }));
    }
    Promise.all(ready).then(function () {
      if (D.joints) gj.on('plotly_click', function (ev) { if (ev.points.length) setTime(ev.points[0].x); });
      if (T.length > 1) timeline();
      setTime(initial());
      return whenDrawn();
    }).then(function () {
      document.body.setAttribute('data-sdar-ready', String(T.length));
      window.dispatchEvent(new Event('sdar-ready'));
    }, function (e) { banner('The page could not draw the plan: ' + String(e)); console.error(e); });
  }

  // -- unpack plotly.js (gzip, base64), then start ----------------------------------------------
  if (typeof DecompressionStream === 'undefined') {
    banner('This browser cannot unpack the page (no DecompressionStream): use Chrome 80, ' +
      'Firefox 113, Safari 16.4 or later.');
    return;
  }
  var packed = atob($('sdar-plotly').textContent.trim()), bytes = new Uint8Array(packed.length);
  for (var i = 0; i < packed.length; i++) bytes[i] = packed.charCodeAt(i);
  new Response(new Blob([bytes]).stream().pipeThrough(new DecompressionStream('gzip'))).text()
    .then(function (code) {
      var s = document.createElement('script');
      s.text = code;
      document.head.appendChild(s);
      start();
    })
    .catch(function (e) { banner('The page could not start: ' + String(e)); console.error(e); });
})();
