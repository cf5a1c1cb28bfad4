// symcorr view: the viewer inside every page `symcorr view` writes. It reads the JSON object of
// <script id="symcorr-data">, draws it with three.js (the global THREE of the script before
// this one) and reports its state as window.symcorrView (DESIGN.md, `symcorr view`).
(function () {
  'use strict';

  var state = {
    ready: false, // true once the first frame is drawn
    kind: null, // 'pair' | 'labels' | 'track'
    mode: null, // colour mode
    modes: [],
    selected: null, // what the last click or hover picked
    loadMs: null, // milliseconds from navigation start to the first frame
    error: null,
    frame: null, // track view: index of the frame shown
    playing: false,
  };
  window.symcorrView = state;

  function fail(message) {
    state.error = message;
    var el = document.getElementById('error');
    el.textContent = 'symcorr view: ' + message;
    el.style.display = 'block';
    console.error('symcorr view: ' + message);
  }

  // ---- data -------------------------------------------------------------------------------
  function decode(b64, Type) {
    var bin = atob(b64);
    var bytes = new Uint8Array(bin.length);
    for (var i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);
    return new Type(bytes.buffer);
  }

  var data;
  try {
    data = JSON.parse(document.getElementById('symcorr-data').textContent);
  } catch (e) {
    fail('the page data cannot be read: ' + e.message);
    return;
  }
  state.kind = data.kind;
  var SEGMENTS = data.segments; // [{name, colour: [r, g, b]}] in index order
  var NO_SEGMENT = 255;
  var LEFT = [3, 5, 7, 9, 11, 13, 15];
  var RIGHT = [4, 6, 8, 10, 12, 14, 16];

  // sRGB 0..255 → linear 0..1 (three.js works in linear light and writes sRGB).
  function lin(c) {
    c /= 255;
    return c <= 0.04045 ? c / 12.92 : Math.pow((c + 0.055) / 1.055, 2.4);
  }
  function setRGB(arr, i, rgb) {
    arr[3 * i] = lin(rgb[0]);
    arr[3 * i + 1] = lin(rgb[1]);
    arr[3 * i + 2] = lin(rgb[2]);
  }
  var GREY = [150, 150, 150];
  var DARK = [90, 90, 90];
  // A perceptual ramp from good (blue) to bad (red), for heat maps.
  var RAMP = [[49, 54, 149], [69, 117, 180], [116, 173, 209], [171, 217, 233], [254, 224, 144],
              [253, 174, 97], [244, 109, 67], [215, 48, 39], [165, 0, 38]];
  function ramp(t) {
    t = Math.max(0, Math.min(1, t)) * (RAMP.length - 1);
    var i = Math.min(RAMP.length - 2, Math.floor(t));
    var f = t - i;
    var a = RAMP[i], b = RAMP[i + 1];
    return [a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1]), a[2] + f * (b[2] - a[2])];
  }

  // ---- a body's frame: up from feet to head, left from right to left limbs ----------------
  function centroid(pos, pick) {
    var c = [0, 0, 0], n = 0;
    for (var v = 0; v < pos.length / 3; v++) {
      if (pick && !pick(v)) continue;
      c[0] += pos[3 * v]; c[1] += pos[3 * v + 1]; c[2] += pos[3 * v + 2]; n++;
    }
    return n ? [c[0] / n, c[1] / n, c[2] / n] : null;
  }
  function sub(a, b) { return [a[0] - b[0], a[1] - b[1], a[2] - b[2]]; }
  function dot(a, b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
  function cross(a, b) { return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]; }
  function norm(a) { var l = Math.hypot(a[0], a[1], a[2]) || 1; return [a[0] / l, a[1] / l, a[2] / l]; }

  // Matrix4 taking mesh coordinates to the view's: centre at the origin, up +Y, the body's
  // left +X, its front +Z. Without segments: `fallback` axes.
  function bodyMatrix(pos, seg, fallback) {
    var c = centroid(pos);
    var up = null, left = null;
    if (seg) {
      var inSet = function (set) { return function (v) { return set.indexOf(seg[v]) >= 0; }; };
      var head = centroid(pos, inSet([2]));
      var feet = centroid(pos, inSet([13, 14, 15, 16]));
      var l = centroid(pos, inSet(LEFT)), r = centroid(pos, inSet(RIGHT));
      if (head && feet) up = norm(sub(head, feet));
      if (up && l && r) {
        var d = sub(l, r);
        d = sub(d, up.map(function (x) { return x * dot(d, up); }));
        if (Math.hypot(d[0], d[1], d[2]) > 1e-9) left = norm(d);
      }
    }
    if (!up || !left) {
      up = fallback.up; left = fallback.left;
    }
    var front = cross(left, up);
    // Rotate, then put the centre of the rotated bounding box at the origin.
    var axes = [left, up, front], lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
    for (var v = 0; v < pos.length / 3; v++) {
      var p = [pos[3 * v], pos[3 * v + 1], pos[3 * v + 2]];
      for (var k = 0; k < 3; k++) {
        var x = dot(axes[k], p);
        if (x < lo[k]) lo[k] = x;
        if (x > hi[k]) hi[k] = x;
      }
    }
    var t = [0, 1, 2].map(function (k) { return isFinite(lo[k]) ? -(lo[k] + hi[k]) / 2 : -dot(axes[k], c || [0, 0, 0]); });
    var m = new THREE.Matrix4();
    m.set(left[0], left[1], left[2], t[0],
          up[0], up[1], up[2], t[1],
          front[0], front[1], front[2], t[2],
          0, 0, 0, 1);
    return m;
  }
  var DEFAULT_AXES = { up: [0, 1, 0], left: [1, 0, 0] };
  // Camera space of a depth camera (+Y up, +Z away): a body facing the camera has its left at −X.
  var CAMERA_AXES = { up: [0, 1, 0], left: [-1, 0, 0] };

  // A smooth colour field over a body: its coordinates in the view's frame, normalised.
  function fieldColours(pos, matrix) {
    var n = pos.length / 3, out = new Array(n);
    var v3 = new THREE.Vector3();
    var lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity], p = new Float32Array(3 * n);
    for (var v = 0; v < n; v++) {
      v3.set(pos[3 * v], pos[3 * v + 1], pos[3 * v + 2]).applyMatrix4(matrix);
      p[3 * v] = v3.x; p[3 * v + 1] = v3.y; p[3 * v + 2] = v3.z;
      for (var k = 0; k < 3; k++) { lo[k] = Math.min(lo[k], p[3 * v + k]); hi[k] = Math.max(hi[k], p[3 * v + k]); }
    }
    for (v = 0; v < n; v++) {
      var c = [];
      for (k = 0; k < 3; k++) c.push(40 + 215 * (p[3 * v + k] - lo[k]) / ((hi[k] - lo[k]) || 1));
      out[v] = c;
    }
    return out;
  }

  // ---- scene ------------------------------------------------------------------------------
  var canvas = document.getElementById('canvas');
  var renderer;
  try {
    renderer = new THREE.WebGLRenderer({ canvas: canvas, antialias: true, preserveDrawingBuffer: true });
  } catch (e) {
    fail('WebGL is not available in this browser: ' + e.message);
    return;
  }
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  renderer.setClearColor(0xffffff, 1);
  renderer.autoClear = false;

  var camera = new THREE.PerspectiveCamera(30, 1, 0.01, 100);
  var orbit = { theta: 0, phi: 0.08, radius: 3, size: 1 };
  var views = []; // {name, scene, mesh, light, rect: {x, y, w, h} in CSS pixels}
  var dirty = true;
  function redraw() { dirty = true; }

  function makeView(name, positions, triangles, matrix) {
    var scene = new THREE.Scene();
    var geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position', new THREE.BufferAttribute(positions, 3));
    geometry.setAttribute('color', new THREE.BufferAttribute(new Float32Array(positions.length), 3));
    geometry.setIndex(new THREE.BufferAttribute(triangles, 1));
    geometry.computeVertexNormals();
    var material = new THREE.MeshLambertMaterial({ vertexColors: true, side: THREE.DoubleSide, transparent: false });
    var mesh = new THREE.Mesh(geometry, material);
    var group = new THREE.Group();
    group.matrixAutoUpdate = false;
    group.matrix.copy(matrix);
    group.add(mesh);
    scene.add(group);
    scene.add(new THREE.AmbientLight(0xffffff, 1.25));
    var light = new THREE.DirectionalLight(0xffffff, 1.9);
    scene.add(light);
    var view = { name: name, scene: scene, group: group, mesh: mesh, light: light, rect: null, markers: {} };
    views.push(view);
    return view;
  }

  function setColours(view, colourOf) {
    var attr = view.mesh.geometry.getAttribute('color');
    var n = attr.count;
    for (var v = 0; v < n; v++) setRGB(attr.array, v, colourOf(v));
    attr.needsUpdate = true;
    redraw();
  }

  function marker(view, key, colour, scale) {
    if (!view.markers[key]) {
      var m = new THREE.Mesh(new THREE.SphereGeometry(1, 20, 14),
        new THREE.MeshBasicMaterial({ color: colour, depthTest: false, depthWrite: false }));
      m.renderOrder = 10;
      m.visible = false;
      view.scene.add(m);
      view.markers[key] = m;
    }
    view.markers[key].scale.setScalar(orbit.size * (scale || 0.012));
    return view.markers[key];
  }
  function worldOf(view, v) {
    var p = view.mesh.geometry.getAttribute('position');
    view.group.updateMatrixWorld(true);
    return new THREE.Vector3(p.getX(v), p.getY(v), p.getZ(v)).applyMatrix4(view.group.matrixWorld);
  }
  function showMarker(view, key, colour, v) {
    var m = marker(view, key, colour);
    if (v === null || v === undefined || v < 0) { m.visible = false; return; }
    m.position.copy(worldOf(view, v));
    m.visible = true;
  }

  function layout() {
    var w = window.innerWidth, h = window.innerHeight;
    renderer.setSize(w, h);
    // The views leave the timeline's strip free at the bottom.
    var timeline = document.getElementById('timeline');
    var vh = timeline.style.display === 'block' ? Math.max(100, h - timeline.offsetHeight - 16) : h;
    var each = w / views.length;
    views.forEach(function (view, i) { view.rect = { x: i * each, y: 0, w: each, h: vh }; });
    var aspect = each / vh;
    camera.aspect = aspect;
    camera.updateProjectionMatrix();
    // Fit the bodies: the radius that shows a sphere of radius size/2 in the narrower field.
    var half = THREE.MathUtils.degToRad(camera.fov / 2);
    var hHalf = Math.atan(Math.tan(half) * aspect);
    orbit.radius = orbit.fit = 0.66 * orbit.size / Math.sin(Math.min(half, hHalf));
    state.views = views.map(function (v) { return { name: v.name, rect: v.rect }; });
    placeCaptions();
    redraw();
  }

  function placeCamera() {
    var r = orbit.radius, t = orbit.theta, p = orbit.phi;
    camera.position.set(r * Math.sin(t) * Math.cos(p), r * Math.sin(p), r * Math.cos(t) * Math.cos(p));
    camera.up.set(0, 1, 0);
    camera.lookAt(0, 0, 0);
    camera.updateMatrixWorld(true);
  }

  function render() {
    placeCamera();
    renderer.setScissorTest(false);
    renderer.clear();
    renderer.setScissorTest(true);
    var h = window.innerHeight;
    views.forEach(function (view) {
      var r = view.rect;
      // WebGL's viewport origin is the bottom left.
      renderer.setViewport(r.x, h - r.y - r.h, r.w, r.h);
      renderer.setScissor(r.x, h - r.y - r.h, r.w, r.h);
      view.light.position.copy(camera.position).add(new THREE.Vector3(0.3, 0.6, 0).multiplyScalar(orbit.radius));
      renderer.render(view.scene, camera);
    });
  }

  function loop() {
    if (state.playing) stepPlayback();
    if (pendingHover) {
      var e = pendingHover;
      pendingHover = null;
      pickFromEvent(e, false);
    }
    if (dirty) {
      dirty = false;
      render();
      if (!state.ready) {
        state.ready = true;
        state.loadMs = performance.now();
      }
    }
    requestAnimationFrame(loop);
  }

  // Screen position (CSS pixels) of vertex v of a view, and whether it is the surface nearest
  // the camera there (not hidden behind another part of the body).
  function project(name, v) {
    var view = views.filter(function (x) { return x.name === name; })[0];
    if (!view) return null;
    placeCamera();
    var w = worldOf(view, v);
    var ndc = w.clone().project(camera);
    var r = view.rect;
    var out = { x: r.x + (ndc.x + 1) / 2 * r.w, y: r.y + (1 - ndc.y) / 2 * r.h, visible: false };
    var hit = pickAt(view, out.x, out.y);
    out.visible = hit !== null && worldOf(view, hit).distanceTo(w) < 0.005 * orbit.size;
    out.inside = out.x >= r.x && out.x < r.x + r.w && out.y >= r.y && out.y < r.y + r.h;
    return out;
  }

  var raycaster = new THREE.Raycaster();
  // The vertex of `view` under CSS position (x, y): the nearest corner of the triangle hit.
  function pickAt(view, x, y) {
    var r = view.rect;
    var ndc = new THREE.Vector2((x - r.x) / r.w * 2 - 1, -((y - r.y) / r.h) * 2 + 1);
    placeCamera();
    view.group.updateMatrixWorld(true);
    raycaster.setFromCamera(ndc, camera);
    var hits = raycaster.intersectObject(view.mesh, false);
    if (!hits.length) return null;
    var f = hits[0].face, best = null, bestD = Infinity;
    [f.a, f.b, f.c].forEach(function (v) {
      var d = worldOf(view, v).distanceTo(hits[0].point);
      if (d < bestD) { bestD = d; best = v; }
    });
    return best;
  }
  function viewAt(x, y) {
    return views.filter(function (view) {
      var r = view.rect;
      return x >= r.x && x < r.x + r.w && y >= r.y && y < r.y + r.h;
    })[0] || null;
  }

  // ---- mouse: drag to turn, wheel to zoom, click (or hover) to pick -------------------------
  var drag = null, onPick = null, hover = true, pendingHover = null;
  canvas.addEventListener('pointerdown', function (e) {
    drag = { x: e.clientX, y: e.clientY, moved: 0 };
    canvas.setPointerCapture(e.pointerId);
  });
  canvas.addEventListener('pointermove', function (e) {
    if (drag) {
      var dx = e.clientX - drag.x, dy = e.clientY - drag.y;
      drag.moved += Math.abs(dx) + Math.abs(dy);
      drag.x = e.clientX; drag.y = e.clientY;
      if (drag.moved > 4) {
        orbit.theta -= dx * 0.01;
        orbit.phi = Math.max(-1.5, Math.min(1.5, orbit.phi + dy * 0.01));
        redraw();
      }
    } else if (hover && onPick) {
      pendingHover = { clientX: e.clientX, clientY: e.clientY }; // picked once per frame
    }
  });
  canvas.addEventListener('pointerup', function (e) {
    if (drag && drag.moved <= 4 && onPick) {
      pendingHover = null;
      pickFromEvent(e, true);
    }
    drag = null;
  });
  canvas.addEventListener('wheel', function (e) {
    e.preventDefault();
    orbit.radius = Math.max(0.1 * orbit.fit, Math.min(10 * orbit.fit, orbit.radius * Math.exp(e.deltaY * 0.001)));
    redraw();
  }, { passive: false });
  function pickFromEvent(e, clicked) {
    var view = viewAt(e.clientX, e.clientY);
    if (!view) return;
    var v = pickAt(view, e.clientX, e.clientY);
    if (v !== null) onPick(view, v, clicked);
  }
  window.addEventListener('resize', layout);

  // ---- panels -----------------------------------------------------------------------------
  var controls = document.getElementById('controls');
  var info = document.getElementById('info');
  var legend = document.getElementById('legend');
  function setInfo(text) { info.textContent = text; }
  function radio(name, label, checked, onChange) {
    var l = document.createElement('label');
    var input = document.createElement('input');
    input.type = 'radio'; input.name = 'mode'; input.value = name; input.checked = checked;
    input.addEventListener('change', function () { if (input.checked) onChange(name); });
    l.appendChild(input);
    l.appendChild(document.createTextNode(' ' + label));
    controls.appendChild(l);
    return input;
  }
  function checkbox(label, checked, onChange) {
    var l = document.createElement('label');
    var input = document.createElement('input');
    input.type = 'checkbox'; input.checked = checked;
    input.addEventListener('change', function () { onChange(input.checked); });
    l.appendChild(input);
    l.appendChild(document.createTextNode(' ' + label));
    controls.appendChild(l);
    return input;
  }
  function segmentLegend() {
    legend.innerHTML = '';
    SEGMENTS.forEach(function (s) {
      var d = document.createElement('div');
      var sw = document.createElement('span');
      sw.className = 'swatch';
      sw.style.background = 'rgb(' + s.colour.join(',') + ')';
      d.appendChild(sw);
      d.appendChild(document.createTextNode(s.name));
      legend.appendChild(d);
    });
    legend.style.display = 'block';
    legend.style.columnCount = 2;
  }
  function heatLegend(title, low, high) {
    legend.innerHTML = '';
    var t = document.createElement('div');
    t.textContent = title;
    legend.appendChild(t);
    var bar = document.createElement('div');
    bar.style.height = '12px';
    bar.style.width = '200px';
    bar.style.background = 'linear-gradient(to right, ' + RAMP.map(function (c) { return 'rgb(' + c.join(',') + ')'; }).join(', ') + ')';
    legend.appendChild(bar);
    var ends = document.createElement('div');
    ends.style.display = 'flex';
    ends.style.justifyContent = 'space-between';
    ends.innerHTML = '<span></span><span></span>';
    ends.children[0].textContent = low;
    ends.children[1].textContent = high;
    legend.appendChild(ends);
    var g = document.createElement('div');
    g.textContent = 'grey: no match';
    legend.appendChild(g);
    legend.style.display = 'block';
    legend.style.columnCount = 1;
  }
  var captions = [];
  function baseName(p) { return String(p).split(/[\\/]/).pop(); }
  function caption(text, full) {
    var c = document.createElement('div');
    c.className = 'caption';
    c.textContent = text;
    if (full) c.title = full;
    document.body.appendChild(c);
    captions.push(c);
  }
  function placeCaptions() {
    captions.forEach(function (c, i) {
      var r = views[i] && views[i].rect;
      if (r) { c.style.left = (r.x + 12) + 'px'; c.style.top = (r.y + 44) + 'px'; }
    });
  }
  function segName(s) { return s === NO_SEGMENT || s === undefined ? 'no segment' : SEGMENTS[s].name; }
  function fmt(x, digits) { return x === null || x === undefined || isNaN(x) ? '–' : Number(x).toFixed(digits); }

  // ---- pair view --------------------------------------------------------------------------
  function pairView() {
    var M = data.meshes;
    var tPos = decode(M.template.positions, Float32Array), gPos = decode(M.target.positions, Float32Array);
    var tSeg = decode(M.template.segments, Uint8Array), gSeg = decode(M.target.segments, Uint8Array);
    var tNear = decode(M.template.nearestPair, Int32Array), gNear = decode(M.target.nearestPair, Int32Array);
    var P = data.pairs;
    var pT = decode(P.template, Uint32Array), pG = decode(P.target, Uint32Array), pC = decode(P.confidence, Float32Array);
    var truth = data.truth, trueT = null, err = null;
    if (truth) { trueT = decode(truth.target, Int32Array); err = decode(truth.error, Float32Array); }
    var missing = decode(data.noCounterpart, Uint32Array);
    var blocked = new Uint8Array(tPos.length / 3);
    for (var i = 0; i < missing.length; i++) blocked[missing[i]] = 1;
    // The pair of each matched template vertex (the first, if several).
    var own = new Int32Array(tPos.length / 3).fill(-1);
    for (i = 0; i < pT.length; i++) if (own[pT[i]] < 0) own[pT[i]] = i;

    var tMatrix = bodyMatrix(tPos, tSeg, DEFAULT_AXES), gMatrix = bodyMatrix(gPos, gSeg, DEFAULT_AXES);
    var tv = makeView('template', tPos, decode(M.template.triangles, Uint32Array), tMatrix);
    var gv = makeView('target', gPos, decode(M.target.triangles, Uint32Array), gMatrix);
    setSize([tv, gv]);
    var field = fieldColours(tPos, tMatrix);
    caption('template: ' + baseName(M.template.path) + ' (' + M.template.vertices + ' vertices)', M.template.path);
    caption('target: ' + baseName(M.target.path) + ' (' + M.target.vertices + ' vertices)', M.target.path);

    var modes = {
      transfer: function () {
        setColours(tv, function (v) { return blocked[v] || tNear[v] < 0 ? GREY : field[v]; });
        setColours(gv, function (q) { return gNear[q] < 0 ? GREY : field[pT[gNear[q]]]; });
        legend.style.display = 'none';
      },
      segments: function () {
        setColours(tv, function (v) { return tSeg[v] === NO_SEGMENT ? DARK : SEGMENTS[tSeg[v]].colour; });
        setColours(gv, function (q) { return gSeg[q] === NO_SEGMENT ? DARK : SEGMENTS[gSeg[q]].colour; });
        segmentLegend();
      },
      confidence: function () {
        var c = function (k) { return k < 0 ? GREY : ramp(1 - pC[k]); };
        setColours(tv, function (v) { return blocked[v] ? GREY : c(tNear[v]); });
        setColours(gv, function (q) { return c(gNear[q]); });
        heatLegend('confidence of the nearest match', 'high', 'low');
      },
    };
    state.modes = ['transfer', 'segments', 'confidence'];
    if (err) {
      // The ramp spans 0 to the errors' 95th percentile, rounded up to 1, 2 or 5 × 10^k.
      var sorted = Array.prototype.filter.call(err, function (e) { return !isNaN(e); }).sort(function (a, b) { return a - b; });
      var p95 = sorted.length ? sorted[Math.min(sorted.length - 1, Math.floor(0.95 * sorted.length))] : 0;
      var top = Math.max(p95, 1e-4), mag = Math.pow(10, Math.floor(Math.log10(top)));
      var scale = [1, 2, 5, 10].map(function (f) { return f * mag; }).filter(function (x) { return x >= top; })[0];
      state.errorScale = scale;
      modes.error = function () {
        var c = function (k) { return k < 0 || isNaN(err[k]) ? GREY : ramp(err[k] / scale); };
        setColours(tv, function (v) { return blocked[v] ? GREY : c(tNear[v]); });
        setColours(gv, function (q) { return c(gNear[q]); });
        heatLegend('geodesic error / √area', '0', '≥ ' + scale);
      };
      state.modes.push('error');
    }
    var labels = { transfer: 'colour transfer', segments: '17 segments', confidence: 'confidence', error: 'error' };
    var inputs = {};
    state.setMode = function (m) {
      if (!modes[m]) throw new Error('no colour mode ' + m);
      state.mode = m;
      inputs[m].checked = true;
      modes[m]();
    };
    state.modes.forEach(function (m) { inputs[m] = radio(m, labels[m], m === 'transfer', state.setMode); });
    checkbox('pick on hover', true, function (on) { hover = on; });

    var summary = pT.length + ' matches of ' + M.template.vertices + ' template vertices' +
      (missing.length ? '; ' + missing.length + ' template points the target does not show (grey)' : '');
    if (err) {
      var sum = 0, n = 0;
      for (i = 0; i < err.length; i++) if (!isNaN(err[i])) { sum += err[i]; n++; }
      summary += '\nmean geodesic error ' + fmt(n ? sum / n : NaN, 4) + ' (' + truth.unit + ', ' + n + ' scored)';
    }
    setInfo(summary + '\nclick or hover a template point to see its match');

    onPick = function (view, v, clicked) {
      if (view !== tv) return;
      var k = blocked[v] ? -1 : (own[v] >= 0 ? own[v] : tNear[v]);
      var sel = { template: v, clicked: clicked, pair: k, matchedTemplate: null, target: null, confidence: null,
                  truth: null, error: null, noCounterpart: !!blocked[v], segment: segName(tSeg[v]) };
      if (k >= 0) {
        sel.matchedTemplate = pT[k];
        sel.target = pG[k];
        sel.confidence = pC[k];
        sel.targetSegment = segName(gSeg[pG[k]]);
        if (trueT) {
          sel.truth = trueT[k] >= 0 ? trueT[k] : null;
          sel.error = isNaN(err[k]) ? null : err[k];
        }
      }
      state.selected = sel;
      showMarker(tv, 'point', 0xff2020, k >= 0 ? pT[k] : v);
      showMarker(gv, 'match', 0x00ff00, sel.target);
      showMarker(gv, 'truth', 0x0040ff, sel.truth);
      var text;
      if (sel.noCounterpart) text = 'template ' + v + ' (' + sel.segment + '): the target does not show this point';
      else if (k < 0) text = 'template ' + v + ' (' + sel.segment + '): no match';
      else {
        text = 'template ' + pT[k] + ' (' + segName(tSeg[pT[k]]) + ')' + (pT[k] !== v ? ', the matched point nearest ' + v : '') +
          '\n→ target ' + sel.target + ' (' + sel.targetSegment + '), confidence ' + fmt(sel.confidence, 3) + ' (green)';
        if (trueT) {
          text += sel.truth === null ? '\nno true point in the dataset'
            : '\ntrue point: target ' + sel.truth + ' (blue), geodesic error ' + fmt(sel.error, 4) + ' (' + truth.unit + ')';
        }
      }
      setInfo(text);
      redraw();
    };
    state.setMode('transfer');
  }

  // Orbit size: the largest extent of the views' bodies.
  function setSize(vs) {
    var size = 0;
    vs.forEach(function (view) {
      view.group.updateMatrixWorld(true);
      var box = new THREE.Box3().setFromObject(view.group);
      var s = box.getSize(new THREE.Vector3());
      size = Math.max(size, s.x, s.y, s.z);
    });
    orbit.size = size || 1;
  }

  // ---- labels view ------------------------------------------------------------------------
  function labelsView() {
    var M = data.meshes.mesh;
    var pos = decode(M.positions, Float32Array), seg = decode(M.segments, Uint8Array);
    var matrix = bodyMatrix(pos, seg, DEFAULT_AXES);
    var view = makeView('mesh', pos, decode(M.triangles, Uint32Array), matrix);
    setSize([view]);
    caption(baseName(M.path) + ' (' + M.vertices + ' vertices)', M.path);
    setColours(view, function (v) { return seg[v] === NO_SEGMENT ? DARK : SEGMENTS[seg[v]].colour; });
    segmentLegend();
    state.mode = 'segments';
    state.modes = ['segments'];
    // The skeleton: joints as balls, bones as rods, drawn over the surface.
    var skeleton = new THREE.Group();
    var jointMat = new THREE.MeshBasicMaterial({ color: 0x111111, depthTest: false, depthWrite: false });
    var boneMat = new THREE.MeshBasicMaterial({ color: 0x333333, depthTest: false, depthWrite: false, transparent: true, opacity: 0.8 });
    var r = 0.012 * orbit.size;
    var J = {};
    Object.keys(data.joints).forEach(function (name) {
      var p = data.joints[name];
      J[name] = new THREE.Vector3(p[0], p[1], p[2]).applyMatrix4(matrix);
      var ball = new THREE.Mesh(new THREE.SphereGeometry(r, 16, 12), jointMat);
      ball.position.copy(J[name]);
      ball.renderOrder = 11;
      skeleton.add(ball);
    });
    data.bones.forEach(function (b) {
      var a = J[b[0]], c = J[b[1]];
      var len = a.distanceTo(c);
      if (len <= 0) return;
      var rod = new THREE.Mesh(new THREE.CylinderGeometry(r * 0.4, r * 0.4, len, 10), boneMat);
      rod.position.copy(a).add(c).multiplyScalar(0.5);
      rod.quaternion.setFromUnitVectors(new THREE.Vector3(0, 1, 0), c.clone().sub(a).normalize());
      rod.renderOrder = 10;
      skeleton.add(rod);
    });
    view.scene.add(skeleton);
    state.joints = Object.keys(data.joints).length;
    state.bones = data.bones.length;
    checkbox('skeleton', true, function (on) { skeleton.visible = on; redraw(); });
    checkbox('x-ray', false, function (on) {
      view.mesh.material.transparent = on;
      view.mesh.material.opacity = on ? 0.35 : 1;
      view.mesh.material.depthWrite = !on;
      view.mesh.material.needsUpdate = true;
      redraw();
    });
    var counts = new Array(SEGMENTS.length).fill(0), none = 0;
    for (var v = 0; v < seg.length; v++) { if (seg[v] === NO_SEGMENT) none++; else counts[seg[v]]++; }
    setInfo(M.vertices + ' vertices in ' + counts.filter(function (c) { return c > 0; }).length + ' segments' +
      (none ? ', ' + none + ' without a segment (dark grey)' : '') + '; ' + state.joints + ' joints, ' + state.bones + ' bones' +
      '\nclick a point to name its segment');
    onPick = function (vw, v, clicked) {
      state.selected = { vertex: v, clicked: clicked, segment: segName(seg[v]) };
      showMarker(view, 'point', 0xff2020, v);
      setInfo('vertex ' + v + ': ' + segName(seg[v]));
      redraw();
    };
  }

  // ---- track view -------------------------------------------------------------------------
  function trackView() {
    var T = data.track;
    var n = T.vertices, frames = T.frames, poses = T.poses;
    var q = decode(poses.data, Uint16Array);
    var lo = poses.min, hi = poses.max;
    var pos = new Float32Array(3 * n);
    function loadPose(i) {
      var base = i * 3 * n;
      for (var j = 0; j < 3 * n; j++) {
        var k = j % 3;
        pos[j] = lo[k] + q[base + j] / 65535 * (hi[k] - lo[k]);
      }
    }
    var first = frames.findIndex(function (f) { return f.pose !== null; });
    if (first >= 0) loadPose(frames[first].pose);
    var firstPose = pos.slice();
    var matrix = bodyMatrix(firstPose, null, CAMERA_AXES);
    var view = makeView('mesh', pos, decode(T.triangles, Uint32Array), matrix);
    setSize([view]);
    var field = fieldColours(firstPose, matrix);
    setColours(view, function (v) { return field[v]; });
    state.mode = 'colour field';
    state.modes = ['colour field'];
    caption(baseName(data.title) + ': the template following the recording (' + n + ' vertices)', data.title);

    document.getElementById('timeline').style.display = 'block';
    info.style.bottom = 'auto';
    info.style.top = '8px';
    info.style.left = 'auto';
    info.style.right = '8px';
    var scrub = document.getElementById('scrub');
    scrub.max = String(Math.max(0, frames.length - 1));
    var strip = document.getElementById('strip');
    // Strip colours: skipped grey, a left/right swap fixed orange, another notable correction
    // (a poor fit accepted, joints borrowed from the previous frame) yellow, else green
    // (reading joints between two log frames is routine).
    function frameColour(f) {
      var c = f.corrections || [];
      if (f.status !== 'ok') return '#bbbbbb';
      if (c.some(function (x) { return /swap_fixed$/.test(x); })) return '#ff9800';
      if (c.some(function (x) { return x !== 'joints_interpolated'; })) return '#fdd835';
      return '#43a047';
    }
    frames.forEach(function (f, i) {
      var d = document.createElement('div');
      d.style.background = frameColour(f);
      d.title = 'frame ' + f.frame + ': ' + f.status + (f.corrections && f.corrections.length ? ' (' + f.corrections.join(', ') + ')' : '');
      d.addEventListener('click', function () { state.setFrame(i); });
      strip.appendChild(d);
    });
    var s = T.summary || {};
    var counts = {};
    frames.forEach(function (f) {
      (f.corrections || []).forEach(function (c) { counts[c] = (counts[c] || 0) + 1; });
    });
    var skipped = frames.filter(function (f) { return f.status !== 'ok'; }).length;
    var fixes = Object.keys(counts).map(function (c) { return c + ' ×' + counts[c]; }).join(', ');
    setInfo(frames.length + ' frames: ' + (frames.length - skipped) + ' ok, ' + skipped + ' skipped' +
      (fixes ? '\ncorrections: ' + fixes : '') + (s.mean_coverage !== undefined ? '\nmean coverage ' + fmt(s.mean_coverage, 3) : '') +
      '\n' + poses.count + ' poses embedded' +
      '\nstrip: green ok · orange left/right swap fixed\nyellow poor fit accepted or joints borrowed · grey skipped');
    var label = document.getElementById('frame-label');
    var status = document.getElementById('frame-status');
    state.frames = frames.length;
    state.setFrame = function (i) {
      i = Math.max(0, Math.min(frames.length - 1, i | 0));
      var f = frames[i];
      state.frame = i;
      scrub.value = String(i);
      label.textContent = 'frame ' + f.frame + ' (' + (i + 1) + ' of ' + frames.length + '), ' + fmt(f.time_s, 3) + ' s';
      status.textContent = f.status + (f.corrections && f.corrections.length ? ' · fixed: ' + f.corrections.join(', ') : '') +
        (f.coverage !== null && f.coverage !== undefined ? ' · coverage ' + fmt(f.coverage, 3) : '') +
        (f.mean_confidence !== null && f.mean_confidence !== undefined ? ' · mean confidence ' + fmt(f.mean_confidence, 3) : '') +
        (f.pose === null ? ' · no pose' : '');
      // A frame without a pose shows the nearest one before it (else after it), faded.
      var shown = i, j;
      if (f.pose === null) {
        shown = -1;
        for (j = i - 1; j >= 0 && shown < 0; j--) if (frames[j].pose !== null) shown = j;
        for (j = i + 1; j < frames.length && shown < 0; j++) if (frames[j].pose !== null) shown = j;
        if (shown >= 0) status.textContent += ': showing frame ' + frames[shown].frame + ', faded';
      }
      var m = view.mesh.material;
      m.transparent = shown !== i;
      m.opacity = shown !== i ? 0.25 : 1;
      m.depthWrite = shown === i;
      m.needsUpdate = true;
      view.mesh.visible = shown >= 0;
      state.shownFrame = shown;
      if (shown >= 0) {
        loadPose(frames[shown].pose);
        var g = view.mesh.geometry;
        g.getAttribute('position').needsUpdate = true;
        g.computeVertexNormals();
        g.computeBoundingSphere();
      }
      redraw();
    };
    var play = document.getElementById('play');
    var clock = null;
    state.play = function () {
      if (state.frame >= frames.length - 1) state.setFrame(0);
      state.playing = true;
      clock = { t0: performance.now(), frame0: state.frame };
      play.textContent = 'pause';
    };
    state.pause = function () { state.playing = false; play.textContent = 'play'; };
    stepPlayback = function () {
      var start = frames[clock.frame0].time_s || 0;
      var t = start + (performance.now() - clock.t0) / 1000;
      var i = state.frame;
      while (i + 1 < frames.length && (frames[i + 1].time_s || 0) <= t) i++;
      if (i !== state.frame) state.setFrame(i);
      if (i >= frames.length - 1) state.pause();
    };
    play.addEventListener('click', function () { if (state.playing) state.pause(); else state.play(); });
    scrub.addEventListener('input', function () { state.pause(); state.setFrame(Number(scrub.value)); });
    onPick = function (vw, v, clicked) {
      state.selected = { vertex: v, clicked: clicked };
      showMarker(view, 'point', 0xff2020, v);
      redraw();
    };
    state.setFrame(first >= 0 ? first : 0);
  }
  var stepPlayback = function () {};

  // ---- start ------------------------------------------------------------------------------
  try {
    if (data.kind === 'pair') pairView();
    else if (data.kind === 'labels') labelsView();
    else if (data.kind === 'track') trackView();
    else throw new Error('unknown page kind ' + data.kind);
    document.title = data.title + ' — symcorr view';
    state.project = project;
    // Turns the camera about the bodies (radians: around the vertical axis, then up).
    state.setCamera = function (theta, phi) {
      orbit.theta = theta;
      orbit.phi = Math.max(-1.5, Math.min(1.5, phi));
      redraw();
    };
    state.pick = function (name, x, y) {
      var view = views.filter(function (w) { return w.name === name; })[0];
      return view ? pickAt(view, x, y) : null;
    };
    if (!controls.children.length) controls.style.display = 'none';
    layout();
    requestAnimationFrame(loop);
  } catch (e) {
    fail(e.message);
  }
})();
