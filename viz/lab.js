/* lab.js — the sidx lab page (viz/lab.html): the library in WebAssembly
 * (viz/lab.h, the sidx_lab_* calls) behind a stepper, a structure picker,
 * the build knobs, a second structure on the same ray, a heat map and an
 * OBJ loader.  Every count, tree and trace shown comes from the module;
 * this file only draws them and keeps the page's state.
 *
 * What a program driving the page may rely on (kept stable):
 *   #scene       select: the scene (built-in name, or the OBJ loaded last)
 *   #accel       select: the structure
 *   #accel2      select: a second structure on the same ray, "" for none
 *   #knob-bins #knob-c_trav #knob-c_tri #knob-leaf_size #knob-max_depth
 *   #knob-lambda #knob-empty_bonus #knob-optimize   number inputs, empty =
 *                the structure's default; a 'change' event rebuilds
 *   #knob-mailbox  checkbox, checked = mailboxing on
 *   #view        the canvas: in 2D a drag from A to B sets the ray from A
 *                towards B (in the scene's middle z plane); in 3D a drag
 *                orbits and a click shoots the ray through that pixel
 *   #heatmap     button: toggles the heat map
 *   #obj-file    input type=file: loads an OBJ (also: drop a file on #view)
 *   #error       the last error message (hidden when there is none)
 *   #stats       the structures' counts
 *   window.sidxLab.ready     a Promise, resolved once the module is loaded
 *                            and the first view is drawn
 *   window.sidxLab.state()   {scene, accel, accel2, knobs, ray: [ox, oy, oz,
 *                            dx, dy, dz], step, events, stats, error, ...}:
 *                            events are the trace's event objects exactly as
 *                            sidx_event_to_json writes them; stats the
 *                            module's build statistics and trace counters
 *   window.sidxLab.timings() {rebuild, trace, heat}: the last ones in ms,
 *                            measured with performance.now() (a trace's
 *                            time includes drawing it)
 * The address (#scene=...&accel=...&ray=...&step=...) keeps the state; a
 * link opens the same view. */
