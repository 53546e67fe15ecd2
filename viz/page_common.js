/* page_common.js: the script both web pages share, sidx-view --html's page
 * (viz/page.html) and the lab (viz/lab_page.html).  The Makefile writes this
 * text in place of the line that holds only the marker SIDX_PAGE_COMMON
 * (between slashes, stars and at signs) in each page's script, so either
 * page stays one file: sidx-view compiles its page with this text into the
 * program, make web writes it into build/web/sidx-lab.html.  Only
 * functions and constants here: each page keeps its own state and passes
 * what they draw (the mesh {pos, idx, ntris, bounds}, the ray as
 * [ox, oy, oz, dx, dy, dz], the structure's node boxes).  No closing
 * script tag in this text. */

/* ---- numbers, text and boxes ---------------------------------------------------------- */
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
function vtx(mesh, t, k) { var i = mesh.idx[3 * t + k] * 3; return [mesh.pos[i], mesh.pos[i + 1], mesh.pos[i + 2]]; }
/* An event's line with a deep indent cut to 16 spaces, so it fits the panel. */
function cutIndent(s) { return s.replace(/^ {17,}/, function (x) { return x.slice(x.length - 16); }); }

/* ---- the replay of the first k traversal events (view_replay_run) --------------------- */
/* What the walk has done after k events: the current node and its interval, the stack,
 * the best hit, the counts, a mark per triangle (1 tested, 2 hit, 3 mailbox skip) and per
 * node of the tree (1 entered, 2 box missed, 3 box hit).  Nodes count as the tree's where
 * hasTree is set and nodeBox has them; with keepCells the cells entered outside the tree
 * (a grid's, whose event has the box) and the boxes missed outside it are listed too. */