'use strict';
(function () {

/* ---- small helpers ------------------------------------------------------------------ */
function $(id) { return document.getElementById(id); }
function num(x) {            /* the JSON floats: "inf", "-inf", "nan" are strings */
  if (typeof x === 'number') return x;
  if (x === 'inf') return Infinity;
  if (x === '-inf') return -Infinity;
  if (x === null || x === undefined) return NaN;
  return parseFloat(x);
}
function g(x) {              /* printf's %.3g, as the viewer and sidx-step print */
  if (typeof x !== 'number' || !isFinite(x)) return x === Infinity ? 'inf' : x === -Infinity ? '-inf' : 'nan';
  if (x === 0) return 1 / x < 0 ? '-0' : '0';
  var e = x.toExponential(2), p = e.indexOf('e'), x10 = parseInt(e.slice(p + 1), 10);
  function trim(m) { return m.indexOf('.') >= 0 ? m.replace(/0+$/, '').replace(/\.$/, '') : m; }
  if (x10 < -4 || x10 >= 3)
    return trim(e.slice(0, p)) + 'e' + (x10 < 0 ? '-' : '+') + (Math.abs(x10) < 10 ? '0' : '') + Math.abs(x10);
  return trim(x.toFixed(2 - x10));
}
function esc(s) { return String(s).replace(/&/g, '&amp;').replace(/</g, '&lt;'); }
function boxOf(b) {          /* {min:[..], max:[..]} from [6] or {min, max} */
  if (!b) return null;
  if (Array.isArray(b)) return { min: [num(b[0]), num(b[1]), num(b[2])], max: [num(b[3]), num(b[4]), num(b[5])] };
  return { min: b.min.map(num), max: b.max.map(num) };
}
function boxEmpty(b) { return !b || !(b.min[0] <= b.max[0] && b.min[1] <= b.max[1] && b.min[2] <= b.max[2]); }
function now() { return performance.now(); }

/* ---- the module --------------------------------------------------------------------- */
/* L wraps the sidx_lab_* calls of viz/lab.h (each answer is JSON text) in
 * the few calls the page makes; M is the emscripten module. */
var L = null;
/* An OBJ larger than this is not read into the page's memory at all (the
 * module refuses scenes over its triangle limit with its own message). */
var MAX_FILE_BYTES = 32 * 1024 * 1024;

function makeLab(M) {
  var dec = typeof TextDecoder !== 'undefined' ? new TextDecoder('utf-8') : null;
  function heap() { return M.HEAPU8; }
  function str(p) {            /* a C string of the module's memory */
    if (!p) return '';
    if (M.UTF8ToString) return M.UTF8ToString(p);
    var h = heap(), e = p;
    while (h[e]) ++e;
    return dec.decode(h.subarray(p, e));
  }
  function json(p) { var s = str(p); return s ? JSON.parse(s) : null; }
  function withBytes(bytes, fn) {   /* bytes copied into the module for one call */
    var p = M._malloc(bytes.length + 1);
    if (!p) throw new Error('out of memory in the WebAssembly module');
    try { heap().set(bytes, p); heap()[p + bytes.length] = 0; return fn(p); } finally { M._free(p); }
  }
  function cstr(s, fn) { return withBytes(new TextEncoder().encode(s), fn); }
  function err() { return str(M._sidx_lab_error()); }
  var scenes = json(M._sidx_lab_scenes());
  return {
    scenes: function () { return scenes.scenes.map(function (x) { return x.name; }); },
    limits: function () { return { triangles: scenes.limit, obj_bytes: MAX_FILE_BYTES }; },
    openScene: function (name) {
      var rc = cstr(name, function (p) { return M._sidx_lab_open_scene(p); });
      return { ok: rc === 0, error: rc === 0 ? '' : err() };
    },
    openObj: function (fileName, bytes) {
      var rc = withBytes(bytes, function (p) {
        return cstr(fileName, function (q) { return M._sidx_lab_open_obj(p, bytes.length, q); });
      });
      return { ok: rc === 0, error: rc === 0 ? '' : err() };
    },
    mesh: function () {
      var j = json(M._sidx_lab_scene_json());
      return { ntris: j.triangles, pos: j.pos, idx: j.idx, bounds: boxOf(j.bounds), flat: j.dims === 2, dims: j.dims };
    },
    accels: function () { return json(M._sidx_lab_structures()).structures; },
    build: function (slot, accel, knobs) {
      var t0 = now();
      var k = {};
      for (var n in knobs) {
        if (n === 'mailbox') { if (!knobs.mailbox) k.mailbox = false; }
        else if (n === 'optimize') { if (knobs.optimize > 0) k.optimize = knobs.optimize; }
        else k[n] = knobs[n];
      }
      var rc = cstr(accel, function (p) {
        return cstr(JSON.stringify(k), function (q) { return M._sidx_lab_build(slot, p, q); });
      });
      if (rc !== 0) return { ok: false, error: err() };
      var t1 = now(), bj = M._sidx_lab_build_json(slot), t2 = now(), b = json(bj);
      T.parts = { build: t1 - t0, build_json: t2 - t1, build_parse: now() - t2 };
      return { ok: true, stats: b.stats, args: b.args, build: b.build, labels: b.labels || {},
               cand_total: b.cand_total, cand_kept: b.cand_kept };
    },
    trace: function (slot, ray) {
      var t0 = now(), rc = M._sidx_lab_trace(slot, ray[0], ray[1], ray[2], ray[3], ray[4], ray[5]);
      if (rc !== 0) return { ok: false, error: err(), events: [] };
      var t1 = now(), t = json(M._sidx_lab_trace_json(slot));
      T.tparts = { trace: t1 - t0, trace_json: now() - t1 };
      return { ok: true, events: t.events, counts: t.counts, hit: t.hit, ray_arg: t.ray_arg, truncated: t.truncated };
    },
    diverge: function () { return json(M._sidx_lab_diverge_json()); },
    heat: function (slot, yaw, pitch, zoom, w, h, what) {
      var rc = M._sidx_lab_heatmap(slot, yaw, pitch, zoom, w, h, what);
      if (rc !== 0) return { ok: false, error: err() };
      var info = json(M._sidx_lab_heatmap_json()), p = M._sidx_lab_heatmap_data();
      var counts = new Uint32Array(M.HEAPU8.buffer, p, w * h).slice();
      return { ok: true, counts: counts, max: info.max, total: info.total, ms: info.ms };
    },
    cameraRay: function (yaw, pitch, zoom, w, h, px, py) {
      var r = json(M._sidx_lab_camera_ray(yaw, pitch, zoom, w, h, px, py));
      return r ? r.o.concat(r.d) : null;
    }
  };
}

/* ---- the state ----------------------------------------------------------------------- */
var BTYPES = ['build_begin', 'build_node', 'build_candidate', 'build_split', 'build_leaf', 'build_end'];
var KNOBS = ['bins', 'c_trav', 'c_tri', 'leaf_size', 'max_depth', 'lambda', 'mailbox', 'empty_bonus', 'optimize'];
var S = {
  scene: '', accel: '', accel2: '', knobs: {}, ray: null, step: 0, mode: '2d', heatMetric: 'steps', heatSize: 256,
  yaw: 0.6, pitch: 0.35, zoom: 1, level: -1, playing: null, error: '', bstep: Infinity
};
var SC = null;               /* the open scene: {name, ntris, pos, idx, bounds, flat} */
var SLOT = [null, null];     /* per structure: {accel, stats, tree, nodeBox, nodeDepth, leaf, maxDepth, trace, error} */
var T = { rebuild: NaN, trace: NaN, heat: NaN, draw: NaN };
var HEATS = [null, null];    /* the heat maps per slot: {key, n, max, scaleMax, mean, canvas, ms} */
var BASE = [{ key: '', canvas: null }, { key: '', canvas: null }];  /* per viewport: the layer that changes
                                                                        only with the scene, tree or camera */
var ORBITING = false;        /* a 3D drag is under way: quicker, coarser drawing */
var GEN = 0;                 /* counts builds and scenes opened: a layer drawn for an older one is stale */

function setError(msg) {
  S.error = msg || '';
  var b = $('error');
  b.textContent = S.error;
  b.style.display = S.error ? 'block' : 'none';
}

/* ---- scene, build, trace: all answers from the module --------------------------------- */
function openScene(name, bytes) {
  var r = bytes ? L.openObj(name, bytes) : L.openScene(name);
  if (!r.ok) return r.error;
  SC = L.mesh();
  SC.name = name;
  SC.gen = ++GEN;
  HEATS = [null, null];
  return '';
}

function buildSlot(i) {
  var accel = i === 0 ? S.accel : S.accel2;
  if (!accel) { SLOT[i] = null; return ''; }
  var t0 = now(), r = L.build(i, accel, S.knobs);
  var s = { accel: accel, stats: null, tree: [], nodeBox: {}, nodeDepth: {}, leaf: {}, maxDepth: 0, trace: [], error: '',
            labels: {}, build: [] };
  SLOT[i] = s;
  s.gen = ++GEN;
  if (!r.ok) { s.error = r.error; return accel + ': ' + r.error; }
  s.stats = r.stats;
  s.args = r.args;
  s.labels = r.labels;
  s.build = r.build;
  /* the tree as the build events describe it (viz/json_write.h's array form):
     BUILD_NODE [1, node, parent, depth, count, box6], BUILD_LEAF [4, node, ...],
     a BSP split [3, node, -1, d, cost, nl, nr, normal xyz] */
  var byId = {};
  r.build.forEach(function (e) {
    if (e[0] === 1 && !(e[1] in byId)) {
      var n = { id: e[1], parent: e[2], depth: e[3] < 0 ? 0 : e[3], count: e[4], box: boxOf(e.slice(5, 11)) };
      byId[n.id] = n;
      s.tree.push(n);
      s.nodeBox[n.id] = n.box;
      s.nodeDepth[n.id] = n.depth;
      if (n.depth > s.maxDepth) s.maxDepth = n.depth;
    } else if (e[0] === 4) {
      s.leaf[e[1]] = 1;
    } else if (e[0] === 3 && e[2] < 0 && e.length > 9 && byId[e[1]]) {
      byId[e[1]].plane = [e[7], e[8], e[9]];
      byId[e[1]].pos = e[3];
    }
  });
  s.buildMs = now() - t0;
  return '';
}

function traceSlot(i) {
  var s = SLOT[i];
  if (!s || s.error || !S.ray) { if (s) s.trace = []; return; }
  var r = L.trace(i, S.ray);
  if (!r.ok) { s.trace = []; s.counts = null; s.traceError = r.error; return; }
  s.traceError = '';
  s.trace = r.events;
  s.trace.forEach(function (e) { if (e.box) e.box6 = boxOf(e.box.slice(1)); });
  s.counts = r.counts;
  s.hit = r.hit;
  s.truncated = r.truncated;
  s.misses = !r.hit;
}

/* Rebuilds both structures (after a scene, structure or knob change), then traces. */
function rebuild() {
  var t0 = now(), msgs = [];
  HEATS = [null, null];
  [0, 1].forEach(function (i) { var m = buildSlot(i); if (m) msgs.push(m); });
  S.bstep = build0().length;  /* a new build shows the whole tree */
  retrace(true);
  T.rebuild = now() - t0;
  setError(msgs.join('\n'));
  if (S.mode === 'heat') heat();
}

/* Traces the ray through both structures; the step stays where it was unless
 * keepStep is false (a new ray shows its whole walk). */
function retrace(keepStep) {
  var t0 = now();
  traceSlot(0);
  traceSlot(1);
  var n = SLOT[0] ? SLOT[0].trace.length : 0;
  S.step = keepStep ? Math.min(S.step, n) : n;
  DIFF = diffAt();
  fillTypes();
  render();
  T.trace = now() - t0;
}

/* ---- the replay of the first k traversal events (as view_replay_run) ----------------- */
function replay(s, k) {
  var ntris = SC ? SC.ntris : 0;
  var r = { current: null, box: null, tn: NaN, tf: NaN, stack: [], more: 0, best: null, bestT: Infinity,
            prims: 0, boxes: 0, entered: 0, mailbox: 0, primMark: new Uint8Array(ntris || 1), nodeMark: {},
            cells: [], missed: [] };
  if (!s) return r;
  var trav = s.trace;
  for (var i = 0; i < k && i < trav.length; ++i) {
    var e = trav[i], inTree = e.node !== null && e.node !== undefined && (e.node in s.nodeBox);
    switch (e.type) {
    case 'node_enter':
      r.current = e.node;
      r.box = e.box6 || (inTree ? s.nodeBox[e.node] : null);
      r.tn = num(e.t_near); r.tf = num(e.t_far);
      r.entered++;
      if (inTree) r.nodeMark[e.node] = 1;
      else if (e.box6) r.cells.push(e.box6);     /* grid cells: not in the tree, the event has the box */
      break;
    case 'box_test':
      r.boxes++;
      if (inTree && r.nodeMark[e.node] !== 1) r.nodeMark[e.node] = e.result === 1 ? 3 : 2;
      else if (!inTree && e.result !== 1 && e.bounds) r.missed.push(boxOf(e.bounds));
      break;
    case 'stack_push':
      if (r.stack.length < 64) r.stack.push({ node: e.node, tn: num(e.t_near), tf: num(e.t_far) });
      else r.more++;
      break;
    case 'stack_pop':
      if (r.more > 0) r.more--;
      else if (r.stack.length > 0) {
        var j = r.stack.length - 1;
        while (j > 0 && r.stack[j].node !== e.node) --j;
        if (r.stack[j].node !== e.node) j = r.stack.length - 1;
        r.stack.splice(j, 1);
      }
      break;
    case 'prim_test':
      r.prims++;
      if (e.prim !== null && e.prim < ntris) r.primMark[e.prim] = e.result === 1 ? 2 : 1;
      break;
    case 'mailbox_hit':
      r.mailbox++;
      if (e.prim !== null && e.prim < ntris && r.primMark[e.prim] === 0) r.primMark[e.prim] = 3;
      break;
    case 'hit_update':
    case 'ray_end':
      r.best = e.prim; r.bestT = num(e.t);
      break;
    }
  }
  /* a triangle test that hits at the current step is the best hit already (the next event records it) */
  var last = k >= 1 && k <= trav.length ? trav[k - 1] : null, next = k < trav.length ? trav[k] : null;
  if (last && next && last.type === 'prim_test' && last.result === 1 && next.type === 'hit_update' &&
      next.prim === last.prim) {
    r.best = next.prim; r.bestT = num(next.t);
  }
  return r;
}

/* The first step where the two walks part (the module compares them: the
 * first event that differs in anything but the structure's name); 0 when
 * they are the same, -1 without two traces. */
var DIFF = -1;
function diffAt() {
  if (!SLOT[0] || !SLOT[1] || !S.ray || SLOT[0].error || SLOT[1].error) return -1;
  var d = L.diverge();
  return d ? d.step : -1;
}

/* ---- drawing helpers ---------------------------------------------------------------- */
var cv = $('view'), cx = cv.getContext('2d');
var PAL = [[31, 119, 180], [255, 127, 14], [44, 160, 44], [214, 39, 40], [148, 103, 189], [140, 86, 75],
           [227, 119, 194], [23, 190, 207]];
function depthColor(d, a) { var c = PAL[d % 8]; return 'rgba(' + c[0] + ',' + c[1] + ',' + c[2] + ',' + a + ')'; }
function line(c, x0, y0, x1, y1, w, col, dash) {
  c.beginPath(); c.lineWidth = w; c.strokeStyle = col; c.setLineDash(dash ? [4, 4] : []);
  c.moveTo(x0, y0); c.lineTo(x1, y1); c.stroke(); c.setLineDash([]);
}
function disc(c, x, y, r, col) { c.beginPath(); c.fillStyle = col; c.arc(x, y, r, 0, 2 * Math.PI); c.fill(); }
function vtx(t, k) { var i = SC.idx[3 * t + k] * 3; return [SC.pos[i], SC.pos[i + 1], SC.pos[i + 2]]; }

/* The viewports: the whole canvas, or its two halves when a second structure is on. */
function viewports() {
  var w = cv.width, h = cv.height;
  if (!S.accel2) return [{ x: 0, y: 0, w: w, h: h, slot: 0 }];
  var hw = Math.floor(w / 2);
  return [{ x: 0, y: 0, w: hw - 1, h: h, slot: 0 }, { x: hw + 1, y: 0, w: w - hw - 1, h: h, slot: 1 }];
}
function viewportAt(px) {
  var v = viewports();
  for (var i = v.length - 1; i >= 0; --i) if (px >= v[i].x) return v[i];
  return v[0];
}

/* ---- 2D: the scene seen from +z, fitted with a 6% margin (view_render.c's make_map) --- */
function makeMap(w, h) {
  var b = SC.bounds, ex = b.max[0] - b.min[0], ey = b.max[1] - b.min[1];
  if (!(ex > 0)) ex = 1;
  if (!(ey > 0)) ey = 1;
  var pad = 0.06, s = Math.min(w / (ex * (1 + 2 * pad)), h / (ey * (1 + 2 * pad)));
  var mx = 0.5 * (b.min[0] + b.max[0]), my = 0.5 * (b.min[1] + b.max[1]);
  return { s: s, ox: w * 0.5 - mx * s, oy: h * 0.5 + my * s };
}
function X(m, x) { return m.ox + x * m.s; }
function Y(m, y) { return m.oy - y * m.s; }
function unmap(m, px, py) { return [(px - m.ox) / m.s, (m.oy - py) / m.s]; }
function rect2d(c, m, b, fill, stroke, w, dash) {
  if (boxEmpty(b)) return;
  var x0 = X(m, b.min[0]), x1 = X(m, b.max[0]), y0 = Y(m, b.max[1]), y1 = Y(m, b.min[1]);
  if (fill) { c.fillStyle = fill; c.fillRect(x0, y0, x1 - x0 + 1, y1 - y0 + 1); }
  if (stroke) {
    c.beginPath(); c.lineWidth = w; c.strokeStyle = stroke; c.setLineDash(dash ? [4, 4] : []);
    c.rect(x0 + 0.5, y0 + 0.5, x1 - x0, y1 - y0); c.stroke(); c.setLineDash([]);
  }
}
var FILL = ['#c9d3e0', '#8fb3e8', '#5cb85c', '#c49ae8'], EDGE = ['#8792a3', '#3f6fb8', '#1e7b1e', '#7d3fb8'];
var SPINE = ['#4b5566', '#1f4f98', '#0e5b0e', '#5d1f98'];
/* The height a flat scene's shapes are cut at for their spines: the ray's z plane, else the
 * scene's middle; NaN if the scene is not flat. */
function spineHeight() {
  var b = SC.bounds, ex = b.max[0] - b.min[0], ey = b.max[1] - b.min[1], ez = b.max[2] - b.min[2];
  if (boxEmpty(b) || !(ez > 0) || !(ez < 0.05 * Math.min(ex, ey))) return NaN;
  return S.ray && S.ray[5] === 0 ? S.ray[2] : 0.5 * (b.min[2] + b.max[2]);
}
/* Where triangle p crosses z = z0: the segment a ray in that plane can hit, or null. */
function spine(p, z0) {
  var q = [];
  for (var k = 0; k < 3; ++k) {
    var u = p[k], w = p[(k + 1) % 3], du = u[2] - z0, dw = w[2] - z0;
    if (du === 0) q.push([u[0], u[1]]);
    else if ((du < 0) !== (dw < 0) && dw !== 0) { var s = du / (du - dw); q.push([u[0] + s * (w[0] - u[0]), u[1] + s * (w[1] - u[1])]); }
  }
  return q.length === 2 && (q[0][0] !== q[1][0] || q[0][1] !== q[1][1]) ? q : null;
}
/* Triangles seen from +z (marked ones, or unmarked ones), each with its spine in a flat scene. */
function triangles2d(c, m, mark, markedPass) {
  var z0 = spineHeight(), ntris = SC.ntris;
  for (var t = 0; t < ntris; ++t) {
    var k = mark ? mark[t] : 0;
    if ((k !== 0) !== markedPass) continue;
    var a = vtx(t, 0), b = vtx(t, 1), q = vtx(t, 2);
    var ax = X(m, a[0]), ay = Y(m, a[1]), bx = X(m, b[0]), by = Y(m, b[1]), qx = X(m, q[0]), qy = Y(m, q[1]);
    var area = (bx - ax) * (qy - ay) - (by - ay) * (qx - ax);
    if (Math.abs(area) > 0.5) {
      c.beginPath(); c.moveTo(ax, ay); c.lineTo(bx, by); c.lineTo(qx, qy); c.closePath();
      c.fillStyle = FILL[k]; c.fill(); c.lineWidth = 1; c.strokeStyle = EDGE[k]; c.stroke();
      var sp = isFinite(z0) ? spine([a, b, q], z0) : null;
      if (sp) line(c, X(m, sp[0][0]), Y(m, sp[0][1]), X(m, sp[1][0]), Y(m, sp[1][1]), 2, SPINE[k]);
    } else if (k) {
      var w = k === 2 ? 4 : 3;
      line(c, ax, ay, bx, by, w, EDGE[k]); line(c, bx, by, qx, qy, w, EDGE[k]); line(c, qx, qy, ax, ay, w, EDGE[k]);
    }
  }
}
function structure2d(c, m, s) {
  if (!s) return;
  for (var i = 0; i < s.tree.length; ++i) {
    var n = s.tree[i];
    if (n.plane) plane2d(c, m, n.plane, n.pos, n.box, 1, '#404040');
    var d = n.depth;
    rect2d(c, m, n.box, null, depthColor(d, d === 0 ? 0.8 : 0.6), 1);
  }
}
/* A BSP plane n·p = d seen from +z: its trace inside box b. */
function plane2d(c, m, n, d, b, w, col) {
  if (boxEmpty(b) || Math.abs(n[2]) > 0.99 * Math.hypot(n[0], n[1], n[2])) return;
  var dd = d - n[2] * 0.5 * (b.min[2] + b.max[2]), p = [];
  if (n[1] !== 0) [b.min[0], b.max[0]].forEach(function (x) {
    var y = (dd - n[0] * x) / n[1]; if (y >= b.min[1] && y <= b.max[1]) p.push([x, y]); });
  if (n[0] !== 0) [b.min[1], b.max[1]].forEach(function (y) {
    var x = (dd - n[1] * y) / n[0]; if (x >= b.min[0] && x <= b.max[0]) p.push([x, y]); });
  if (p.length >= 2) line(c, X(m, p[0][0]), Y(m, p[0][1]), X(m, p[p.length - 1][0]), Y(m, p[p.length - 1][1]), w, col);
}
/* where the ray leaves the padded scene box, for drawing it */
function rayEnd() {
  var b = SC.bounds;
  var e = 0.5 * ((b.max[0] - b.min[0]) + (b.max[1] - b.min[1]) + (b.max[2] - b.min[2])) + 1;
  var tf = Infinity;
  for (var i = 0; i < 3; ++i) {
    var d = S.ray[3 + i]; if (d === 0) continue;
    var t1 = (b.min[i] - e - S.ray[i]) / d, t2 = (b.max[i] + e - S.ray[i]) / d;
    tf = Math.min(tf, Math.max(t1, t2));
  }
  return isFinite(tf) && tf > 0 ? tf : 1;
}
function at(t) { return [S.ray[0] + t * S.ray[3], S.ray[1] + t * S.ray[4], S.ray[2] + t * S.ray[5]]; }

/* The layer that changes only with the scene, the structure or the view size. */
function baseLayer(slot, key, w, h, paint) {
  var base = BASE[slot];
  if (!base.canvas) base.canvas = document.createElement('canvas');
  if (base.key !== key) {
    base.canvas.width = w; base.canvas.height = h;
    var c = base.canvas.getContext('2d');
    paint(c);
    base.key = key;
  }
  return base.canvas;
}

function draw2d(vp, r, s) {
  var w = vp.w, h = vp.h, m = makeMap(w, h);
  var key = ['2d', w, h, SC.gen, s ? s.gen : 0, S.ray ? S.ray[2] : '', S.ray ? S.ray[5] : ''].join('|');
  cx.save();
  cx.beginPath(); cx.rect(vp.x, vp.y, w, h); cx.clip();
  cx.translate(vp.x, vp.y);
  cx.drawImage(baseLayer(vp.slot, key, w, h, function (c) {
    c.fillStyle = '#f7f6f0'; c.fillRect(0, 0, w, h);
    triangles2d(c, m, null, false);
    structure2d(c, m, s);
  }), 0, 0);
  if (S.ray && s) {
    for (var id in r.nodeMark) {
      if (r.nodeMark[id] === 1) rect2d(cx, m, s.nodeBox[id], null, '#e0b000', 2);
      else if (r.nodeMark[id] === 2) rect2d(cx, m, s.nodeBox[id], null, '#d02020', 1, true);
    }
    r.cells.forEach(function (b) { rect2d(cx, m, b, null, '#e0b000', 2); });
    r.missed.forEach(function (b) { rect2d(cx, m, b, null, '#d02020', 1, true); });
    triangles2d(cx, m, r.primMark, true);
    if (r.box) rect2d(cx, m, r.box, 'rgba(255,153,0,0.31)', '#ff7f00', 3);
  }
  if (S.ray) {
    var a = S.ray, q = at(rayEnd());
    line(cx, X(m, a[0]), Y(m, a[1]), X(m, q[0]), Y(m, q[1]), 2, '#a01010');
    if (isFinite(r.tn) && isFinite(r.tf)) {
      var p0 = at(r.tn), p1 = at(r.tf);
      line(cx, X(m, p0[0]), Y(m, p0[1]), X(m, p1[0]), Y(m, p1[1]), 6, 'rgba(255,127,0,0.75)');
    }
    disc(cx, X(m, a[0]), Y(m, a[1]), 5, '#a01010');
    if (r.best !== null && isFinite(r.bestT)) {
      var hp = at(r.bestT);
      disc(cx, X(m, hp[0]), Y(m, hp[1]), 7, '#000'); disc(cx, X(m, hp[0]), Y(m, hp[1]), 5, '#ff2020');
      cx.fillStyle = '#000'; cx.font = '12px monospace';
      cx.fillText('t=' + g(r.bestT), X(m, hp[0]) + 9, Y(m, hp[1]) - 8);
    }
  }
  cx.fillStyle = '#333'; cx.font = 'bold 18px monospace';
  cx.fillText('2D: ' + (s ? s.accel : '(no structure)'), 10, 24);
  cx.restore();
}

/* The build mode: the tree as far as its first k build events made it (sidx-view's build
 * mode); the current node's box, its split or candidate plane, a leaf's triangles. */
function drawBuild(vp, s, k) {
  var w = vp.w, h = vp.h, m = makeMap(w, h), b = s ? s.build : [], e = null, box = null, i;
  cx.save();
  cx.beginPath(); cx.rect(vp.x, vp.y, w, h); cx.clip();
  cx.translate(vp.x, vp.y);
  cx.fillStyle = '#f7f6f0'; cx.fillRect(0, 0, w, h);
  triangles2d(cx, m, null, false);
  for (i = 0; i < k && i < b.length; ++i) {
    var x = b[i];
    if (x[0] === 3 && x[2] < 0 && x.length > 9) plane2d(cx, m, [x[7], x[8], x[9]], x[3], s.nodeBox[x[1]], 1, '#404040');
    if (x[0] === 1) { var d = x[3] < 0 ? 0 : x[3]; rect2d(cx, m, boxOf(x.slice(5, 11)), null, depthColor(d, d === 0 ? 0.8 : 0.6), 1); }
  }
  if (k > 0 && k <= b.length) {
    e = b[k - 1];
    box = e[0] === 0 ? boxOf(e.slice(2, 8)) : e[0] === 1 ? boxOf(e.slice(5, 11)) : s.nodeBox[e[1]];
    rect2d(cx, m, box, 'rgba(255,153,0,0.25)', '#ff7f00', 3);
    if ((e[0] === 2 || e[0] === 3) && box) {
      var col = e[0] === 3 ? '#d00000' : 'rgba(208,128,0,0.75)';
      if (e[2] === 0) line(cx, X(m, e[3]), Y(m, box.min[1]), X(m, e[3]), Y(m, box.max[1]), 3, col);
      else if (e[2] === 1) line(cx, X(m, box.min[0]), Y(m, e[3]), X(m, box.max[0]), Y(m, e[3]), 3, col);
      else if (e[2] < 0 && e.length > 9) plane2d(cx, m, [e[7], e[8], e[9]], e[3], box, 3, col);
    }
    if (e[0] === 4 && e[6]) {
      var mk = new Uint8Array(SC.ntris || 1);
      e[6].forEach(function (p) { if (p < SC.ntris) mk[p] = 2; });
      triangles2d(cx, m, mk, true);
    }
  }
  cx.fillStyle = '#333'; cx.font = 'bold 18px monospace';
  cx.fillText('build: ' + (s ? s.accel : '(no structure)'), 10, 24);
  cx.restore();
}

/* The SAH cost over the split position of the current build event's node, from its
 * candidate events (viz/page.html's curve). */
function drawSah(s, k) {
  var sahCv = $('sah'), sx = sahCv.getContext('2d'), w = sahCv.width, h = sahCv.height, pts = [], split = null, i;
  var b = s.build, node = k > 0 && k <= b.length && b[k - 1][0] !== 0 && b[k - 1][0] !== 5 ? b[k - 1][1] : null;
  sx.fillStyle = '#2a2f39'; sx.fillRect(0, 0, w, h);
  $('sah-title').textContent = node === null ? 'SAH cost' : 'SAH cost over split position (node ' + node + ')';
  var note = $('sah-note');
  note.textContent = '';
  if (node === null) return;
  for (i = 0; i < k && i < b.length; ++i) {
    var e = b[i];
    if (e[1] !== node) continue;
    if (e[0] === 3) split = e;
    if (e[0] === 2 && isFinite(e[3]) && isFinite(e[4])) pts.push(e);
  }
  if (!pts.length) {
    sx.fillStyle = '#9aa3b0'; sx.font = '12px monospace'; sx.fillText('no candidates for this node', 8, 20);
    if (s.cand_kept < s.cand_total) note.textContent = 'the page keeps the first ' + s.cand_kept + ' of ' + s.cand_total + ' candidate events';
    return;
  }
  var p0 = Infinity, p1 = -Infinity, c0 = Infinity, c1 = -Infinity;
  pts.forEach(function (e) { p0 = Math.min(p0, e[3]); p1 = Math.max(p1, e[3]); c0 = Math.min(c0, e[4]); c1 = Math.max(c1, e[4]); });
  if (!(p1 > p0)) { p0 -= 0.5; p1 += 0.5; }
  if (!(c1 > c0)) { c0 -= 0.5; c1 += 0.5; }
  var AX = ['#ff6b6b', '#6bdc6b', '#6ba8ff'], last = [null, null, null];
  pts.forEach(function (e) {
    var a = e[2] >= 0 && e[2] < 3 ? e[2] : 0;
    var px = 4 + (e[3] - p0) / (p1 - p0) * (w - 8), py = h - 4 - (e[4] - c0) / (c1 - c0) * (h - 8);
    if (last[a]) { sx.beginPath(); sx.strokeStyle = AX[a]; sx.lineWidth = 1; sx.moveTo(last[a][0], last[a][1]); sx.lineTo(px, py); sx.stroke(); }
    sx.beginPath(); sx.fillStyle = AX[a]; sx.arc(px, py, 1.8, 0, 2 * Math.PI); sx.fill();
    last[a] = [px, py];
  });
  if (split && split[3] >= p0 && split[3] <= p1) {
    var qx = 4 + (split[3] - p0) / (p1 - p0) * (w - 8);
    sx.beginPath(); sx.setLineDash([3, 3]); sx.strokeStyle = '#ffc14d'; sx.moveTo(qx, 2); sx.lineTo(qx, h - 2); sx.stroke(); sx.setLineDash([]);
  }
  note.textContent = 'pos ' + g(p0) + '..' + g(p1) + '  cost ' + g(c0) + '..' + g(c1) + '  (x red, y green, z blue)';
}
/* A build event's line (viz/page.html's wording). */
var AXN = ['x', 'y', 'z'];
function buildLine(s, e) {
  var d = e[0] === 1 || e[0] === 4 ? Math.max(e[0] === 1 ? e[3] : e[2], 0) : (e[1] in s.nodeDepth ? s.nodeDepth[e[1]] + 1 : 0);
  var pad = new Array(Math.min(d, 8) + 1).join('  '), lab = s.labels && s.labels[e[1]] ? '  [' + s.labels[e[1]] + ']' : '';
  switch (e[0]) {
  case 0: return 'build begin (' + s.accel + '): ' + e[1] + ' prims';
  case 1: return pad + 'build node ' + e[1] + '  depth ' + e[3] + '  prims ' + e[4] + (e[2] < 0 ? '  (root)' : '  (parent ' + e[2] + ')') + lab;
  case 2: case 3:
    return pad + (e[0] === 3 ? 'split node ' + e[1] + ' ' : 'candidate ') + 'axis ' + (e[2] < 0 ? 'plane' : AXN[e[2]]) +
           ' at ' + g(e[3]) + '  cost ' + g(e[4]) + '  (L ' + e[5] + ' | R ' + e[6] + ')';
  case 4: return pad + 'leaf node ' + e[1] + '  prims ' + e[3] + '  cost ' + g(e[4]) + '  (' + e[5] + ')' + lab;
  case 5: return 'build end: ' + e[1] + ' nodes, ' + e[2] + ' refs, depth ' + e[3];
  }
  return 'event ' + e[0];
}

/* ---- 3D: a pinhole camera around the scene (view_render.c's make_camera) ------------ */
function sub(a, b) { return [a[0] - b[0], a[1] - b[1], a[2] - b[2]]; }
function dot(a, b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
function cross(a, b) { return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]; }
function norm(a) { var l = Math.hypot(a[0], a[1], a[2]); return l > 0 ? [a[0] / l, a[1] / l, a[2] / l] : a; }
function camera(w, h) {
  var b = SC.bounds;
  var tgt = [0.5 * (b.min[0] + b.max[0]), 0.5 * (b.min[1] + b.max[1]), 0.5 * (b.min[2] + b.max[2])];
  var rad = 0.5 * Math.hypot(b.max[0] - b.min[0], b.max[1] - b.min[1], b.max[2] - b.min[2]);
  if (!(rad > 0)) rad = 1;
  var dist = rad * 2.4 / Math.max(S.zoom, 0.05), cp = Math.cos(S.pitch), sp = Math.sin(S.pitch);
  var eye = [tgt[0] + dist * cp * Math.sin(S.yaw), tgt[1] + dist * sp, tgt[2] + dist * cp * Math.cos(S.yaw)];
  var fwd = norm(sub(tgt, eye)), right = cross(fwd, [0, 1, 0]);
  if (Math.hypot(right[0], right[1], right[2]) < 1e-4) right = [1, 0, 0];
  right = norm(right);
  return { eye: eye, fwd: fwd, right: right, up: cross(right, fwd), f: h * 0.5 / Math.tan(22.5 * Math.PI / 180),
           cx: w * 0.5, cy: h * 0.5 };
}
function project(c, p) {
  var d = sub(p, c.eye), z = dot(d, c.fwd);
  if (z < 1e-3) return null;
  return [c.cx + dot(d, c.right) / z * c.f, c.cy - dot(d, c.up) / z * c.f, z];
}
var EDGES = [[0, 1], [2, 3], [4, 5], [6, 7], [0, 2], [1, 3], [4, 6], [5, 7], [0, 4], [1, 5], [2, 6], [3, 7]];
function box3d(c, cam, b, w, col) {
  if (boxEmpty(b)) return;
  var p = [];
  for (var i = 0; i < 8; ++i)
    p.push(project(cam, [i & 1 ? b.max[0] : b.min[0], i & 2 ? b.max[1] : b.min[1], i & 4 ? b.max[2] : b.min[2]]));
  EDGES.forEach(function (e) { var a = p[e[0]], q = p[e[1]]; if (a && q) line(c, a[0], a[1], q[0], q[1], w, col); });
}
/* The shaded triangles in painter's order, coloured by normal; with mark (per-triangle marks)
 * only the marked ones, in their mark's colour, over the cached picture.  Every vertex is
 * projected once; fast (while orbiting) leaves out the edge strokes that hide the seams. */
function shade3d(c, cam, mark, fast) {
  var light = norm([cam.up[0] * 0.6 + cam.right[0] - cam.fwd[0], cam.up[1] * 0.6 + cam.right[1] - cam.fwd[1],
                    cam.up[2] * 0.6 + cam.right[2] - cam.fwd[2]]);
  var P = SC.pos, I = SC.idx, nv = P.length / 3, ntris = SC.ntris;
  var sx = new Float32Array(nv), sy = new Float32Array(nv), sz = new Float32Array(nv);
  var e = cam.eye, fw = cam.fwd, rt = cam.right, up = cam.up, t, k;
  for (k = 0; k < nv; ++k) {
    var dx = P[3 * k] - e[0], dy = P[3 * k + 1] - e[1], dz = P[3 * k + 2] - e[2];
    var z = dx * fw[0] + dy * fw[1] + dz * fw[2];
    sz[k] = z;
    if (z < 1e-3) continue;
    sx[k] = cam.cx + (dx * rt[0] + dy * rt[1] + dz * rt[2]) / z * cam.f;
    sy[k] = cam.cy - (dx * up[0] + dy * up[1] + dz * up[2]) / z * cam.f;
  }
  var order = [], depth = new Float32Array(ntris);
  for (t = 0; t < ntris; ++t) {
    if (mark && !mark[t]) continue;
    var a = I[3 * t], b = I[3 * t + 1], q = I[3 * t + 2];
    if (sz[a] < 1e-3 || sz[b] < 1e-3 || sz[q] < 1e-3) continue;
    depth[t] = sz[a] + sz[b] + sz[q];
    order.push(t);
  }
  order.sort(function (u, v) { return depth[v] - depth[u]; });
  for (var o = 0; o < order.length; ++o) {
    t = order[o];
    var ia = 3 * I[3 * t], ib = 3 * I[3 * t + 1], iq = 3 * I[3 * t + 2];
    var ux = P[ib] - P[ia], uy = P[ib + 1] - P[ia + 1], uz = P[ib + 2] - P[ia + 2];
    var vx = P[iq] - P[ia], vy = P[iq + 1] - P[ia + 1], vz = P[iq + 2] - P[ia + 2];
    var n = norm([uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx]);
    var cen = [(P[ia] + P[ib] + P[iq]) / 3 - e[0], (P[ia + 1] + P[ib + 1] + P[iq + 1]) / 3 - e[1],
               (P[ia + 2] + P[ib + 2] + P[iq + 2]) / 3 - e[2]];
    if (dot(n, cen) > 0) n = [-n[0], -n[1], -n[2]];
    var lam = 0.35 + 0.65 * Math.max(0, dot(n, light)), mk = mark ? mark[t] : 0;
    var col = mk === 2 ? [92, 184, 92] : mk === 1 ? [143, 179, 232] : mk === 3 ? [196, 154, 232]
            : [255 * (0.5 + 0.5 * n[0]), 255 * (0.5 + 0.5 * n[1]), 255 * (0.5 + 0.5 * n[2])];
    var a0 = I[3 * t], b0 = I[3 * t + 1], q0 = I[3 * t + 2];
    c.beginPath(); c.moveTo(sx[a0], sy[a0]); c.lineTo(sx[b0], sy[b0]); c.lineTo(sx[q0], sy[q0]); c.closePath();
    c.fillStyle = 'rgb(' + Math.round(col[0] * lam) + ',' + Math.round(col[1] * lam) + ',' + Math.round(col[2] * lam) + ')';
    c.fill();
    if (!fast) { c.lineWidth = 0.5; c.strokeStyle = c.fillStyle; c.stroke(); }
  }
}
function draw3d(vp, r, s) {
  var w = vp.w, h = vp.h, cam = camera(w, h);
  var key = ['3d', w, h, S.yaw, S.pitch, S.zoom, SC.gen, ORBITING].join('|');
  cx.save();
  cx.beginPath(); cx.rect(vp.x, vp.y, w, h); cx.clip();
  cx.translate(vp.x, vp.y);
  cx.drawImage(baseLayer(vp.slot, key, w, h, function (c) {
    c.fillStyle = '#30343c'; c.fillRect(0, 0, w, h);
    shade3d(c, cam, null, ORBITING);
  }), 0, 0);
  if (S.ray) {
    var any = false;
    for (var t = 0; t < r.primMark.length; ++t) if (r.primMark[t]) { any = true; break; }
    if (any) shade3d(cx, cam, r.primMark, false);
  }
  if (s && S.level >= 0) s.tree.forEach(function (n) { if (n.depth === S.level) box3d(cx, cam, n.box, 1, depthColor(n.id, 0.8)); });
  if (S.ray && s) {
    for (var nid in r.nodeMark) if (r.nodeMark[nid] === 1 && +nid !== r.current) box3d(cx, cam, s.nodeBox[nid], 1, 'rgba(255,208,0,0.56)');
    if (r.box) box3d(cx, cam, r.box, 3, '#ff7f00');
  }
  if (S.ray) {
    var tEnd = isFinite(r.bestT) ? r.bestT : rayEnd();
    var pa = project(cam, at(1e-3)), pb = project(cam, at(tEnd));
    if (pa && pb) line(cx, pa[0], pa[1], pb[0], pb[1], 2, '#ff3030');
    if (isFinite(r.bestT) && pb) disc(cx, pb[0], pb[1], 5, '#ff2020');
  }
  cx.fillStyle = '#fff'; cx.font = 'bold 18px monospace';
  cx.fillText('3D: ' + (s ? s.accel : '(no structure)'), 10, 24);
  cx.restore();
}

/* ---- the heat map: the module counts, the page colours (log scale) ------------------ */
function heatColor(f) {       /* 0..1 -> dark blue, red, yellow, white */
  var st = [[0, 0, 40], [40, 40, 200], [220, 40, 40], [255, 200, 0], [255, 255, 255]];
  var x = Math.max(0, Math.min(1, f)) * (st.length - 1), i = Math.min(Math.floor(x), st.length - 2), u = x - i;
  return [st[i][0] + u * (st[i + 1][0] - st[i][0]), st[i][1] + u * (st[i + 1][1] - st[i][1]), st[i][2] + u * (st[i + 1][2] - st[i][2])];
}
function heatKey(slot) {
  var sl = SLOT[slot];
  return [SC ? SC.gen : 0, sl ? sl.gen : 0, S.yaw, S.pitch, S.zoom, S.heatMetric, S.heatSize].join('|');
}
/* The heat maps of both structures, coloured on one scale (the larger maximum), so two
 * structures compare pixel for pixel. */
function heat() {
  var n = S.heatSize, res = [null, null], max = 0;
  HEATS = [null, null];
  for (var k = 0; k < 2; ++k) {
    var s = SLOT[k];
    if (!s || s.error) continue;
    var t0 = now(), r = L.heat(k, S.yaw, S.pitch, S.zoom, n, n, S.heatMetric === 'tris' ? 1 : 0);
    if (!r.ok) { setError(r.error); continue; }
    r.t0 = t0;
    res[k] = r;
    if (r.max > max) max = r.max;
  }
  var lm = Math.log(1 + max) || 1;
  for (k = 0; k < 2; ++k) {
    r = res[k];
    if (!r) continue;
    var cnv = document.createElement('canvas');
    cnv.width = n; cnv.height = n;
    var c = cnv.getContext('2d'), img = c.createImageData(n, n), counts = r.counts, d = img.data;
    for (var i = 0; i < n * n; ++i) {
      var col = heatColor(Math.log(1 + counts[i]) / lm);
      d[4 * i] = col[0]; d[4 * i + 1] = col[1]; d[4 * i + 2] = col[2]; d[4 * i + 3] = 255;
    }
    c.putImageData(img, 0, 0);
    HEATS[k] = { key: heatKey(k), n: n, max: r.max, scaleMax: max, mean: r.total / (n * n), canvas: cnv, ms: r.ms };
    if (k === 0) T.heat = now() - r.t0;
  }
  render();
}
/* Where the n x n heat image lies in the viewport: centred, as large as fits. */
function heatRect(vp) {
  var sz = Math.min(vp.w, vp.h);
  return { x: vp.x + Math.floor((vp.w - sz) / 2), y: vp.y + Math.floor((vp.h - sz) / 2), s: sz };
}
function drawHeat(vp, r, s) {
  cx.fillStyle = '#30343c'; cx.fillRect(vp.x, vp.y, vp.w, vp.h);
  var H = HEATS[vp.slot];
  if (!H || H.key !== heatKey(vp.slot)) {
    cx.fillStyle = '#fff'; cx.font = '14px monospace'; cx.fillText('computing the heat map...', vp.x + 10, vp.y + 50);
    return;
  }
  var q = heatRect(vp);
  cx.imageSmoothingEnabled = false;
  cx.drawImage(H.canvas, q.x, q.y, q.s, q.s);
  if (S.ray && s) {             /* the ray, drawn with the heat map's camera */
    var cam = camera(q.s, q.s);
    cx.save(); cx.beginPath(); cx.rect(q.x, q.y, q.s, q.s); cx.clip(); cx.translate(q.x, q.y);
    var tEnd = isFinite(r.bestT) ? r.bestT : rayEnd();
    var pa = project(cam, at(1e-3)), pb = project(cam, at(tEnd));
    if (pa && pb) line(cx, pa[0], pa[1], pb[0], pb[1], 2, '#00ffff');
    if (isFinite(r.bestT) && pb) disc(cx, pb[0], pb[1], 4, '#00ffff');
    cx.restore();
  }
  cx.fillStyle = '#fff'; cx.font = 'bold 18px monospace';
  cx.fillText('heat: ' + (s ? s.accel : ''), vp.x + 10, vp.y + 24);
}
function heatLegend() {
  var show = S.mode === 'heat';
  $('heat-legend').style.display = show ? 'block' : 'none';
  if (!show) return;
  var bar = $('heat-bar'), c = bar.getContext('2d');
  for (var x = 0; x < bar.width; ++x) {
    var col = heatColor(x / (bar.width - 1));
    c.fillStyle = 'rgb(' + (col[0] | 0) + ',' + (col[1] | 0) + ',' + (col[2] | 0) + ')';
    c.fillRect(x, 0, 1, bar.height);
  }
  var what = S.heatMetric === 'tris' ? 'triangle tests' : 'steps (nodes entered + triangle tests)', note = [];
  HEATS.forEach(function (H, k) {
    if (H) note.push(SLOT[k].accel + ': max ' + H.max + ', mean ' + g(H.mean) + ' per pixel, ' + H.n + '\u00d7' + H.n +
                     ' rays in ' + g(H.ms) + ' ms');
  });
  $('heat-note').textContent = note.length ? 'log scale 0 .. ' + HEATS.reduce(function (m, H) { return H ? Math.max(m, H.scaleMax) : m; }, 0) +
    ' ' + what + '\n' + note.join('\n') : '';
}

/* ---- the panel ------------------------------------------------------------------------ */
function trace0() { return SLOT[0] ? SLOT[0].trace : []; }
function build0() { return SLOT[0] ? SLOT[0].build : []; }
function count() { return trace0().length; }
/* The stepper walks the build in build mode, the ray's trace elsewhere. */
function bm() { return S.mode === 'build'; }
function steps() { return bm() ? build0().length : count(); }
function cur() { return bm() ? S.bstep : S.step; }
function typeOf(i) { return bm() ? BTYPES[build0()[i][0]] || 'other' : trace0()[i].type; }
function fillTypes() {
  var sel = $('evtype'), seen = {}, old = sel.value, n = steps();
  sel.innerHTML = '';
  for (var i = 0; i < n; ++i) {
    var t = typeOf(i);
    if (seen[t]) continue;
    seen[t] = 1;
    var o = document.createElement('option'); o.value = o.textContent = t; sel.appendChild(o);
  }
  if (seen[old]) sel.value = old;
  else if (seen.node_enter) sel.value = 'node_enter';
  else if (seen.build_split) sel.value = 'build_split';
}
function statsRows(s) {
  if (!s) return null;
  if (s.error) return { error: s.error };
  var st = s.stats || {};
  return st;
}
function statsHtml() {
  var cols = [0, 1].filter(function (i) { return SLOT[i]; });
  if (!cols.length) return '<span class="dim">no structure</span>';
  var keys = [['nodes', 'nodes'], ['leaves', 'leaves'], ['depth', 'max_depth'], ['SAH', 'sah_cost'],
              ['refs', 'prim_refs'], ['KiB', 'bytes'], ['build ms', 'build_ms']];
  var h = ['<table><tr><td></td>'];
  keys.forEach(function (k) { h.push('<th>' + k[0] + '</th>'); });
  h.push('</tr>');
  cols.forEach(function (i) {
    var s = SLOT[i];
    h.push('<tr><td>' + esc(s.accel) + '</td>');
    keys.forEach(function (k) {
      var v = s.stats ? s.stats[k[1]] : undefined;
      if (k[1] === 'bytes' && typeof v === 'number') v = v / 1024;
      h.push('<td data-key="' + k[1] + '">' + (s.error ? '<span class="bad">-</span>' : v === undefined || v === null ? '' :
        typeof v === 'number' && !Number.isInteger(v) ? g(v) : esc(v)) + '</td>');
    });
    h.push('</tr>');
  });
  h.push('</table>');
  cols.forEach(function (i) {
    if (!SLOT[i].error) h.push('<div class="dim">= sidx-step --accel ' + esc(SLOT[i].accel) + ' ' + esc(S.scene) +
                (SLOT[i].args ? ' ' + esc(SLOT[i].args) : '') + '</div>');
  });
  return h.join('');
}
/* The walk's counts (the module's: events of each type in the whole trace). */
function walkCounts(s) { return s.counts || {}; }
function compareHtml() {
  if (!S.accel2 || !SLOT[0] || !SLOT[1] || !S.ray) return '';
  var a = walkCounts(SLOT[0]), b = walkCounts(SLOT[1]);
  var rows = [['nodes entered', 'nodes'], ['boxes tested', 'boxes'], ['triangles tested', 'triangles'],
              ['mailbox hits', 'mailbox'], ['events', 'events']];
  var h = ['<h2>the same ray through both</h2><table><tr><td></td><th>' + esc(SLOT[0].accel) + '</th><th>' +
           esc(SLOT[1].accel) + '</th></tr>'];
  rows.forEach(function (rw) {
    h.push('<tr><td>' + rw[0] + '</td><td>' + (a[rw[1]] === undefined ? '' : a[rw[1]]) + '</td><td>' +
           (b[rw[1]] === undefined ? '' : b[rw[1]]) + '</td></tr>');
  });
  function hitOf(s) { return s.hit ? 'prim ' + s.hit.prim : 'miss'; }
  function tOf(s) { return s.hit ? g(num(s.hit.t)) : ''; }
  h.push('<tr><td>hit</td><td>' + hitOf(SLOT[0]) + '</td><td>' + hitOf(SLOT[1]) + '</td></tr>');
  h.push('<tr><td>t</td><td>' + tOf(SLOT[0]) + '</td><td>' + tOf(SLOT[1]) + '</td></tr></table>');
  if (DIFF > 0) {
    h.push('<div>the walks part at step <a href="#" id="goto-part" class="hi">' + DIFF + '</a>:</div>');
    [0, 1].forEach(function (k) {
      var e = SLOT[k].trace[DIFF - 1];
      h.push('<div class="dim">&nbsp;&nbsp;' + esc(SLOT[k].accel) + ': ' + (e ? esc(lineOf(e).trim()) : '(its walk has ended)') + '</div>');
    });
  } else h.push('<div class="good">the two walks are the same, event for event</div>');
  return h.join('');
}
function panel(r) {
  var s = SLOT[0], k = cur(), n = steps(), info = [], inBuild = bm();
  $('title-note').textContent = SC ? SC.name + ' (' + SC.ntris + ' triangles)' : '';
  ['2d', 'build', '3d'].forEach(function (m) { $('m-' + m).className = S.mode === m ? 'on' : ''; });
  $('heatmap').className = S.mode === 'heat' ? 'on' : '';
  $('b-play').textContent = S.playing ? 'pause' : 'play';
  $('level-row').style.display = S.mode === '3d' ? '' : 'none';
  $('level').textContent = S.level >= 0 ? S.level + ' (max ' + (s ? s.maxDepth : 0) + ')' : 'off';
  $('jump').max = n;
  $('stats').innerHTML = statsHtml();
  var banner = $('banner');
  if (inBuild) banner.style.display = 'none';
  else if (!S.ray) { banner.style.display = 'block'; banner.textContent = S.mode === '2d' ? 'Drag on the view to shoot a ray.' : 'Click on the view to shoot a ray.'; }
  else if (s && s.misses) { banner.style.display = 'block'; banner.textContent = 'The ray misses: it hits no triangle.'; }
  else banner.style.display = 'none';
  if (inBuild && s) {
    info.push('<span class="hi">build step ' + k + ' / ' + n + '</span>');
    if (k > 0 && k <= s.build.length) info.push(esc(buildLine(s, s.build[k - 1]).trim()));
    if (s.cand_kept < s.cand_total)
      info.push('<span class="dim">SAH candidates: the first ' + s.cand_kept + ' of ' + s.cand_total + ' are in the page</span>');
  } else if (S.ray) {
    info.push('ray o=(' + S.ray.slice(0, 3).map(g).join(', ') + ')');
    info.push('    d=(' + S.ray.slice(3).map(g).join(', ') + ')');
    info.push('<span class="hi">step ' + k + ' / ' + n + '</span>');
    info.push(r.best !== null ? '<span class="good">best hit: prim ' + r.best + '  t=' + g(r.bestT) + '</span>'
                              : 'best hit: none' + (k >= n && s && s.misses ? ' (the ray misses)' : ' yet'));
    info.push('entered ' + r.entered + '  boxes ' + r.boxes + '  prims ' + r.prims + '  mailbox ' + r.mailbox);
    if (r.current !== null) info.push('current node ' + r.current + (s && s.leaf[r.current] ? ' (leaf)' : '') +
                                      '  t=[' + g(r.tn) + ', ' + g(r.tf) + ']');
  }
  $('info').innerHTML = info.join('<br>');
  $('compare').innerHTML = inBuild ? '' : compareHtml();
  $('stack-box').style.display = inBuild ? 'none' : '';
  $('sah-box').style.display = inBuild ? '' : 'none';
  if (inBuild && s) drawSah(s, k);
  var gp = $('goto-part');
  if (gp) gp.onclick = function (e) { e.preventDefault(); go(DIFF); };
  $('stack-title').textContent = 'stack (top first): ' + (r.stack.length + r.more);
  var st = $('stack'); st.innerHTML = '';
  for (var i = r.stack.length - 1; i >= 0; --i) {
    var li = document.createElement('li');
    li.textContent = 'node ' + r.stack[i].node + '  t=[' + g(r.stack[i].tn) + ', ' + g(r.stack[i].tf) + ']';
    st.appendChild(li);
  }
  if (r.more) { var mo = document.createElement('li'); mo.textContent = '... ' + r.more + ' more'; st.appendChild(mo); }
  var tr = trace0(), lines = 30, first = Math.max(0, Math.min(k - 1 - (lines >> 1), n - lines)), html = [];
  for (var j = first; j < first + lines && j < n; ++j)
    html.push('<div data-i="' + j + '" class="' + (j === k - 1 ? 'cur' : j < k - 1 ? 'past' : 'future') +
              (!inBuild && j === DIFF - 1 ? ' part' : '') + '">' + ('    ' + (j + 1)).slice(-5) + ' ' +
              esc(inBuild ? buildLine(s, s.build[j]) : lineOf(tr[j])) + '</div>');
  $('events').innerHTML = html.join('');
  heatLegend();
}
/* An event's line: the printer's text from the module when it gives one. */
function lineOf(e) {
  if (e.line) return e.line.replace(/^ {17,}/, function (x) { return x.slice(x.length - 16); });
  var p = [e.type];
  ['node', 'prim', 'depth', 'result', 'reason'].forEach(function (f) { if (e[f] !== undefined) p.push(f + ' ' + e[f]); });
  if (e.t_near !== undefined) p.push('t=[' + g(num(e.t_near)) + ', ' + g(num(e.t_far)) + ']');
  if (e.t !== undefined) p.push('t=' + g(num(e.t)));
  return p.join('  ');
}

/* ---- render, the address ------------------------------------------------------------- */
function render() {
  var t0 = now(), v = $('viewbox');
  if (cv.width !== v.clientWidth || cv.height !== v.clientHeight) {
    cv.width = Math.max(200, v.clientWidth); cv.height = Math.max(200, v.clientHeight);
  }
  if (!SC) { cx.fillStyle = '#f7f6f0'; cx.fillRect(0, 0, cv.width, cv.height); panel(replay(null, 0)); return; }
  var r0 = null;
  viewports().forEach(function (vp) {
    var s = SLOT[vp.slot], r = replay(s, S.step);
    if (vp.slot === 0) r0 = r;
    if (S.mode === 'heat' && !ORBITING) drawHeat(vp, r, s);
    else if (S.mode === 'build') drawBuild(vp, s, Math.min(S.bstep, s ? s.build.length : 0));
    else if (S.mode === '2d') draw2d(vp, r, s);
    else draw3d(vp, r, s);
    if (s && s.error) {
      cx.fillStyle = 'rgba(122,31,31,0.85)'; cx.fillRect(vp.x + 10, vp.y + 34, vp.w - 20, 22);
      cx.fillStyle = '#fff'; cx.font = '13px monospace'; cx.fillText(s.error.slice(0, 90), vp.x + 16, vp.y + 50);
    }
  });
  if (viewports().length > 1) { cx.fillStyle = '#1f232b'; cx.fillRect(viewports()[1].x - 2, 0, 2, cv.height); }
  panel(r0);
  $('hint').textContent = S.mode === '2d' ? 'drag: a new ray from the press point towards the release point'
    : S.mode === 'build' ? 'the build, event by event: step with the arrows'
    : S.mode === '3d' ? 'drag: orbit   wheel: zoom   click: a ray through that pixel' : 'click: a ray through that pixel';
  writeHash();
  T.draw = now() - t0;
}

/* A float as the shortest decimal that reads back to the same float (at most 9 digits). */
function fmt(x) {
  if (!isFinite(x) || x !== Math.fround(x)) return String(x);
  for (var p = 1; p < 9; ++p) { var t = +x.toPrecision(p); if (Math.fround(t) === x) return String(t); }
  return String(+x.toPrecision(9));
}
var LAST_HASH = '';
function writeHash() {
  var p = ['scene=' + encodeURIComponent(S.scene), 'accel=' + encodeURIComponent(S.accel)];
  if (S.accel2) p.push('accel2=' + encodeURIComponent(S.accel2));
  KNOBS.forEach(function (k) { if (S.knobs[k] !== undefined) p.push(k + '=' + fmt(S.knobs[k])); });
  p.push('mode=' + S.mode);
  if (S.mode !== '2d') p.push('cam=' + [S.yaw, S.pitch, S.zoom].map(function (x) { return +x.toFixed(4); }).join(','));
  if (S.level >= 0) p.push('level=' + S.level);
  if (S.mode === 'heat') p.push('heat=' + S.heatMetric + ',' + S.heatSize);
  if (S.ray) p.push('ray=' + S.ray.map(fmt).join(','));
  if (S.ray) p.push('step=' + S.step);
  if (S.mode === 'build') p.push('bstep=' + S.bstep);
  var h = '#' + p.join('&');
  LAST_HASH = h;
  if (location.hash !== h) try { history.replaceState(null, '', h); } catch (e) { /* some browsers refuse on file: */ }
}
function readHash() {
  var q = {};
  location.hash.replace(/^#/, '').split('&').forEach(function (kv) {
    var i = kv.indexOf('=');
    if (i > 0) q[kv.slice(0, i)] = decodeURIComponent(kv.slice(i + 1));
  });
  return q;
}

/* ---- actions -------------------------------------------------------------------------- */
function f32(x) { return Math.fround(x); }
function setRay(ray, keepStep) {
  if (!ray || ray.length !== 6 || !ray.every(isFinite) || (ray[3] === 0 && ray[4] === 0 && ray[5] === 0)) return false;
  S.ray = ray.map(f32);       /* the module traces float rays: state() reports what it traced */
  retrace(!!keepStep);
  return true;
}
function go(k) {
  k = Math.max(0, Math.min(steps(), k | 0));
  if (bm()) S.bstep = k; else S.step = k;
  render();
}
function stop() { if (S.playing) { clearInterval(S.playing); S.playing = null; } }
function play() {
  if (S.playing) { stop(); render(); return; }
  if (cur() >= steps()) go(0);
  S.playing = setInterval(function () { if (cur() >= steps()) { stop(); render(); } else go(cur() + 1); }, 120);
  render();
}
function nextWhere(dir, pred) {
  var n = steps();
  for (var i = cur() - 1 + dir; i >= 0 && i < n; i += dir) if (pred(i)) { go(i + 1); return; }
}
function nextOfType(dir) { var t = $('evtype').value; nextWhere(dir, function (i) { return typeOf(i) === t; }); }
function nextLeaf(dir) {
  var s = SLOT[0];
  /* a leaf entered, as sidx-step's "leaf": a grid cell, or a node the build made a leaf */
  nextWhere(dir, function (i) {
    if (bm()) return build0()[i][0] === 4;
    var e = trace0()[i];
    return e.type === 'node_enter' && ((e.cell && e.cell[0] >= 0) || (s && s.leaf[e.node] === 1));
  });
}
function setMode(m) {
  stop();
  S.mode = m;
  fillTypes();
  if (m === 'heat' && (!HEATS[0] || HEATS[0].key !== heatKey(0))) { render(); setTimeout(heat, 0); return; }
  render();
}

/* the knobs: the inputs -> S.knobs (only those set) */
function readKnobs() {
  var k = {};
  KNOBS.forEach(function (name) {
    var el = $('knob-' + name);
    if (name === 'mailbox') { if (!el.checked) k.mailbox = 0; return; }
    if (el.value === '') return;
    var v = Number(el.value);
    if (isFinite(v)) k[name] = v;
  });
  return k;
}
function writeKnobs() {
  KNOBS.forEach(function (name) {
    var el = $('knob-' + name);
    if (name === 'mailbox') el.checked = S.knobs.mailbox !== 0;
    else el.value = S.knobs[name] === undefined ? '' : S.knobs[name];
  });
}

function fillSceneSelect(extra) {
  var sel = $('scene');
  sel.innerHTML = '';
  L.scenes().forEach(function (n) { var o = document.createElement('option'); o.value = o.textContent = n; sel.appendChild(o); });
  if (extra) { var o = document.createElement('option'); o.value = extra; o.textContent = extra + ' (file)'; sel.appendChild(o); }
  sel.value = S.scene;
}
/* The structures that suit the open scene (the module says which). */
function fillAccelSelects() {
  var list = L.accels(), a = $('accel'), b = $('accel2');
  a.innerHTML = ''; b.innerHTML = '';
  var none = document.createElement('option'); none.value = ''; none.textContent = '(none)'; b.appendChild(none);
  list.forEach(function (x) {
    if (x.suits === false) return;
    [a, b].forEach(function (sel) {
      var o = document.createElement('option'); o.value = o.textContent = x.name; o.title = x.description || ''; sel.appendChild(o);
    });
  });
  var names = list.filter(function (x) { return x.suits !== false; }).map(function (x) { return x.name; });
  if (names.indexOf(S.accel) < 0) S.accel = names.indexOf('bvh') >= 0 ? 'bvh' : names[0] || '';
  if (S.accel2 && names.indexOf(S.accel2) < 0) S.accel2 = '';
  a.value = S.accel; b.value = S.accel2;
}
/* A default ray across the scene, in its middle z plane (as sidx-view's). */
function defaultRay() {
  if (SC.name === 'kd-slide') return [0, 4.2, 0, 1, 0.15, 0];
  var b = SC.bounds, cx0 = 0.5 * (b.min[0] + b.max[0]), cy0 = 0.5 * (b.min[1] + b.max[1]), cz = 0.5 * (b.min[2] + b.max[2]);
  var ex = b.max[0] - b.min[0], ey = b.max[1] - b.min[1];
  if (SC.flat) return [b.min[0] - 0.05 * ex, cy0 + 0.13 * ey, cz, 1, -0.1, 0];
  return L.cameraRay(S.yaw, S.pitch, S.zoom, 400, 400, 200.5, 200.5);
}
/* Opens a scene (a name, or an OBJ file's bytes): every view on it starts afresh. */
function loadScene(name, bytes, ray) {
  var msg = openScene(name, bytes);
  if (msg) { setError(msg); return false; }
  S.scene = name;
  fillSceneSelect(bytes ? name : FILE ? FILE.name : null);
  fillAccelSelects();
  if (S.mode === '2d' && !SC.flat && !ray) S.mode = '3d';
  if (SC.flat && S.mode !== '2d' && !ray) S.mode = '2d';
  S.ray = (ray || defaultRay()).map(f32);
  S.step = Infinity;          /* a new scene shows the whole walk */
  rebuild();
  return true;
}

/* An OBJ from the file picker or a drop. */
function loadFile(file) {
  if (!file) return;
  var lim = L.limits();
  if (lim.obj_bytes && file.size > lim.obj_bytes) {
    setError(file.name + ': ' + file.size + ' bytes; the lab opens files of at most ' + lim.obj_bytes + ' bytes (' +
             Math.round(lim.obj_bytes / 1048576) + ' MiB)' + (lim.triangles ? ' and ' + lim.triangles + ' triangles' : ''));
    return;
  }
  var rd = new FileReader();
  rd.onload = function () {
    var saved = { scene: S.scene }, link = PENDING && PENDING.scene === file.name ? PENDING : null;
    if (!loadScene(file.name, new Uint8Array(rd.result), null)) {
      S.scene = saved.scene;          /* the scene before stays open */
      $('scene').value = S.scene;
      return;
    }
    FILE = { name: file.name, bytes: new Uint8Array(rd.result) };
    setError('');
    if (link) { PENDING = null; applyLink(link, true); }
  };
  rd.onerror = function () { setError(file.name + ': the browser could not read the file'); };
  rd.readAsArrayBuffer(file);
}

/* ---- input ------------------------------------------------------------------------------ */
function bindInputs() {
  $('scene').onchange = function () {
    loadScene(this.value, FILE && FILE.name === this.value ? FILE.bytes : null, null);
  };
  $('accel').onchange = function () { S.accel = this.value; rebuild(); };
  $('accel2').onchange = function () { S.accel2 = this.value; rebuild(); };
  KNOBS.forEach(function (name) {
    $('knob-' + name).addEventListener('change', function () { S.knobs = readKnobs(); rebuild(); });
  });
  $('knob-reset').onclick = function () { S.knobs = {}; writeKnobs(); rebuild(); };
  $('obj-file').onchange = function () { loadFile(this.files[0]); this.value = ''; };
  var vb = $('viewbox');
  vb.addEventListener('dragover', function (e) { e.preventDefault(); vb.className = 'dragover'; });
  vb.addEventListener('dragleave', function () { vb.className = ''; });
  vb.addEventListener('drop', function (e) {
    e.preventDefault(); vb.className = '';
    if (e.dataTransfer && e.dataTransfer.files.length) loadFile(e.dataTransfer.files[0]);
  });
  $('m-2d').onclick = function () { setMode('2d'); };
  $('m-build').onclick = function () { setMode('build'); };
  $('m-3d').onclick = function () { setMode('3d'); };
  $('heatmap').onclick = function () { setMode(S.mode === 'heat' ? '3d' : 'heat'); };
  $('heat-metric').onchange = function () { S.heatMetric = this.value; if (S.mode === 'heat') heat(); };
  $('heat-size').onchange = function () { S.heatSize = +this.value; if (S.mode === 'heat') heat(); };
  $('b-first').onclick = function () { go(0); };
  $('b-prev').onclick = function () { go(cur() - 1); };
  $('b-next').onclick = function () { go(cur() + 1); };
  $('b-last').onclick = function () { go(steps()); };
  $('b-play').onclick = play;
  $('b-jump').onclick = function () { go(parseInt($('jump').value, 10) || 0); };
  $('jump').onkeydown = function (e) { if (e.key === 'Enter') { go(parseInt($('jump').value, 10) || 0); $('jump').blur(); } };
  $('b-nexttype').onclick = function () { nextOfType(1); };
  $('b-prevtype').onclick = function () { nextOfType(-1); };
  $('b-nextleaf').onclick = function () { nextLeaf(1); };
  $('b-prevleaf').onclick = function () { nextLeaf(-1); };
  $('b-lvup').onclick = function () { S.level = Math.min(S.level + 1, SLOT[0] ? SLOT[0].maxDepth : 0); render(); };
  $('b-lvdown').onclick = function () { S.level = Math.max(S.level - 1, -1); render(); };
  $('events').onclick = function (e) { var d = e.target.closest('div[data-i]'); if (d) go(+d.dataset.i + 1); };
  document.addEventListener('keydown', function (e) {
    if (e.target && (e.target.tagName === 'INPUT' || e.target.tagName === 'SELECT')) return;
    var k = e.key;
    if (k === 'ArrowRight' || k === 'n') go(cur() + 1);
    else if (k === 'ArrowLeft' || k === 'p') go(cur() - 1);
    else if (k === 'Home') go(0);
    else if (k === 'End') go(steps());
    else if (k === ' ') play();
    else if (k === 'g') { $('jump').focus(); $('jump').select(); }
    else if (k === 't') nextOfType(1);
    else if (k === 'T') nextOfType(-1);
    else if (k === 'l') nextLeaf(1);
    else if (k === 'L') nextLeaf(-1);
    else if (k === '1') setMode('2d');
    else if (k === '2') setMode('build');
    else if (k === '3') setMode('3d');
    else if (k === '4') setMode('heat');
    else if (k === '+' || k === '=') $('b-lvup').onclick();
    else if (k === '-') $('b-lvdown').onclick();
    else return;
    e.preventDefault();
  });

  /* the view: 2D drags a ray, 3D orbits or shoots one */
  var drag = null;
  function local(e) { var b = cv.getBoundingClientRect(); return [(e.clientX - b.left) * cv.width / b.width, (e.clientY - b.top) * cv.height / b.height]; }
  function ray2d(d) {
    var vp = d.vp, m = makeMap(vp.w, vp.h);
    var a = unmap(m, d.x0 - vp.x, d.y0 - vp.y), b = unmap(m, d.x1 - vp.x, d.y1 - vp.y);
    var z = 0.5 * (SC.bounds.min[2] + SC.bounds.max[2]);
    return [a[0], a[1], z, b[0] - a[0], b[1] - a[1], 0];
  }
  cv.addEventListener('mousedown', function (e) {
    if (!SC || e.button !== 0 || S.mode === 'build') return;
    var p = local(e);
    drag = { x0: p[0], y0: p[1], x1: p[0], y1: p[1], vp: viewportAt(p[0]), yaw: S.yaw, pitch: S.pitch, moved: false, cx: e.clientX, cy: e.clientY };
    e.preventDefault();
  });
  window.addEventListener('mousemove', function (e) {
    if (!drag) return;
    var p = local(e);
    drag.x1 = p[0]; drag.y1 = p[1];
    drag.moved = drag.moved || Math.abs(e.clientX - drag.cx) + Math.abs(e.clientY - drag.cy) > 3;
    if (!drag.moved) return;
    if (S.mode === '2d') setRay(ray2d(drag), false);   /* the walk follows the mouse */
    else {                     /* 3D and the heat map: orbit (the heat map is recomputed on release) */
      ORBITING = true;
      S.yaw = drag.yaw - (e.clientX - drag.cx) * 0.01;
      S.pitch = Math.max(-1.5, Math.min(1.5, drag.pitch + (e.clientY - drag.cy) * 0.01));
      render();
    }
  });
  window.addEventListener('mouseup', function (e) {
    if (!drag) return;
    var d = drag;
    drag = null;
    var p = local(e);
    d.x1 = p[0]; d.y1 = p[1];
    if (S.mode === '2d') { if (d.moved) setRay(ray2d(d), false); return; }
    if (ORBITING) { ORBITING = false; if (S.mode === 'heat') heat(); else render(); return; }
    if (d.moved) return;
    /* a click: the camera ray through that pixel */
    var vp = d.vp;
    if (S.mode === 'heat') {   /* the heat map's pixel: its image is n x n */
      var q = heatRect(vp), n = S.heatSize;
      if (d.x1 < q.x || d.y1 < q.y || d.x1 >= q.x + q.s || d.y1 >= q.y + q.s) return;
      setRay(L.cameraRay(S.yaw, S.pitch, S.zoom, n, n, Math.floor((d.x1 - q.x) * n / q.s) + 0.5,
                         Math.floor((d.y1 - q.y) * n / q.s) + 0.5), false);
    } else {
      setRay(L.cameraRay(S.yaw, S.pitch, S.zoom, vp.w, vp.h, d.x1 - vp.x, d.y1 - vp.y), false);
    }
  });
  cv.addEventListener('wheel', function (e) {
    if (S.mode === '2d') return;
    S.zoom *= e.deltaY < 0 ? 1.1 : 1 / 1.1;
    e.preventDefault();
    if (S.mode === 'heat') heat(); else render();
  }, { passive: false });
  window.addEventListener('resize', function () { render(); });
}

/* ---- the state a program reads --------------------------------------------------------- */
function stripped(e) {        /* the event as sidx_event_to_json writes it */
  var o = {};
  for (var k in e) if (k !== 'line' && k !== 'box' && k !== 'box6') o[k] = e[k];
  return o;
}
window.sidxLab = {
  ready: null,
  state: function () {
    var s0 = SLOT[0], s1 = SLOT[1];
    return {
      scene: S.scene, accel: S.accel, accel2: S.accel2 || null, knobs: JSON.parse(JSON.stringify(S.knobs)),
      ray: S.ray ? S.ray.slice() : null, step: S.step, mode: S.mode,
      events: s0 ? s0.trace.map(stripped) : [],
      events2: s1 ? s1.trace.map(stripped) : [],
      stats: s0 && s0.stats ? Object.assign({}, s0.stats, s0.trace ? { walk: walkCounts(s0) } : {}) : null,
      stats2: s1 && s1.stats ? Object.assign({}, s1.stats, { walk: walkCounts(s1) }) : null,
      part: DIFF, heat: HEATS[0] ? { n: HEATS[0].n, max: HEATS[0].max, mean: HEATS[0].mean } : null,
      error: S.error || (window.sidxErrors.length ? window.sidxErrors.join('\n') : '')
    };
  },
  timings: function () { return { rebuild: T.rebuild, trace: T.trace, heat: T.heat, draw: T.draw, parts: T.parts, tparts: T.tparts }; },
  /* for a program: the same as the inputs, without the mouse */
  setRay: function (r) { return setRay(r, false); },
  heat: function () { if (S.mode !== 'heat') S.mode = 'heat'; heat(); return T.heat; }
};

/* ---- start ------------------------------------------------------------------------------ */
/* The view an address describes: {scene, accel, accel2, knobs, mode, cam, level, heat, ray, step}. */
function linkOf(q) {
  var v = { scene: q.scene || 'kd-slide', accel: q.accel || '', accel2: q.accel2 || '', knobs: {}, mode: null,
            cam: null, level: -1, heat: null, ray: null, step: null };
  KNOBS.forEach(function (k) { if (q[k] !== undefined && q[k] !== '' && isFinite(+q[k])) v.knobs[k] = +q[k]; });
  if (q.mode === '2d' || q.mode === 'build' || q.mode === '3d' || q.mode === 'heat') v.mode = q.mode;
  if (q.cam) { var c = q.cam.split(',').map(Number); if (c.length === 3 && c.every(isFinite)) v.cam = c; }
  if (q.level && /^\d+$/.test(q.level)) v.level = +q.level;
  if (q.heat) {
    var hp = q.heat.split(',');
    v.heat = [hp[0] === 'tris' ? 'tris' : 'steps', +hp[1] > 0 ? Math.min(1024, +hp[1] | 0) : 256];
  }
  var ray = q.ray ? q.ray.split(',').map(Number) : null;
  if (ray && ray.length === 6 && ray.every(isFinite)) v.ray = ray;
  if (q.step && /^\d+$/.test(q.step)) v.step = +q.step;
  v.bstep = q.bstep && /^\d+$/.test(q.bstep) ? +q.bstep : null;
  return v;
}
/* Opens the view of a link: its scene, structures, knobs, camera, ray and step.  A scene that
 * was a file cannot come back by itself: the page says so, and applies the rest of the link
 * when a file of that name is opened. */
var PENDING = null;
var FILE = null;             /* the OBJ opened last, {name, bytes}: the scene list offers it again */
function applyLink(v, sceneLoaded) {
  S.accel = v.accel; S.accel2 = v.accel2; S.knobs = v.knobs;
  writeKnobs();
  if (v.cam) { S.yaw = v.cam[0]; S.pitch = v.cam[1]; S.zoom = v.cam[2]; }
  S.level = v.level;
  if (v.heat) { S.heatMetric = v.heat[0]; S.heatSize = v.heat[1]; }
  $('heat-metric').value = S.heatMetric; $('heat-size').value = String(S.heatSize);
  if (v.mode) S.mode = v.mode;
  if (sceneLoaded) {
    fillAccelSelects();
    S.ray = v.ray ? v.ray.map(f32) : defaultRay().map(f32);
    S.step = Infinity;
    rebuild();
  } else {
    var msgErr = S.error;
    if (!loadScene(v.scene, null, v.ray)) return;
    if (msgErr && !S.error) setError(msgErr);
  }
  if (v.mode) S.mode = v.mode;
  if (v.step !== null) S.step = Math.min(v.step, count());
  if (v.bstep !== null) S.bstep = Math.min(v.bstep, build0().length);
  fillTypes();
  if (S.mode === 'heat') heat(); else render();
}
function onHash() {
  var h = location.hash;
  if (h === LAST_HASH) return;          /* the page's own address */
  var v = linkOf(readHash());
  if (L.scenes().indexOf(v.scene) < 0) {
    if (v.scene === S.scene && SC) { applyLink(v, true); return; }
    PENDING = v;
    setError('The scene "' + v.scene + '" of this link is a file: open it with "open OBJ..." (or drop it here) and ' +
             'the link\'s structures, knobs, ray and step follow.');
    if (!SC) { v = linkOf({}); applyLink(v, false); setError(S.error); }
    return;
  }
  applyLink(v, false);
}

function start(lab) {
  L = lab;
  bindInputs();
  onHash();
  if (!SC) applyLink(linkOf({}), false);
  $('loading').style.display = 'none';
  window.addEventListener('hashchange', onHash);
  render();
}

window.sidxLab.ready = new Promise(function (resolve, reject) {
  function fail(msg) {
    $('loading').textContent = msg;
    setError(msg);
    reject(new Error(msg));
  }
  function go(M) {
    try { start(makeLab(M)); resolve(); } catch (e) { fail('The page could not start: ' + e.message); console.error(e); }
  }
  try {
    var factory = window.sidxLabModule || window.SidxLab || window.createSidxLab;
    if (typeof factory !== 'function') { fail('The WebAssembly module is missing from the page.'); return; }
    factory().then(go, function (e) { fail('The WebAssembly module did not load: ' + (e && e.message ? e.message : e)); });
  } catch (e) { fail('The WebAssembly module did not load: ' + e.message); }
});

})();