function replayWalk(trav, k, ntris, nodeBox, hasTree, keepCells) {
  var r = { current: null, box: null, tn: NaN, tf: NaN, stack: [], more: 0, best: null, bestT: Infinity,
            prims: 0, boxes: 0, entered: 0, mailbox: 0, primMark: new Uint8Array(ntris || 1), nodeMark: {},
            cells: [], missed: [] };
  for (var i = 0; i < k && i < trav.length; ++i) {
    var e = trav[i], known = e.node !== null && e.node !== undefined && (e.node in nodeBox), inTree = hasTree && known;
    switch (e.type) {
    case 'node_enter':
      r.current = e.node;
      r.box = e.box6 || (known ? nodeBox[e.node] : null);
      r.tn = num(e.t_near); r.tf = num(e.t_far);
      r.entered++;
      if (inTree) r.nodeMark[e.node] = 1;
      else if (keepCells && e.box6) r.cells.push(e.box6);
      break;
    case 'box_test':
      r.boxes++;
      if (inTree && r.nodeMark[e.node] !== 1) r.nodeMark[e.node] = e.result === 1 ? 3 : 2;
      else if (keepCells && !inTree && e.result !== 1 && e.bounds) r.missed.push(boxOf(e.bounds));
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
  /* A triangle test that hits at the current step is the best hit already: the structure
     records it as the closest hit in the very next event, so the panel does not say "none
     yet" beside the highlighted "prim 6 test: hit". */
  var last = k >= 1 && k <= trav.length ? trav[k - 1] : null, next = k < trav.length ? trav[k] : null;
  if (last && next && last.type === 'prim_test' && last.result === 1 && next.type === 'hit_update' &&
      next.prim === last.prim) {
    r.best = next.prim; r.bestT = num(next.t);
  }
  return r;
}

/* ---- drawing helpers (c: a canvas's 2D context) --------------------------------------- */
var PAL = [[31, 119, 180], [255, 127, 14], [44, 160, 44], [214, 39, 40], [148, 103, 189], [140, 86, 75],
           [227, 119, 194], [23, 190, 207]];
function depthColor(d, a) { var c = PAL[d % 8]; return 'rgba(' + c[0] + ',' + c[1] + ',' + c[2] + ',' + a + ')'; }
function line(c, x0, y0, x1, y1, w, col, dash) {
  c.beginPath(); c.lineWidth = w; c.strokeStyle = col; c.setLineDash(dash ? [4, 4] : []);
  c.moveTo(x0, y0); c.lineTo(x1, y1); c.stroke(); c.setLineDash([]);
}
function disc(c, x, y, r, col) { c.beginPath(); c.fillStyle = col; c.arc(x, y, r, 0, 2 * Math.PI); c.fill(); }

/* The ray's point at t, and where it leaves the padded scene box b (for drawing it). */
function at(ray, t) { return [ray[0] + t * ray[3], ray[1] + t * ray[4], ray[2] + t * ray[5]]; }
function rayEnd(b, ray) {
  var e = 0.5 * ((b.max[0] - b.min[0]) + (b.max[1] - b.min[1]) + (b.max[2] - b.min[2])) + 1;
  var tf = Infinity;
  for (var i = 0; i < 3; ++i) {
    var d = ray[3 + i]; if (d === 0) continue;
    var t1 = (b.min[i] - e - ray[i]) / d, t2 = (b.max[i] + e - ray[i]) / d;
    tf = Math.min(tf, Math.max(t1, t2));
  }
  return isFinite(tf) && tf > 0 ? tf : 1;
}

/* ---- 2D: the scene seen from +z, fitted with a 6% margin (view_render.c's make_map) --- */
function makeMap(b, w, h) {
  var ex = b.max[0] - b.min[0], ey = b.max[1] - b.min[1];
  if (!(ex > 0)) ex = 1;
  if (!(ey > 0)) ey = 1;
  var pad = 0.06, s = Math.min(w / (ex * (1 + 2 * pad)), h / (ey * (1 + 2 * pad)));
  var mx = 0.5 * (b.min[0] + b.max[0]), my = 0.5 * (b.min[1] + b.max[1]);
  return { s: s, ox: w * 0.5 - mx * s, oy: h * 0.5 + my * s };
}
function X(m, x) { return m.ox + x * m.s; }
function Y(m, y) { return m.oy - y * m.s; }
function rect2d(c, m, b, fill, stroke, w, dash) {
  if (boxEmpty(b)) return;
  var x0 = X(m, b.min[0]), x1 = X(m, b.max[0]), y0 = Y(m, b.max[1]), y1 = Y(m, b.min[1]);
  if (fill) { c.fillStyle = fill; c.fillRect(x0, y0, x1 - x0 + 1, y1 - y0 + 1); }
  if (stroke) {
    c.beginPath(); c.lineWidth = w; c.strokeStyle = stroke; c.setLineDash(dash ? [4, 4] : []);
    c.rect(x0 + 0.5, y0 + 0.5, x1 - x0, y1 - y0); c.stroke(); c.setLineDash([]);
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
var FILL = ['#c9d3e0', '#8fb3e8', '#5cb85c', '#c49ae8'], EDGE = ['#8792a3', '#3f6fb8', '#1e7b1e', '#7d3fb8'];
var SPINE = ['#4b5566', '#1f4f98', '#0e5b0e', '#5d1f98'];
/* The height a 2D scene's shapes are cut at for their spines: the ray's z plane, else the
 * scene's middle; NaN if the scene is not flat (z extent under 5% of x and y). */
function spineHeight(b, ray) {
  var ex = b.max[0] - b.min[0], ey = b.max[1] - b.min[1], ez = b.max[2] - b.min[2];
  if (boxEmpty(b) || !(ez > 0) || !(ez < 0.05 * Math.min(ex, ey))) return NaN;
  return ray && ray[5] === 0 ? ray[2] : 0.5 * (b.min[2] + b.max[2]);
}
/* Where triangle p crosses z = z0: the segment a ray in that plane can hit (flat2d's
 * spine, its longest median), or null. */
function spine(p, z0) {
  var q = [];
  for (var k = 0; k < 3; ++k) {
    var u = p[k], w = p[(k + 1) % 3], du = u[2] - z0, dw = w[2] - z0;
    if (du === 0) q.push([u[0], u[1]]);
    else if ((du < 0) !== (dw < 0) && dw !== 0) { var s = du / (du - dw); q.push([u[0] + s * (w[0] - u[0]), u[1] + s * (w[1] - u[1])]); }
  }
  return q.length === 2 && (q[0][0] !== q[1][0] || q[0][1] !== q[1][1]) ? q : null;
}
/* The mesh's triangles seen from +z (the marked ones, or the unmarked ones); in a 2D scene
 * each with its spine at the ray's height (what a ray in the plane hits); edge-on ones as
 * thick segments. */
function triangles2d(c, m, mesh, ray, mark, markedPass) {
  var z0 = spineHeight(mesh.bounds, ray), ntris = mesh.ntris;
  for (var t = 0; t < ntris; ++t) {
    var k = mark ? mark[t] : 0;
    if ((k !== 0) !== markedPass) continue;
    var a = vtx(mesh, t, 0), b = vtx(mesh, t, 1), q = vtx(mesh, t, 2);
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
/* The tree as far as the first k build events b made it: each node's box in its depth's
 * colour, each BSP plane (boxAt(e): a BUILD_NODE event's box). */
function buildUpTo2d(c, m, b, k, nodeBox, boxAt) {
  for (var i = 0; i < k && i < b.length; ++i) {
    var e = b[i];
    if (e[0] === 3 && e[2] < 0 && e.length > 9) plane2d(c, m, [e[7], e[8], e[9]], e[3], nodeBox[e[1]], 1, '#404040');
    if (e[0] === 1) { var d = e[3] < 0 ? 0 : e[3]; rect2d(c, m, boxAt(e), null, depthColor(d, d === 0 ? 0.8 : 0.6), 1); }
  }
}
/* The current build event e: its node's box, a split's or a candidate's plane, a leaf's
 * triangles. */
function buildStep2d(c, m, mesh, ray, e, box) {
  rect2d(c, m, box, 'rgba(255,153,0,0.25)', '#ff7f00', 3);
  if ((e[0] === 2 || e[0] === 3) && box) {
    var col = e[0] === 3 ? '#d00000' : 'rgba(208,128,0,0.75)';
    if (e[2] === 0) line(c, X(m, e[3]), Y(m, box.min[1]), X(m, e[3]), Y(m, box.max[1]), 3, col);
    else if (e[2] === 1) line(c, X(m, box.min[0]), Y(m, e[3]), X(m, box.max[0]), Y(m, e[3]), 3, col);
    else if (e[2] < 0 && e.length > 9) plane2d(c, m, [e[7], e[8], e[9]], e[3], box, 3, col);
  }
  if (e[0] === 4 && e[6]) {
    var mk = new Uint8Array(mesh.ntris || 1);
    e[6].forEach(function (p) { if (p < mesh.ntris) mk[p] = 2; });
    triangles2d(c, m, mesh, ray, mk, true);
  }
}
/* What the walk replayed in r has marked: the nodes entered, the boxes missed, the
 * triangles tested, the current cell. */
function walkMarks2d(c, m, mesh, ray, r, nodeBox) {
  for (var id in r.nodeMark) {
    if (r.nodeMark[id] === 1) rect2d(c, m, nodeBox[id], null, '#e0b000', 2);
    else if (r.nodeMark[id] === 2) rect2d(c, m, nodeBox[id], null, '#d02020', 1, true);
  }
  r.cells.forEach(function (b) { rect2d(c, m, b, null, '#e0b000', 2); });
  r.missed.forEach(function (b) { rect2d(c, m, b, null, '#d02020', 1, true); });
  triangles2d(c, m, mesh, ray, r.primMark, true);
  if (r.box) rect2d(c, m, r.box, 'rgba(255,153,0,0.31)', '#ff7f00', 3);
}
/* The ray across the scene box b, the current interval on it, its origin and its best hit. */
function drawRay2d(c, m, b, ray, r) {
  var q = at(ray, rayEnd(b, ray));
  line(c, X(m, ray[0]), Y(m, ray[1]), X(m, q[0]), Y(m, q[1]), 2, '#a01010');
  if (isFinite(r.tn) && isFinite(r.tf)) {
    var p0 = at(ray, r.tn), p1 = at(ray, r.tf);
    line(c, X(m, p0[0]), Y(m, p0[1]), X(m, p1[0]), Y(m, p1[1]), 6, 'rgba(255,127,0,0.75)');
  }
  disc(c, X(m, ray[0]), Y(m, ray[1]), 5, '#a01010');
  if (r.best !== null && isFinite(r.bestT)) {
    var hp = at(ray, r.bestT);
    disc(c, X(m, hp[0]), Y(m, hp[1]), 7, '#000'); disc(c, X(m, hp[0]), Y(m, hp[1]), 5, '#ff2020');
    c.fillStyle = '#000'; c.font = '12px monospace';
    c.fillText('t=' + g(r.bestT), X(m, hp[0]) + 9, Y(m, hp[1]) - 8);
  }
}

/* ---- 3D: a pinhole camera around the scene (view_render.c's make_camera) ------------ */
function sub(a, b) { return [a[0] - b[0], a[1] - b[1], a[2] - b[2]]; }
function dot(a, b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
function cross(a, b) { return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]; }
function norm(a) { var l = Math.hypot(a[0], a[1], a[2]); return l > 0 ? [a[0] / l, a[1] / l, a[2] / l] : a; }
/* The camera around scene box b at v.yaw, v.pitch, v.zoom for a w x h view. */
function camera(b, v, w, h) {
  var tgt = [0.5 * (b.min[0] + b.max[0]), 0.5 * (b.min[1] + b.max[1]), 0.5 * (b.min[2] + b.max[2])];
  var rad = 0.5 * Math.hypot(b.max[0] - b.min[0], b.max[1] - b.min[1], b.max[2] - b.min[2]);
  if (!(rad > 0)) rad = 1;
  var dist = rad * 2.4 / Math.max(v.zoom, 0.05), cp = Math.cos(v.pitch), sp = Math.sin(v.pitch);
  var eye = [tgt[0] + dist * cp * Math.sin(v.yaw), tgt[1] + dist * sp, tgt[2] + dist * cp * Math.cos(v.yaw)];
  var fwd = norm(sub(tgt, eye)), right = cross(fwd, [0, 1, 0]);
  if (Math.hypot(right[0], right[1], right[2]) < 1e-4) right = [1, 0, 0];
  right = norm(right);
  return { eye: eye, fwd: fwd, right: right, up: cross(right, fwd), f: h * 0.5 / Math.tan(22.5 * Math.PI / 180),
           cx: w * 0.5, cy: h * 0.5 };
}
function project(cam, p) {
  var d = sub(p, cam.eye), z = dot(d, cam.fwd);
  if (z < 1e-3) return null;
  return [cam.cx + dot(d, cam.right) / z * cam.f, cam.cy - dot(d, cam.up) / z * cam.f, z];
}
var EDGES = [[0, 1], [2, 3], [4, 5], [6, 7], [0, 2], [1, 3], [4, 6], [5, 7], [0, 4], [1, 5], [2, 6], [3, 7]];
function box3d(c, cam, b, w, col) {
  if (boxEmpty(b)) return;
  var p = [];
  for (var i = 0; i < 8; ++i)
    p.push(project(cam, [i & 1 ? b.max[0] : b.min[0], i & 2 ? b.max[1] : b.min[1], i & 4 ? b.max[2] : b.min[2]]));
  EDGES.forEach(function (e) { var a = p[e[0]], q = p[e[1]]; if (a && q) line(c, a[0], a[1], q[0], q[1], w, col); });
}
/* The nodes the walk replayed in r has entered (but the current one), and the current box. */
function walkMarks3d(c, cam, r, nodeBox) {
  for (var nid in r.nodeMark) if (r.nodeMark[nid] === 1 && +nid !== r.current) box3d(c, cam, nodeBox[nid], 1, 'rgba(255,208,0,0.56)');
  if (r.box) box3d(c, cam, r.box, 3, '#ff7f00');
}
/* The ray up to its best hit (else out of scene box b) in colour col, the hit a disc. */
function drawRay3d(c, cam, b, ray, r, col, hitRadius, hitCol) {
  var tEnd = isFinite(r.bestT) ? r.bestT : rayEnd(b, ray);
  var pa = project(cam, at(ray, 1e-3)), pb = project(cam, at(ray, tEnd));
  if (pa && pb) line(c, pa[0], pa[1], pb[0], pb[1], 2, col);
  if (isFinite(r.bestT) && pb) disc(c, pb[0], pb[1], hitRadius, hitCol);
}

/* ---- the build: the SAH curve, the event lines ------------------------------------------ */
/* The SAH cost over the split position of build node `node`, from its candidate events among
 * the first k build events b, on canvas cnv with its note; s.cand_kept of s.cand_total
 * candidate events are in the page. */
function sahCurve(cnv, note, s, b, node, k) {
  /* a canvas sized by fitCanvas draws in CSS pixels (cssW x cssH), its backing store at the screen's density */
  var sx = cnv.getContext('2d'), w = cnv.cssW || cnv.width, h = cnv.cssH || cnv.height, pts = [], split = null, i;
  sx.fillStyle = '#2a2f39'; sx.fillRect(0, 0, w, h);
  $('sah-title').textContent = 'SAH cost over split position (node ' + node + ')';
  for (i = 0; i < k && i < b.length; ++i) {
    var e = b[i];
    if (e[1] !== node) continue;
    if (e[0] === 3) split = e;
    if (e[0] === 2 && isFinite(e[3]) && isFinite(e[4])) pts.push(e);
  }
  if (!pts.length) {
    sx.fillStyle = '#9aa3b0'; sx.font = '12px monospace'; sx.fillText('no candidates for this node', 8, 20);
    note.textContent = s.cand_kept < s.cand_total
      ? 'the page keeps the first ' + s.cand_kept + ' of ' + s.cand_total + ' candidate events' : '';
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
/* A build event's line, indented by depth; s: the structure {accel, nodeDepth, labels}
 * (labels, the slide's node names, may be absent). */
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

/* ---- the panel ------------------------------------------------------------------------ */
/* The event type select: the types of the n events (typeOf(i)), the one chosen before kept. */
function fillTypeSelect(n, typeOf) {
  var sel = $('evtype'), seen = {}, old = sel.value;
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
/* The build mode's lines of the info box at step k of n (b: the build events). */
function buildInfo(info, s, b, k, n) {
  info.push('<span class="hi">build step ' + k + ' / ' + n + '</span>');
  if (k > 0 && k <= n) info.push(esc(buildLine(s, b[k - 1]).trim()));
  if (s.cand_kept < s.cand_total)
    info.push('<span class="dim">SAH candidates: the first ' + s.cand_kept + ' of ' + s.cand_total + ' are in the page</span>');
}
/* The walk's lines of the info box at step k of n: the ray, the best hit, the counts. */
function walkInfo(info, ray, r, k, n, misses) {
  info.push('ray o=(' + ray.slice(0, 3).map(g).join(', ') + ')');
  info.push('    d=(' + ray.slice(3).map(g).join(', ') + ')');
  info.push('<span class="hi">step ' + k + ' / ' + n + '</span>');
  info.push(r.best !== null ? '<span class="good">best hit: prim ' + r.best + '  t=' + g(r.bestT) + '</span>'
                            : 'best hit: none' + (k >= n && misses ? ' (the ray misses)' : ' yet'));
  info.push('entered ' + r.entered + '  boxes ' + r.boxes + '  prims ' + r.prims + '  mailbox ' + r.mailbox);
}
/* The stack list, top first, each node named by name(id) (with its id as data-node where
 * dataNode is set). */
function stackList(r, name, dataNode) {
  $('stack-title').textContent = 'stack (top first): ' + (r.stack.length + r.more);
  var st = $('stack'); st.innerHTML = '';
  for (var i = r.stack.length - 1; i >= 0; --i) {
    var li = document.createElement('li');
    if (dataNode) li.dataset.node = r.stack[i].node;
    li.textContent = 'node ' + name(r.stack[i].node) + '  t=[' + g(r.stack[i].tn) + ', ' + g(r.stack[i].tf) + ']';
    st.appendChild(li);
  }
  if (r.more) { var mo = document.createElement('li'); mo.textContent = '... ' + r.more + ' more'; st.appendChild(mo); }
}
/* The 30 event lines around step k of n (text(j): event j's line), the current one marked,
 * event `part` marked as where two walks part; into the element with id `into` (default
 * "events"). */
function eventLines(k, n, text, part, into) {
  var lines = 30, first = Math.max(0, Math.min(k - 1 - (lines >> 1), n - lines)), html = [];
  for (var j = first; j < first + lines && j < n; ++j)
    html.push('<div data-i="' + j + '" class="' + (j === k - 1 ? 'cur' : j < k - 1 ? 'past' : 'future') +
              (j === part ? ' part' : '') + '">' + ('    ' + (j + 1)).slice(-5) + ' ' + esc(text(j)) + '</div>');
  $(into || 'events').innerHTML = html.join('');
}

/* Sizes canvas cnv to w x h CSS pixels with a backing store of devicePixelRatio times as
 * many (sharp on a HiDPI screen and under browser zoom) and returns its context scaled so
 * that drawing is in CSS pixels; cnv.cssW, cnv.cssH keep the CSS size. */
function fitCanvas(cnv, w, h) {
  var d = window.devicePixelRatio || 1, bw = Math.max(1, Math.round(w * d)), bh = Math.max(1, Math.round(h * d));
  if (cnv.width !== bw || cnv.height !== bh) { cnv.width = bw; cnv.height = bh; }
  cnv.cssW = w; cnv.cssH = h;
  var c = cnv.getContext('2d');
  c.setTransform(bw / w, 0, 0, bh / h, 0, 0);
  return c;
}
/* 1 where element t takes typed text (the stepper's keys leave it alone): a text or number
 * field, a text area, an editable element.  A select, a checkbox, a button or the canvas
 * do not: the keys step the walk whatever else has the focus. */
function isTextEntry(t) {
  if (!t || !t.tagName) return false;
  if (t.isContentEditable || t.tagName === 'TEXTAREA') return true;
  if (t.tagName !== 'INPUT') return false;
  return ['text', 'number', 'search', 'email', 'url', 'tel', 'password', ''].indexOf(String(t.type || '').toLowerCase()) >= 0;
}

/* ---- the stepper's buttons and keys --------------------------------------------------- */
/* p: the page's go(k), cur(), count(), play(), nextOfType(dir), setMode(m), level(dir) (the
 * 3D level up or down) and keys, its own further keys {key: function}, which come before
 * the common ones.  The keys are taken in the capture phase, before a focused select or
 * checkbox acts on them (an arrow key would change the select's choice): they reach the
 * stepper whatever has the focus, except a text field being edited. */
function bindStepper(p) {
  $('m-2d').onclick = function () { p.setMode('2d'); };
  $('m-build').onclick = function () { p.setMode('build'); };
  $('m-3d').onclick = function () { p.setMode('3d'); };
  $('b-first').onclick = function () { p.go(0); };
  $('b-prev').onclick = function () { p.go(p.cur() - 1); };
  $('b-next').onclick = function () { p.go(p.cur() + 1); };
  $('b-last').onclick = function () { p.go(p.count()); };
  $('b-play').onclick = p.play;
  $('b-jump').onclick = function () { p.go(parseInt($('jump').value, 10) || 0); };
  $('jump').onkeydown = function (e) { if (e.key === 'Enter') { p.go(parseInt($('jump').value, 10) || 0); $('jump').blur(); } };
  $('b-nexttype').onclick = function () { p.nextOfType(1); };
  $('b-prevtype').onclick = function () { p.nextOfType(-1); };
  $('b-lvup').onclick = function () { p.level(1); };
  $('b-lvdown').onclick = function () { p.level(-1); };
  $('events').onclick = function (e) { var d = e.target.closest('div[data-i]'); if (d) p.go(+d.dataset.i + 1); };
  var spaceTaken = false;
  document.addEventListener('keydown', function (e) {
    if (isTextEntry(e.target) || e.ctrlKey || e.metaKey || e.altKey) return;
    var k = e.key;
    if (Object.prototype.hasOwnProperty.call(p.keys, k)) p.keys[k]();
    else if (k === 'ArrowRight' || k === 'n') p.go(p.cur() + 1);
    else if (k === 'ArrowLeft' || k === 'p') p.go(p.cur() - 1);
    else if (k === 'Home') p.go(0);
    else if (k === 'End') p.go(p.count());
    else if (k === ' ') p.play();
    else if (k === 'g') { $('jump').focus(); $('jump').select(); }
    else if (k === 't') p.nextOfType(1);
    else if (k === 'T') p.nextOfType(-1);
    else if (k === '1') p.setMode('2d');
    else if (k === '2') p.setMode('build');
    else if (k === '3') p.setMode('3d');
    else if (k === '+' || k === '=') p.level(1);
    else if (k === '-') p.level(-1);
    else return;
    e.preventDefault();
    e.stopPropagation();
    spaceTaken = k === ' ';
  }, true);
  /* a focused button or checkbox acts on Space when the key goes up: not after the stepper took it */
  document.addEventListener('keyup', function (e) {
    if (e.key === ' ' && spaceTaken && !isTextEntry(e.target)) { e.preventDefault(); e.stopPropagation(); }
    if (e.key === ' ') spaceTaken = false;
  }, true);
}
