// lab_test.js — the lab page (build/web/sidx-lab.html) in headless Chromium.
//
//   node tests/web/lab_test.js [BUILD [WEB]]    (tests/run_web_page.sh runs it)
//   LAB_ONLY='knob|heat' node tests/web/lab_test.js    only the checks named so
//
// Drives the page through the DevTools protocol (cdp.js) with real mouse
// and keyboard events and checks what it shows against the native
// programs of the same build:
//   - a ray and step given in the address: the page's trace equals
//     `sidx-step --accel kdtree kd-slide --ray R --json` event for event;
//   - rays dragged on #view in the 2D scene kd-slide: the same, with R the
//     page's ray, each float written so that strtof gives it back exactly;
//     the page's address then opens the same walk in a new tab;
//   - the built-in teapot, a click on the 3D view: the ray through that
//     pixel traces as `sidx-step --accel bvh teapot --ray R --json`;
//   - a build knob typed into its input: the node count equals the
//     build_end count of `sidx-step --build` with the same knob;
//   - another structure picked: the trace follows it (against sidx-step);
//   - a malformed OBJ given to #obj-file: #error holds the library's
//     message and the page still traces afterwards;
//   - the page from file:// with networking off (offline, and the browser's
//     requests through a dead proxy): it starts and no request leaves it;
//   - the build mode: as many build steps as sidx-step --build's events
//     (kdtree and bvh on kd-slide), and at bvh's first split the SAH curve
//     drawn from the node's candidates, which the page asks for on entering;
//   - the heat map: 256 x 256, not empty, no error;
//   - side by side: the second structure's walk against sidx-step, the
//     counts shown for both against their traces, and the step where the
//     walks part against sidx-step --diff;
//   - keys after a dropdown choice and after a drag step the walk, the
//     dropdown keeps its choice;
//   - layout: the drawing's share of the width at 1024 x 768 under 150 %
//     zoom (>= 60 %) and in presentation mode (>= 80 %), the canvas's
//     backing store at devicePixelRatio 1.5 and 2, the keys' list, 4K;
//   - exports: PNG, SVG (parsed), the trace's JSON Lines = sidx-step --json
//     and read by sidx-step --diff, copy link;
//   - bad input (the +-3e38 OBJ, a '%' in the address, zero and
//     overflowing directions, unknown names, a camera out of range, a knob
//     that does not apply or is out of range): a message each, no script error;
//   - the heat map in a worker: keys answered while a 1024 x 1024 map
//     counts, coarse to fine, cancel; the worker's map = the page's;
//   - a long build in a worker (rayclass twice over a 20,480-triangle
//     icosphere): keys answered meanwhile, a progress bar, cancel
//     keeps the view before; a build the worker finishes (kdtree-median over
//     the teapot): its walks and a new ray as sidx-step's, l on its first
//     leaf, its build mode's limit stated; with max_depth 10 the build
//     mode's events from the worker as sidx-step --build's;
//   - the stack's t-intervals drawn along the ray (the canvas's pixels);
//     l / L and t / T in 2D, 3D and the build mode;
//   - every lesson preset against sidx-step, PageDown and PageUp;
//   - random addresses and OBJ files (tests/web/fuzz_gen.js) through the
//     page: no script error, no stuck stepper.
// Each mode's screenshot goes to WEB/screens/*.png (WEB: BUILD/web); the page's
// timings() are printed, never compared with a limit.  Every wait gives up
// after a fixed time.  Exit status: 0 all passed, 1 a check failed.
'use strict';

const cdp = require('./cdp');
const { execFileSync } = require('child_process');
const fs = require('fs');
const os = require('os');
const path = require('path');

const BUILD = process.argv[2] || process.env.BUILD || 'build';
const WEB = process.argv[3] || path.join(BUILD, 'web');
const PAGE = path.resolve(WEB, 'sidx-lab.html');
const STEP = path.resolve(BUILD, 'bin/sidx-step');
const SCREENS = path.resolve(WEB, 'screens');
const URL0 = 'file://' + PAGE;
const WAIT_MS = 20000;
// the fuzz of the page (tests/web/fuzz_gen.js): LAB_FUZZ_LINKS random addresses and
// LAB_FUZZ_FILES random OBJ files from seed LAB_FUZZ_SEED (small in make test)
const FUZZ_LINKS = Number(process.env.LAB_FUZZ_LINKS || 80);
const FUZZ_FILES = Number(process.env.LAB_FUZZ_FILES || 30);
const FUZZ_SEED = Number(process.env.LAB_FUZZ_SEED || 1);

let failures = 0;
function ok(name) { console.log('  ok    ' + name); }
function bad(name, why) {
    console.log('  FAIL  ' + name + ': ' + why);
    failures++;
}

const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

// ---- the native side ------------------------------------------------------------------------

function native(args) {
    return execFileSync(STEP, args, { encoding: 'utf8', timeout: 60000, maxBuffer: 64 << 20, stdio: ['ignore', 'pipe', 'pipe'] });
}

// A float of the ray as sidx-step --ray reads it (strtof): the page's value
// rounded to float, written in the shortest form that reads back as that
// double, which strtof rounds to the same float.
function rayArg(ray) { return ray.map((v) => String(Math.fround(v))).join(','); }

function nativeTrace(accel, scene, ray, knobArgs) {
    const out = native(['--accel', accel, scene, '--ray', rayArg(ray), '--json', ...(knobArgs || [])]);
    return out.split('\n').filter((l) => l.trim()).map((l) => JSON.parse(l));
}

function nativeNodes(accel, scene, knobArgs) {
    const out = native(['--accel', accel, scene, '--build', '--json', ...(knobArgs || [])]);
    const end = out.split('\n').filter((l) => l.includes('"build_end"')).map((l) => JSON.parse(l)).pop();
    if (!end) throw new Error('no build_end in sidx-step --build');
    return end.node;
}

// ---- comparing ------------------------------------------------------------------------------

const traceOnly = (evs) => evs.filter((e) => !String(e.type).startsWith('build_'));

function sameValue(a, b) { return JSON.stringify(a) === JSON.stringify(b); }

// null if the two traces agree event for event, else where they part.
function traceDiff(page, want) {
    const n = Math.max(page.length, want.length);
    for (let i = 0; i < n; ++i) {
        if (!sameValue(page[i], want[i])) {
            return `event ${i + 1} of ${page.length} (page) / ${want.length} (sidx-step):\n` +
                `        page:      ${JSON.stringify(page[i])}\n        sidx-step: ${JSON.stringify(want[i])}`;
        }
    }
    return null;
}

// The first value of key anywhere in obj (the page's stats may nest it).
function findKey(obj, key) {
    if (!obj || typeof obj !== 'object') return undefined;
    if (key in obj && typeof obj[key] !== 'object') return obj[key];
    for (const k of Object.keys(obj)) {
        const v = findKey(obj[k], key);
        if (v !== undefined) return v;
    }
    return undefined;
}

// ---- the page -------------------------------------------------------------------------------

const state = (p) => p.eval('sidxLab.state()');

// Polls the page's state until pred(state) holds; the last state, or throws.
async function until(p, what, pred, ms) {
    const t0 = Date.now();
    let s;
    for (;;) {
        s = await state(p);
        if (pred(s)) return s;
        if (Date.now() - t0 > (ms || WAIT_MS)) throw new Error(`waited ${ms || WAIT_MS} ms for ${what}; state: ${JSON.stringify(s).slice(0, 400)}`);
        await sleep(50);
    }
}

async function open(b, opts) {
    const p = await b.newPage(null, opts);
    await p.goto(URL0);
    await p.eval('sidxLab.ready', WAIT_MS);
    return p;
}

// Picks value in a <select> the way a user's choice reaches the page: the
// value set and a change event.
async function choose(p, sel, value) {
    const r = await p.eval(`(() => {
        const e = document.querySelector(${JSON.stringify(sel)});
        if (!e) return 'no ' + ${JSON.stringify(sel)};
        if (![...e.options].some((o) => o.value === ${JSON.stringify(value)}))
            return ${JSON.stringify(sel)} + ' has no option ' + ${JSON.stringify(value)} + ' (has ' + [...e.options].map((o) => o.value).join(' ') + ')';
        e.focus();
        e.value = ${JSON.stringify(value)};
        e.dispatchEvent(new Event('input', {bubbles: true}));
        e.dispatchEvent(new Event('change', {bubbles: true}));
        return '';
    })()`);
    if (r) throw new Error(r);
}

// Types text into an <input> with real key events: a triple click selects
// what is there, the text replaces it, Enter and Tab commit it.
async function typeInto(p, sel, text) {
    const bx = await p.box(sel);
    const x = bx.x + bx.w / 2, y = bx.y + bx.h / 2;
    await p.send('Input.dispatchMouseEvent', { type: 'mousePressed', x, y, button: 'left', buttons: 1, clickCount: 3 });
    await p.send('Input.dispatchMouseEvent', { type: 'mouseReleased', x, y, button: 'left', buttons: 0, clickCount: 3 });
    await p.eval(`document.querySelector(${JSON.stringify(sel)}).select && document.querySelector(${JSON.stringify(sel)}).select()`);
    await p.send('Input.insertText', { text });
    for (const key of [['Enter', 13, '\r'], ['Tab', 9, '\t']]) {
        await p.send('Input.dispatchKeyEvent', { type: 'rawKeyDown', key: key[0], code: key[0], windowsVirtualKeyCode: key[1] });
        if (key[0] === 'Enter') await p.send('Input.dispatchKeyEvent', { type: 'char', key: key[0], text: key[2] });
        await p.send('Input.dispatchKeyEvent', { type: 'keyUp', key: key[0], code: key[0], windowsVirtualKeyCode: key[1] });
    }
}

// Drags a ray on #view from fraction (fx0,fy0) of the canvas to (fx1,fy1).
async function dragRay(p, fx0, fy0, fx1, fy1) {
    const bx = await p.box('#view');
    await p.drag(bx.x + bx.w * fx0, bx.y + bx.h * fy0, bx.x + bx.w * fx1, bx.y + bx.h * fy1, 10);
}

// A key pressed and released as the keyboard sends it (Input.dispatchKeyEvent).
const KEYCODES = { ArrowLeft: ['ArrowLeft', 37], ArrowRight: ['ArrowRight', 39], Home: ['Home', 36], End: ['End', 35],
                   Escape: ['Escape', 27], p: ['KeyP', 80], '?': ['Slash', 191, 8], PageUp: ['PageUp', 33],
                   PageDown: ['PageDown', 34], l: ['KeyL', 76], L: ['KeyL', 76, 8], t: ['KeyT', 84], '1': ['Digit1', 49],
                   '2': ['Digit2', 50], '3': ['Digit3', 51] };
async function press(p, key) {
    const [code, vk, mod] = KEYCODES[key];
    const base = { key, code, windowsVirtualKeyCode: vk, modifiers: mod || 0 };
    await p.send('Input.dispatchKeyEvent', Object.assign({ type: 'rawKeyDown' }, base));
    if (key.length === 1) await p.send('Input.dispatchKeyEvent', Object.assign({ type: 'char', text: key }, base));
    await p.send('Input.dispatchKeyEvent', Object.assign({ type: 'keyUp' }, base));
}

async function shot(p, name) {
    const f = await p.screenshot(path.join(SCREENS, name + '.png'));
    console.log('        screenshot ' + path.relative(process.cwd(), f));
}

// Prints the page's timings() after what; key (rebuild, trace or heat)
// also goes into the summary printed at the end as label.
const summary = [];
async function timings(p, what, key, label) {
    const t = await p.eval('sidxLab.timings()');
    console.log(`        timings after ${what}: ${JSON.stringify(t)}`);
    if (key && t && typeof t[key] === 'number') summary.push(`${label} ${t[key].toFixed(1)} ms`);
}

// Runs one check (only those whose name matches LAB_ONLY, a regular
// expression, when it is set); a thrown error fails it with its message.
async function check(name, fn) {
    if (process.env.LAB_ONLY && !new RegExp(process.env.LAB_ONLY).test(name)) return;
    try {
        const why = await fn();
        if (why) bad(name, why);
        else ok(name);
    } catch (e) {
        bad(name, e.message);
    }
}

// The page's trace of its current ray against sidx-step's.
async function compareTrace(p, s, scenePath) {
    const want = traceOnly(nativeTrace(s.accel, scenePath || s.scene, s.ray, knobArgs(s.knobs)));
    const got = traceOnly(s.events || []);
    const d = traceDiff(got, want);
    if (d) return `ray ${rayArg(s.ray)}: ${d}`;
    console.log(`        ${s.accel} on ${s.scene}, ray ${rayArg(s.ray)}: ${got.length} events agree` +
        ` (${got.filter((e) => e.type === 'prim_test').length} triangle tests, ${got.some((e) => e.type === 'hit_update') ? 'a hit' : 'no hit'})`);
    return null;
}

// The page's knobs as sidx-step flags (only those the page has set away
// from the default 0 / off).
function knobArgs(k) {
    const a = [];
    if (!k) return a;
    const num = { bins: '--bins', c_trav: '--c-trav', c_tri: '--c-tri', leaf_size: '--leaf-size', max_depth: '--max-depth', lambda: '--lambda', empty_bonus: '--empty-bonus', optimize: '--optimize' };
    for (const [key, flag] of Object.entries(num)) {
        if (k[key] !== undefined && k[key] !== null && Number(k[key]) !== 0) a.push(flag, String(k[key]));
    }
    if (k.mailbox === false || k.mailbox === 0) a.push('--no-mailbox');
    return a;
}

// ---- the checks -----------------------------------------------------------------------------

async function main() {
    // every request through a dead proxy: nothing can leave the browser (the offline check
    // below; the page needs no network anywhere)
    const b = await cdp.launch({ timeoutMs: WAIT_MS, lifeMs: 540000, proxy: '127.0.0.1:9' });
    try {
        // a tab with the network emulated offline as well: the page must start from file:// alone
        await check('offline: the page starts from file:// and asks the network for nothing', async () => {
            const p2 = await open(b, { offline: true });
            const s = await state(p2);
            await shot(p2, 'offline');
            await p2.send('Target.closeTarget', { targetId: p2.targetId }).catch(() => null);
            if (s.error) return 'error: ' + s.error;
            const out = p2.requests.filter((u) => !/^(file|data|blob|about):/.test(u));
            if (out.length) return 'requests: ' + out.join(' ');
            console.log(`        requests: ${p2.requests.length} (${[...new Set(p2.requests.map((u) => u.split(':')[0]))].join(', ')})`);
            return null;
        });

        const p = await open(b);
        const s0 = await state(p);
        if (s0.error) bad('page starts', 'error at start: ' + s0.error);
        if (p.exceptions.length) bad('page starts', 'script errors: ' + p.exceptions.join('; '));

        await check('address: a ray and step given in the URL trace as sidx-step does', async () => {
            const ray = [0, 4.2, 0, 1, 0.15, 0];
            const p2 = await b.newPage(null);
            await p2.goto(URL0 + '#scene=kd-slide&accel=kdtree&ray=' + ray.join(',') + '&step=5');
            await p2.eval('sidxLab.ready', WAIT_MS);
            const s = await state(p2);
            await p2.send('Target.closeTarget', { targetId: p2.targetId }).catch(() => null);
            if (s.scene !== 'kd-slide' || s.accel !== 'kdtree') return `the page opened ${s.scene} with ${s.accel}`;
            if (!sameValue(s.ray, ray.map(Math.fround))) return `the page traces ${s.ray}, the address says ${ray}`;
            if (s.step !== 5) return `the page is at step ${s.step}, the address says 5`;
            return compareTrace(p2, s);
        });

        await check('2D: a dragged ray on kd-slide traces as sidx-step does', async () => {
            await choose(p, '#scene', 'kd-slide');
            await choose(p, '#accel', 'kdtree');
            await until(p, 'kd-slide with kdtree', (s) => s.scene === 'kd-slide' && s.accel === 'kdtree');
            await shot(p, '2d-kd-slide');
            const drags = [[0.05, 0.5, 0.95, 0.45], [0.1, 0.15, 0.9, 0.85], [0.5, 0.95, 0.45, 0.05]];
            let prev = JSON.stringify((await state(p)).ray);
            let hits = 0;
            for (const d of drags) {
                await dragRay(p, ...d);
                const s = await until(p, 'a new ray after the drag', (x) => JSON.stringify(x.ray) !== prev);
                prev = JSON.stringify(s.ray);
                if (s.ray[2] !== 0 || s.ray[5] !== 0) return `a 2D ray leaves the plane z = 0: ${s.ray}`;
                const why = await compareTrace(p, s);
                if (why) return why;
                if (traceOnly(s.events).some((e) => e.type === 'hit_update')) ++hits;
            }
            await timings(p, 'a dragged ray', 'trace', 'trace of a dragged ray (kd-slide, kdtree, drawn)');
            await shot(p, '2d-dragged-ray');
            // the address keeps the state: the same link in a new tab shows the same walk
            const href = await p.eval('location.href');
            const s1 = await state(p);
            const p3 = await b.newPage(null);
            await p3.goto(href);
            await p3.eval('sidxLab.ready', WAIT_MS);
            const s3 = await state(p3);
            await p3.send('Target.closeTarget', { targetId: p3.targetId }).catch(() => null);
            for (const k of ['scene', 'accel', 'ray', 'step', 'events']) {
                if (!sameValue(s3[k], s1[k])) return `the link ${href} opens with another ${k}: ${JSON.stringify(s3[k]).slice(0, 200)}`;
            }
            return hits ? null : 'none of the dragged rays hit a shape: the drags test too little';
        });

        // The built-in teapot: its floats are the same in the module and in
        // sidx-step (lib/scenes.c computes its own sines).
        await check('3D: a click on the built-in teapot traces as sidx-step --accel bvh teapot does', async () => {
            await choose(p, '#scene', 'teapot');
            await choose(p, '#accel', 'bvh');
            let s = await until(p, 'teapot with bvh', (x) => x.scene === 'teapot' && x.accel === 'bvh');
            if (s.mode !== '3d') {
                const b3 = await p.box('#m-3d');
                await p.click(b3.x + b3.w / 2, b3.y + b3.h / 2);
                s = await until(p, 'teapot in 3D', (x) => x.mode === '3d');
            }
            if (s.error) return 'error: ' + s.error;
            const before = JSON.stringify(s.ray);
            const bx = await p.box('#view');
            await p.click(bx.x + bx.w * 0.52, bx.y + bx.h * 0.48);
            s = await until(p, 'a new ray after the click', (x) => JSON.stringify(x.ray) !== before);
            const why = await compareTrace(p, s);
            if (why) return why;
            if (!traceOnly(s.events).some((e) => e.type === 'hit_update')) return 'the click in the middle of the view missed the teapot';
            await timings(p, 'a clicked ray on teapot', 'trace', 'trace of a clicked ray (teapot, bvh, drawn)');
            await shot(p, '3d-teapot-clicked-ray');
            return null;
        });

        await check('knob: max_depth typed in rebuilds the kd-tree with the native node count', async () => {
            await choose(p, '#scene', 'teapot');
            await choose(p, '#accel', 'kdtree');
            await until(p, 'teapot with kdtree', (s) => s.scene === 'teapot' && s.accel === 'kdtree');
            for (const depth of ['3', '8']) {
                await typeInto(p, '#knob-max_depth', depth);
                const s = await until(p, 'max_depth ' + depth, (x) => String(x.knobs && x.knobs.max_depth) === depth);
                const want = nativeNodes('kdtree', 'teapot', knobArgs(s.knobs));
                const got = await until(p, 'a node count', (x) => findKey(x.stats, 'nodes') !== undefined)
                    .then((x) => findKey(x.stats, 'nodes'));
                if (got !== want) return `max_depth ${depth}: the page shows ${got} nodes, sidx-step --build ${want}`;
                console.log(`        kdtree on teapot, max_depth ${depth}: ${got} nodes on both (stats ${JSON.stringify(s.stats).slice(0, 200)})`);
                await timings(p, 'rebuilding teapot, max_depth ' + depth, 'rebuild', 'rebuild teapot kdtree max_depth ' + depth);
            }
            await shot(p, 'knob-max-depth');
            return null;
        });

        await check('knob: defaults, then leaf_size typed in rebuilds the BVH with the native node count', async () => {
            await choose(p, '#scene', 'teapot');
            await choose(p, '#accel', 'bvh');
            await until(p, 'teapot with bvh', (s) => s.scene === 'teapot' && s.accel === 'bvh');
            const r = await p.box('#knob-reset');
            await p.click(r.x + r.w / 2, r.y + r.h / 2);
            await until(p, 'the knobs back to their defaults', (x) => Object.keys(x.knobs || {}).length === 0);
            for (const leaf of ['1', '16']) {
                await typeInto(p, '#knob-leaf_size', leaf);
                const s = await until(p, 'leaf_size ' + leaf, (x) => String(x.knobs && x.knobs.leaf_size) === leaf);
                const want = nativeNodes('bvh', 'teapot', knobArgs(s.knobs));
                const got = findKey(s.stats, 'nodes');
                if (got !== want) return `leaf_size ${leaf}: the page shows ${got} nodes, sidx-step --build ${want}`;
                console.log(`        bvh on teapot, knobs ${JSON.stringify(s.knobs)}: ${got} nodes on both`);
                await timings(p, 'rebuilding teapot, bvh leaf_size ' + leaf, 'rebuild', 'rebuild teapot bvh leaf_size ' + leaf);
            }
            return null;
        });

        await check('structures: each picked structure traces kd-slide as sidx-step does', async () => {
            await choose(p, '#scene', 'kd-slide');
            const s0 = await until(p, 'kd-slide', (s) => s.scene === 'kd-slide');
            const names = await p.eval(`[...document.querySelector('#accel').options].map((o) => o.value)`);
            const want = ['bvh', 'kdtree', 'grid', 'quadtree', 'brute'].filter((n) => names.includes(n));
            if (want.length < 3) return `#accel on kd-slide offers only ${names.join(' ')}`;
            for (const name of want) {
                await choose(p, '#accel', name);
                const s = await until(p, name, (x) => x.accel === name && x.scene === 'kd-slide');
                if (!sameValue(s.ray, s0.ray)) return `picking ${name} changed the ray`;
                const why = await compareTrace(p, s);
                if (why) return name + ': ' + why;
            }
            await timings(p, 'rebuilding kd-slide', 'rebuild', 'rebuild kd-slide ' + want[want.length - 1]);
            await shot(p, 'structures-' + want[want.length - 1]);
            return null;
        });

        await check('malformed OBJ: #error shows the library\'s message, the page goes on', async () => {
            const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'sidx-lab-'));
            const obj = path.join(dir, 'bad.obj');
            fs.writeFileSync(obj, 'v 0 0 0\nv 1 0 0\nf 1 2 7\n');
            let msg;
            try {
                native(['--accel', 'bvh', obj, '--build']);
                return 'sidx-step accepted the malformed OBJ';
            } catch (e) {
                // "sidx-step: PATH:LINE: MESSAGE": the page names the file its own way
                msg = String(e.stderr).trim().replace(/^sidx-step: /, '').replace(obj + ':', '').replace(/^\d+: /, '');
            }
            await p.setFiles('#obj-file', [obj]);
            let err = '';
            const t0 = Date.now();
            while (!err && Date.now() - t0 < WAIT_MS) {
                err = await p.eval(`document.querySelector('#error').textContent.trim()`);
                if (!err) await sleep(50);
            }
            fs.rmSync(dir, { recursive: true, force: true });
            if (!err.includes(msg)) return `#error says '${err}', the library says '${msg}'`;
            console.log(`        #error: ${err}`);
            await shot(p, 'bad-obj');
            if (p.exceptions.length) return 'script errors: ' + p.exceptions.join('; ');
            await choose(p, '#scene', 'kd-slide');
            await choose(p, '#accel', 'kdtree');
            const before = JSON.stringify((await state(p)).ray);
            await dragRay(p, 0.05, 0.3, 0.95, 0.6);
            const s = await until(p, 'a ray after the bad file', (x) => x.scene === 'kd-slide' && JSON.stringify(x.ray) !== before);
            return compareTrace(p, s);
        });

        await check('build mode: a click on #m-build steps through sidx-step --build\'s events', async () => {
            await choose(p, '#scene', 'kd-slide');
            await choose(p, '#accel', 'kdtree');
            await until(p, 'kd-slide with kdtree', (x) => x.scene === 'kd-slide' && x.accel === 'kdtree');
            const m = await p.box('#m-build');
            await p.click(m.x + m.w / 2, m.y + m.h / 2);
            const s = await until(p, 'mode build', (x) => x.mode === 'build');
            const want = native(['--accel', 'kdtree', 'kd-slide', '--build', '--json', ...knobArgs(s.knobs)])
                .split('\n').filter((l) => l.includes('"type":"build_')).length;
            // the address holds the build step: the whole build at first, then one back
            const bstep = async () => Number((/[#&]bstep=(\d+)/.exec(await p.eval('location.hash')) || [])[1]);
            let got = await bstep();
            if (got !== want) return `the build mode shows ${got} build steps, sidx-step --build prints ${want} events`;
            await p.send('Input.dispatchKeyEvent', { type: 'rawKeyDown', key: 'ArrowLeft', code: 'ArrowLeft', windowsVirtualKeyCode: 37 });
            await p.send('Input.dispatchKeyEvent', { type: 'keyUp', key: 'ArrowLeft', code: 'ArrowLeft', windowsVirtualKeyCode: 37 });
            const t0 = Date.now();
            while ((got = await bstep()) !== want - 1 && Date.now() - t0 < WAIT_MS) await sleep(50);
            if (got !== want - 1) return `Left in the build mode leaves the build step at ${got}, not ${want - 1}`;
            console.log(`        kdtree on kd-slide: ${want} build events, Left goes to ${got}`);
            await shot(p, 'build-mode');
            // a binned BVH proposes SAH candidates: the page asks the module for
            // them on entering the build mode; the curve of the first split's node
            // is drawn from them and the steps count them
            await choose(p, '#accel', 'bvh');
            const kr = await p.box('#knob-reset');
            await p.click(kr.x + kr.w / 2, kr.y + kr.h / 2);
            await until(p, 'kd-slide with bvh, default knobs', (x) => x.scene === 'kd-slide' && x.accel === 'bvh' &&
                        x.mode === 'build' && Object.keys(x.knobs || {}).length === 0);
            const lines = native(['--accel', 'bvh', 'kd-slide', '--build', '--json'])
                .split('\n').filter((l) => l.includes('"type":"build_')).map((l) => JSON.parse(l));
            let t1 = Date.now();
            while ((got = await bstep()) !== lines.length && Date.now() - t1 < WAIT_MS) await sleep(50);
            if (got !== lines.length) return `bvh: the build mode shows ${got} build steps, sidx-step --build prints ${lines.length} events`;
            const split = lines.findIndex((e) => e.type === 'build_split');
            const cands = split < 0 ? 0 : lines.filter((e) => e.type === 'build_candidate' && e.node === lines[split].node).length;
            if (cands < 2) return `bvh on kd-slide: sidx-step --build gives the first split's node ${cands} candidates`;
            const h = await p.eval('location.hash');
            await p.eval(`location.hash = ${JSON.stringify(h.replace(/bstep=\d+/, 'bstep=' + (split + 1)))}`);
            t1 = Date.now();
            let note = '';
            while (((got = await bstep()) !== split + 1 || !/^pos /.test(note = await p.eval("document.getElementById('sah-note').textContent"))) &&
                   Date.now() - t1 < WAIT_MS) await sleep(50);
            if (got !== split + 1 || !/^pos /.test(note)) return `bvh: at build step ${split + 1} (a split) the SAH curve says '${note}', not its candidates`;
            console.log(`        bvh on kd-slide: ${lines.length} build events; step ${split + 1} splits node ${lines[split].node}, its curve from ${cands} candidates: ${note}`);
            await shot(p, 'build-mode-sah');
            await timings(p, 'the build mode of bvh on kd-slide', 'rebuild', 'rebuild kd-slide bvh in build mode');
            const b2 = await p.box('#m-2d');
            await p.click(b2.x + b2.w / 2, b2.y + b2.h / 2);
            await until(p, 'mode 2d', (x) => x.mode === '2d');
            return null;
        });

        await check('heat map: drawn for teapot without an error', async () => {
            await choose(p, '#scene', 'teapot');
            await choose(p, '#accel', 'bvh');
            await until(p, 'teapot', (s) => s.scene === 'teapot' && s.accel === 'bvh');
            const kind = await p.eval(`(() => { const e = document.querySelector('#heatmap'); return e ? e.tagName + ':' + (e.type || '') : ''; })()`);
            if (!kind) return 'no #heatmap in the page';
            if (!kind.startsWith('CANVAS')) {
                const bx = await p.box('#heatmap');
                await p.click(bx.x + bx.w / 2, bx.y + bx.h / 2);
            }
            const t0 = Date.now();
            let t;
            do {
                t = await p.eval('sidxLab.timings()');
                if (t && typeof t.heat === 'number' && t.heat > 0) break;
                await sleep(100);
            } while (Date.now() - t0 < WAIT_MS);
            const s = await state(p);
            if (s.error) return 'error: ' + s.error;
            if (s.mode !== 'heat') return `the page is in mode ${s.mode}, not heat, after a click on #heatmap`;
            if (!s.heat || s.heat.n !== 256) return `the heat map is ${JSON.stringify(s.heat)}, not 256 x 256`;
            if (!(s.heat.max > 0)) return `the heat map is empty: ${JSON.stringify(s.heat)}`;
            console.log(`        teapot, bvh: 256 x 256 heat map, max ${s.heat.max}, mean ${s.heat.mean}`);
            await timings(p, 'the 256 x 256 heat map', 'heat', 'heat map 256x256 teapot bvh');
            await shot(p, 'heatmap');
            return null;
        });

        await check('side by side: both walks, their counts and where they part as sidx-step --diff', async () => {
            await choose(p, '#scene', 'kd-slide');
            await choose(p, '#accel', 'kdtree');
            const names = await p.eval(`[...document.querySelector('#accel2').options].map((o) => o.value)`);
            const other = ['kdtree-median', 'kdtree-middle', 'bvh'].find((n) => names.includes(n));
            if (!other) return '#accel2 offers only ' + names.join(' ');
            await choose(p, '#accel2', other);
            const s = await until(p, 'kdtree beside ' + other, (x) => x.accel === 'kdtree' && x.accel2 === other);
            if (s.error) return 'error: ' + s.error;
            let why = await compareTrace(p, s);
            if (why) return why;
            const want2 = nativeTrace(other, s.scene, s.ray, knobArgs(s.knobs));
            why = traceDiff(traceOnly(s.events2 || []), traceOnly(want2));
            if (why) return other + ': ' + why;
            // the counts shown beside each other: events of the walk
            const counts = (evs) => ({
                nodes: evs.filter((e) => e.type === 'node_enter').length,
                boxes: evs.filter((e) => e.type === 'box_test').length,
                triangles: evs.filter((e) => e.type === 'prim_test').length,
                mailbox: evs.filter((e) => e.type === 'mailbox_hit').length,
            });
            for (const [st, evs, name] of [[s.stats, s.events, 'kdtree'], [s.stats2, want2, other]]) {
                const want = counts(traceOnly(evs)), got = (st && st.walk) || {};
                for (const k of Object.keys(want)) {
                    if (got[k] !== want[k]) return `${name}: the page counts ${k} ${got[k]}, the trace has ${want[k]}`;
                }
            }
            // where they part: sidx-step --diff of the two native traces
            const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'sidx-lab-'));
            const a = path.join(dir, 'a.jsonl'), b2 = path.join(dir, 'b.jsonl');
            fs.writeFileSync(a, native(['--accel', 'kdtree', s.scene, '--ray', rayArg(s.ray), '--json']));
            fs.writeFileSync(b2, native(['--accel', other, s.scene, '--ray', rayArg(s.ray), '--json']));
            let part = -1;
            try {
                native(['--diff', a, b2]);
            } catch (e) {
                const m = /part at event (\d+)/.exec(String(e.stdout));
                if (!m) throw new Error('sidx-step --diff: ' + e.message);
                part = Number(m[1]);
            }
            fs.rmSync(dir, { recursive: true, force: true });
            if (s.part !== part) return `the page says the walks part at step ${s.part}, sidx-step --diff at ${part}`;
            console.log(`        kdtree and ${other}: counts ${JSON.stringify(s.stats.walk)} and ${JSON.stringify(s.stats2.walk)}; they part at step ${part}`);
            await shot(p, 'side-by-side');
            await choose(p, '#accel2', '');
            return null;
        });

        await check('keys: after a dropdown choice the keys step the walk and leave the dropdown alone', async () => {
            await choose(p, '#scene', 'kd-slide');
            await choose(p, '#accel', 'kdtree');
            let s = await until(p, 'kd-slide with kdtree', (x) => x.scene === 'kd-slide' && x.accel === 'kdtree');
            const focused = () => p.eval('document.activeElement ? document.activeElement.id : ""');
            if (await focused() !== 'accel') return `#accel does not have the focus after the choice (${await focused()}): the check would prove nothing`;
            const n = s.events.length;
            await press(p, 'End');
            await until(p, 'End: step ' + n, (x) => x.step === n);
            await press(p, 'ArrowLeft');
            await until(p, 'Left: step ' + (n - 1), (x) => x.step === n - 1);
            await press(p, 'Home');
            s = await until(p, 'Home: step 0', (x) => x.step === 0);
            const val = await p.eval(`document.querySelector('#accel').value`);
            if (s.accel !== 'kdtree' || val !== 'kdtree') return `the keys changed the structure to ${s.accel} (the select shows ${val})`;
            // a scene chosen, then a ray dragged: the drawing takes the focus, the keys step that walk
            await choose(p, '#scene', 'flat2d');
            s = await until(p, 'flat2d', (x) => x.scene === 'flat2d');
            const before = JSON.stringify(s.ray);
            await dragRay(p, 0.05, 0.35, 0.95, 0.6);
            s = await until(p, 'a dragged ray on flat2d', (x) => JSON.stringify(x.ray) !== before);
            if (await focused() !== 'view') return `after a drag on the drawing the focus is on #${await focused()}, not #view`;
            const k = s.step;
            await press(p, 'ArrowLeft');
            s = await until(p, 'Left after the drag: step ' + (k - 1), (x) => x.step === k - 1);
            if (s.scene !== 'flat2d' || s.mode !== '2d') return `Left after the drag left the page at ${s.scene} in ${s.mode}`;
            console.log(`        kdtree on kd-slide: End ${n}, Left ${n - 1}, Home 0 with #accel focused; flat2d: Left ${k} -> ${k - 1} after a drag`);
            return null;
        });

        await check('layout: 1024x768 at 150 % zoom, presentation mode, devicePixelRatio 2, 4K', async () => {
            await choose(p, '#scene', 'kd-slide');
            await choose(p, '#accel', 'kdtree');
            await until(p, 'kd-slide with kdtree', (x) => x.scene === 'kd-slide' && x.accel === 'kdtree');
            const metrics = (w, h, d) => p.send('Emulation.setDeviceMetricsOverride', { width: w, height: h, deviceScaleFactor: d, mobile: false });
            const measure = () => p.eval(`(() => { const v = document.getElementById('view'), r = v.getBoundingClientRect();
                return { w: r.width, h: r.height, iw: innerWidth, bw: v.width, bh: v.height, dpr: devicePixelRatio }; })()`);
            const settle = async (what, pred) => {
                const t0 = Date.now();
                let m;
                while (!pred(m = await measure())) {
                    if (Date.now() - t0 > WAIT_MS) throw new Error(`waited for ${what}: ${JSON.stringify(m)}`);
                    await sleep(50);
                }
                return m;
            };
            const sharp = (m, d) => m.bw === Math.round(m.w * d) && m.bh === Math.round(m.h * d);
            const figures = [];
            try {
                // 1024 x 768 at 150 %: 683 x 512 CSS pixels at a device pixel ratio of 1.5
                await metrics(683, 512, 1.5);
                let m = await settle('683 x 512 at 1.5', (x) => x.iw === 683 && x.dpr === 1.5 && sharp(x, 1.5));
                figures.push(`150 %: drawing ${m.w} of ${m.iw} px (${(100 * m.w / m.iw).toFixed(0)} %), canvas ${m.bw} x ${m.bh}`);
                if (m.w < 0.6 * m.iw) return `at 1024 x 768 and 150 % the drawing is ${m.w} of ${m.iw} CSS pixels, under 60 %`;
                await shot(p, 'layout-1024x768-zoom150');
                await press(p, 'p');
                await until(p, 'presentation mode', (x) => x.present === true);
                m = await settle('the presentation layout', (x) => x.w > 0.79 * x.iw && sharp(x, 1.5));
                figures.push(`presentation: ${m.w} of ${m.iw} px (${(100 * m.w / m.iw).toFixed(0)} %)`);
                if (m.w < 0.8 * m.iw) return `in presentation mode the drawing is ${m.w} of ${m.iw} CSS pixels, under 80 %`;
                if (!/present=1/.test(await p.eval('location.hash'))) return 'the address does not keep presentation mode';
                await shot(p, 'layout-1024x768-zoom150-present');
                await press(p, '?');
                const keys = await p.eval(`(() => { const k = document.getElementById('keys'), r = k.getBoundingClientRect();
                    return { shown: getComputedStyle(k).display !== 'none', top: r.top, bottom: r.bottom, text: k.textContent }; })()`);
                if (!keys.shown || keys.top < 0 || keys.bottom > 512 || !/Right \/ Left/.test(keys.text)) return `? does not show the keys over the drawing: ${JSON.stringify(keys).slice(0, 200)}`;
                await shot(p, 'layout-keys');
                await press(p, 'Escape');
                await press(p, 'p');
                await until(p, 'presentation mode left', (x) => x.present === false);
                // a HiDPI screen: the backing store at twice the CSS size
                await metrics(800, 600, 2);
                m = await settle('800 x 600 at 2', (x) => x.iw === 800 && x.dpr === 2 && sharp(x, 2));
                figures.push(`dpr 2: canvas ${m.bw} x ${m.bh} for ${m.w} x ${m.h} CSS px`);
                // 4K: 3840 x 2160 device pixels at 200 %
                await metrics(1920, 1080, 2);
                await settle('1920 x 1080 at 2', (x) => x.iw === 1920 && sharp(x, 2));
                await shot(p, 'layout-4k');
            } finally {
                await metrics(1280, 900, 1);
                await settle('1280 x 900', (x) => x.iw === 1280 && sharp(x, 1)).catch(() => null);
            }
            console.log('        ' + figures.join('; '));
            return null;
        });

        await check('export: PNG and SVG of the view, the trace as JSON Lines for sidx-step --diff, copy link', async () => {
            await choose(p, '#scene', 'kd-slide');
            await choose(p, '#accel', 'kdtree');
            const s = await until(p, 'kd-slide with kdtree', (x) => x.scene === 'kd-slide' && x.accel === 'kdtree' && x.events.length > 3);
            const png = Buffer.from((await p.eval('sidxLab.png()')).replace(/^data:image\/png;base64,/, ''), 'base64');
            const size = await p.eval(`[document.getElementById('view').width, document.getElementById('view').height]`);
            if (png.length < 2000 || png.toString('latin1', 1, 4) !== 'PNG' || png.readUInt32BE(16) !== size[0] || png.readUInt32BE(20) !== size[1])
                return `the PNG is ${png.length} bytes, ${png.readUInt32BE(16)} x ${png.readUInt32BE(20)}, the canvas ${size}`;
            const svg = await p.eval('sidxLab.svg()');
            const parsed = await p.eval(`(() => { const d = new DOMParser().parseFromString(${JSON.stringify(svg)}, 'image/svg+xml');
                const e = d.querySelector('parsererror');
                return { error: e ? e.textContent : '', root: d.documentElement.nodeName, paths: d.querySelectorAll('path').length,
                         text: [...d.querySelectorAll('text')].map((t) => t.textContent).join('|') }; })()`);
            if (parsed.error || parsed.root !== 'svg' || parsed.paths < 20 || !parsed.text.includes('2D: kdtree'))
                return `the SVG does not parse as a drawing: ${JSON.stringify(parsed).slice(0, 300)}`;
            fs.mkdirSync(SCREENS, { recursive: true });
            fs.writeFileSync(path.join(SCREENS, 'export.svg'), svg);
            fs.writeFileSync(path.join(SCREENS, 'export.png'), png);
            // the trace as sidx-step --json writes it, line for line, and sidx-step --diff reads it
            const jsonl = await p.eval('sidxLab.jsonl()');
            const want = native(['--accel', 'kdtree', 'kd-slide', '--ray', rayArg(s.ray), '--json']);
            if (jsonl !== want) {
                const a = jsonl.split('\n'), b2 = want.split('\n'), i = a.findIndex((l, j) => l !== b2[j]);
                return `the JSON Lines differ from sidx-step --json at line ${i + 1}:\n        page: ${a[i]}\n        sidx-step: ${b2[i]}`;
            }
            const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'sidx-lab-'));
            fs.writeFileSync(path.join(dir, 'page.jsonl'), jsonl);
            fs.writeFileSync(path.join(dir, 'step.jsonl'), want);
            const diff = native(['--diff', path.join(dir, 'page.jsonl'), path.join(dir, 'step.jsonl')]);
            fs.rmSync(dir, { recursive: true, force: true });
            const bl = await p.box('#b-link');
            await p.click(bl.x + bl.w / 2, bl.y + bl.h / 2);
            const n = await until(p, 'a note about the link', (x) => x.notes.some((t) => /^link/.test(t)));
            console.log(`        PNG ${png.length} bytes ${size[0]} x ${size[1]}; SVG ${svg.length} bytes, ${parsed.paths} paths; ` +
                `JSON Lines ${jsonl.split('\n').length - 1} events = sidx-step --json; --diff: ${diff.trim().split('\n').pop()}; ${n.notes.filter((t) => /^link/.test(t))[0].slice(0, 60)}`);
            return null;
        });

        await check('2D: past 8,000 tested triangles one in k is drawn, and the drawing says so', async () => {
            // brute force over 12,000 flat triangles tests them all: one in 2 drawn, every hit kept
            await p.eval(`sidxLab.openLink('#scene=flat2d:12000&accel=brute&mode=2d')`);
            let s = await until(p, 'brute over flat2d:12000', (x) => !x.job && !x.tracing && x.accel === 'brute' && x.mode === '2d' && x.count > 0, 60000);
            const fill = '#8fb3e8';   // a tested triangle's fill (page_common.js FILL[1], the key's 'prim tested')
            const count = (svg) => svg.split(`fill="${fill}"`).length - 1;
            let svg = await p.eval('sidxLab.svg()');
            const note = /(\d+) triangles tested so far: one in (\d+) drawn/.exec(svg), drawn = count(svg);
            if (!note || note[1] !== '12000' || note[2] !== '2') return `the drawing says ${note ? note[0] : 'nothing of the tested triangles'}`;
            if (drawn < 5000 || drawn > 6000) return `${drawn} tested triangles drawn of 12,000 (one in 2 wanted)`;
            // under the limit: every tested triangle drawn, no note
            await p.eval(`sidxLab.openLink('#scene=flat2d:2000&accel=brute&mode=2d')`);
            s = await until(p, 'brute over flat2d:2000', (x) => !x.job && !x.tracing && x.scene === 'flat2d:2000' && x.count > 0, 60000);
            svg = await p.eval('sidxLab.svg()');
            if (/tested so far/.test(svg) || count(svg) < 1900) return `flat2d:2000: ${count(svg)} tested triangles drawn, note ${/tested so far/.test(svg)}`;
            console.log(`        brute over flat2d:12000 in 2D: ${drawn} tested triangles drawn, '${note[0]}'; flat2d:2000: ${count(svg)} drawn, no note`);
            await p.eval(`sidxLab.openLink('#scene=kd-slide&accel=kdtree&mode=2d')`);
            return null;
        });

        await check('bad input: the +-3e38 OBJ, a % in the address, a zero direction, unknown names: a message each, no script error', async () => {
            const ex0 = p.exceptions.length;
            const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'sidx-lab-'));
            const huge = path.join(dir, 'huge.obj'), good = path.join(dir, 'good.obj');
            fs.writeFileSync(huge, 'v -3e38 -3e38 -3e38\nv 3e38 -3e38 3e38\nv 3e38 3e38 -3e38\nv -3e38 3e38 3e38\nv 0 0 3e38\nv 3e38 0 0\nf 1 2 3\nf 4 5 6\n');
            fs.writeFileSync(good, 'v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\n');
            const msgs = [];
            const load = async (file, name) => {
                const n0 = (await state(p)).loads;
                await p.setFiles('#obj-file', [file]);
                return until(p, name + ' loaded', (x) => x.loads > n0);
            };
            try {
                await choose(p, '#accel', 'bvh');
                let s = await load(huge, 'huge.obj');
                const sah = s.notes.find((t) => /SAH cost is not a finite number/.test(t));
                if (s.scene !== 'huge.obj' || !/huge\.obj/.test(s.title) || s.error || !sah || p.exceptions.length > ex0)
                    return `the +-3e38 OBJ: scene ${s.scene}, title '${s.title}', error '${s.error}', notes ${JSON.stringify(s.notes)}, script errors ${p.exceptions.slice(ex0)}`;
                msgs.push(sah);
                s = await load(good, 'good.obj');
                if (s.scene !== 'good.obj' || !/good\.obj/.test(s.title) || s.error || s.notes.length || !(s.events.length > 0))
                    return `a good file after it: scene ${s.scene}, title '${s.title}', error '${s.error}', notes ${JSON.stringify(s.notes)}`;
            } finally {
                fs.rmSync(dir, { recursive: true, force: true });
            }
            // a '%' in the address of a page opened afresh
            const p2 = await b.newPage(null);
            await p2.goto(URL0 + '#scene=kd-slide&accel=kdtree&note=100%&step=3');
            await p2.eval('sidxLab.ready', WAIT_MS);
            const s2 = await state(p2);
            const ex2 = p2.exceptions.slice();
            await p2.send('Target.closeTarget', { targetId: p2.targetId }).catch(() => null);
            const pct = s2.notes.find((t) => t.includes('100%'));
            if (!pct || ex2.length || s2.error || s2.accel !== 'kdtree' || s2.step !== 3)
                return `a % in the address: notes ${JSON.stringify(s2.notes)}, error '${s2.error}', script errors ${ex2}, step ${s2.step}`;
            msgs.push(pct);
            // links through the page's own parser: each gives its message and the rest of the view
            const cases = [
                ['scene=kd-slide&accel=kdtree&ray=1,2,0,0,0,0', /zero direction/, (x) => x.events.length > 0 && x.accel === 'kdtree'],
                ['scene=kd-slide&accel=kdtree&ray=0,4,0,1e39,0,0', /too large for a float/, (x) => x.events.length > 0],
                ['scene=kd-slide&accel=nosuch', /no structure "nosuch"/, (x) => x.accel === 'kdtree'],
                ['scene=flat2d&accel=bvh&accel2=quadtree2', /no structure "quadtree2"/, (x) => x.accel === 'bvh' && !x.accel2],
                ['scene=icosphere&accel=quadtree', /quadtree does not suit this 3D scene/, (x) => x.accel === 'bvh'],
                ['scene=Teapot&accel=bvh', /no scene "Teapot"/, (x) => x.scene === 'teapot'],
                ['scene=nosuch&accel=bvh', /no built-in scene "nosuch"/, (x) => x.scene === 'kd-slide'],
                ['scene=kd-slide&accel=kdtree&mode=3d&cam=0.5,0.3,0', /zoom outside/, (x) => x.mode === '3d'],
                ['scene=kd-slide&accel=kdtree&bins=8', /bins does not apply to kdtree/, (x) => x.accel === 'kdtree'],
            ];
            for (const [hash, want, ok2] of cases) {
                const s = await p.eval(`sidxLab.openLink(${JSON.stringify('#' + hash)})`);
                const m = s.notes.find((t) => want.test(t)) || (want.test(s.error) ? s.error : '');
                if (!m || !ok2(s) || p.exceptions.length > ex0 || s.caught.length)
                    return `#${hash}: notes ${JSON.stringify(s.notes)}, error '${s.error}', scene ${s.scene}, structure ${s.accel}, script errors ${p.exceptions.slice(ex0)} ${s.caught}`;
                msgs.push(m);
            }
            const off = await p.eval(`document.getElementById('knob-bins').disabled`);
            if (!off) return 'bins on kdtree: the knob is not greyed out';
            // a knob's message names the page's field, not the command line's flag
            const s = await p.eval(`sidxLab.openLink('#scene=kd-slide&accel=bvh&bins=1')`);
            if (!/the field "bins"/.test(s.error) || /--bins/.test(s.error)) return `bins=1 on bvh: the error says '${s.error}'`;
            msgs.push(s.error);
            await p.eval(`sidxLab.openLink('#scene=kd-slide&accel=kdtree')`);
            console.log('        messages:\n          ' + msgs.map((t) => t.slice(0, 110)).join('\n          '));
            return null;
        });

        await check('heat map in a worker: a 1024 x 1024 brute-force map refines coarse to fine, the page answers, cancel goes back', async () => {
            const n = (await p.eval(`sidxLab.openLink('#scene=teapot&accel=brute&mode=3d')`)).count;
            await p.eval(`sidxLab.openLink('#scene=teapot&accel=brute&mode=heat&heat=steps,1024'), 0`);
            // the page answers while the worker counts: a real key steps the walk; the page's own
            // measure (from the key's arrival to the walk redrawn) is held to 500 ms, the protocol's
            // round trips (a loaded machine's scheduling) are printed
            const worst = [], trips = [];
            let s = null;
            for (const key of ['Home', 'End', 'Home']) {
                const t0 = Date.now();
                await press(p, key);
                const want = new RegExp('[#&]step=' + (key === 'Home' ? 0 : n) + '(&|$)');
                while (!want.test(await p.eval('location.hash'))) {
                    if (Date.now() - t0 > 5000) return `${key} was not answered in 5 s while the heat map counts`;
                    await sleep(20);
                }
                trips.push(Date.now() - t0);
                worst.push(Math.round(await p.eval('sidxLab.timings().key')));
            }
            const t1 = Date.now();
            while (!(s = await p.eval('sidxLab.state()')).heatPartial) {
                if (Date.now() - t1 > WAIT_MS) return 'no coarse round of the heat map arrived';
                await sleep(50);
            }
            if (!s.worker || !s.heatJob || !s.heatJob.shown || s.heat) return `the heat map is not counting in a worker with a progress bar: ${JSON.stringify({ w: s.worker, j: s.heatJob, h: s.heat })}`;
            const bar = await p.eval(`getComputedStyle(document.getElementById('progress')).display`);
            if (bar === 'none') return 'no progress bar while the heat map counts';
            await shot(p, 'heat-progress');
            const bc = await p.box('#b-cancel');
            await p.click(bc.x + bc.w / 2, bc.y + bc.h / 2);
            s = await until(p, 'cancel: back to 3D', (x) => x.mode === '3d' && !x.heatJob);
            if (s.error || s.caught.length) return `after cancel: error '${s.error}' ${s.caught}`;
            if (Math.max(...worst) > 500) return `the page took ${Math.max(...worst)} ms to answer a key while the heat map counts (over 500)`;
            // a map the worker finishes equals the one the page counts in place
            await p.eval('sidxLab._heatWorkerAlways(true)');
            await p.eval(`sidxLab.openLink('#scene=kd-slide&accel=kdtree&mode=heat&heat=steps,64&cam=0.6,0.35,1')`);
            s = await until(p, 'the 64 x 64 map from the worker', (x) => x.heat && x.heat.n === 64);
            await p.eval('sidxLab._heatWorkerAlways(false)');
            const inPlace = await p.eval(`(() => { const r = sidxLab._heatInPlace(64); return { max: r.max, total: r.total }; })()`);
            if (s.heat.max !== inPlace.max || Math.abs(s.heat.mean * 64 * 64 - inPlace.total) > 1e-6)
                return `the worker's map (max ${s.heat.max}, mean ${s.heat.mean}) is not the page's (${JSON.stringify(inPlace)})`;
            console.log(`        keys answered in ${worst.join(', ')} ms (round trips ${trips.join(', ')} ms) while the 1024 x 1024 map counted; the coarse round ${s.heatPartial || 'seen'}; ` +
                `cancel back to 3D; the worker's 64 x 64 map = the page's (max ${inPlace.max}, total ${inPlace.total})`);
            await p.eval(`sidxLab.openLink('#scene=kd-slide&accel=kdtree&mode=2d')`);
            return null;
        });

        await check('heat map over 10 minutes: refused with its estimate, the 3D view kept', async () => {
            // a link to a scene over the page's limit says why it shows another
            let s = await p.eval(`sidxLab.openLink('#scene=icosphere:6&accel=bvh&mode=3d')`);
            if (s.scene !== 'kd-slide' || !/81920 triangles; the page holds at most 50000/.test(s.error) || s.caught.length)
                return `a link to icosphere:6 (81,920 triangles): scene ${s.scene}, error '${s.error}' ${s.caught}`;
            // brute force twice over icosphere:5 walks all 2 x 20,480 triangles a ray: 1024 x 1024 of them is some 14 minutes
            await p.eval(`sidxLab.openLink('#scene=icosphere:5&accel=brute&accel2=brute&mode=heat&heat=steps,1024')`);
            s = await until(p, 'the heat map refused', (x) => !x.job && !x.tracing && x.scene === 'icosphere:5' &&
                x.notes.some((t) => /^heat map 1024/.test(t)), 60000);
            const note = s.notes.find((t) => /^heat map 1024/.test(t)), min = /about (\d+) min/.exec(note);
            if (!min || +min[1] <= 10 || !/at most 10 min/.test(note)) return `the note says '${note}'`;
            if (s.mode !== '3d' || s.heatJob || s.heat || s.error || s.caught.length)
                return `after the refusal: mode ${s.mode}, heat job ${JSON.stringify(s.heatJob)}, map ${!!s.heat}, error '${s.error}' ${s.caught}`;
            console.log(`        a link to icosphere:6 says why kd-slide is shown; brute twice over icosphere:5 at 1024 x 1024: '${note.slice(0, 44)}...', back to 3D, nothing counted`);
            await p.eval(`sidxLab.openLink('#scene=kd-slide&accel=kdtree&mode=2d')`);
            return null;
        });

        await check('long build in a worker: the page answers while it builds, cancel keeps the view before', async () => {
            let s = await p.eval(`sidxLab.openLink('#scene=kd-slide&accel=kdtree&ray=0,4.2,0,1,0.15,0&step=6')`);
            const before = { events: JSON.stringify(s.events), ray: JSON.stringify(s.ray) };
            // the icosphere at detail 5 (20,480 triangles) with rayclass twice: some 7 s of building, cancelled after 1 s or so
            // the build's answer held until the check is over: cancelled however fast the machine builds
            await p.eval(`sidxLab._holdJobs(true), sidxLab.openLink('#scene=icosphere:5&accel=rayclass&accel2=rayclass'), 0`);
            s = await state(p);
            if (!s.job || s.scene !== 'kd-slide') return `no job in a worker for rayclass over icosphere:5: job ${JSON.stringify(s.job)}, scene ${s.scene}, mode ${s.mode}`;
            // the view before answers the keys meanwhile: the page's own measure, from the key's arrival to the walk redrawn
            const worst = [];
            for (const [key, want] of [['End', s.count], ['Home', 0], ['ArrowRight', 1]]) {
                await press(p, key);
                const t0 = Date.now();
                while (!new RegExp('[#&]step=' + want + '(&|$)').test(await p.eval('location.hash'))) {
                    if (Date.now() - t0 > 5000) return `${key} was not answered in 5 s while the structures build`;
                    await sleep(20);
                }
                worst.push(Math.round(await p.eval('sidxLab.timings().key')));
            }
            s = await until(p, 'the progress bar', (x) => x.job && x.job.shown);
            const bar = await p.eval(`[getComputedStyle(document.getElementById('progress')).display, document.getElementById('progress-text').textContent]`);
            if (bar[0] === 'none' || !/rayclass|icosphere/.test(bar[1])) return `the progress bar shows ${JSON.stringify(bar)}`;
            const bc = await p.box('#b-cancel');
            await p.click(bc.x + bc.w / 2, bc.y + bc.h / 2);
            s = await until(p, 'cancel', (x) => !x.job);
            await p.eval('sidxLab._holdJobs(false), 0');
            await shot(p, 'build-cancelled');
            if (s.scene !== 'kd-slide' || s.accel !== 'kdtree' || s.accel2 || s.step !== 1 || JSON.stringify(s.events) !== before.events ||
                JSON.stringify(s.ray) !== before.ray || s.error || s.caught.length || !s.notes.some((t) => /^cancelled/.test(t)))
                return `after cancel: ${s.scene} ${s.accel} ${s.accel2} step ${s.step}, error '${s.error}', notes ${JSON.stringify(s.notes)} ${s.caught}`;
            if (!/scene=kd-slide/.test(await p.eval('location.hash'))) return 'the address does not name the view kept';
            await press(p, 'End');
            s = await until(p, 'End after cancel', (x) => x.step === x.count);
            const why = await compareTrace(p, s);
            if (why) return 'after cancel: ' + why;
            if (Math.max(...worst) > 500) return `keys took ${worst.join(', ')} ms while the structures built (over 500)`;
            console.log(`        keys answered in ${worst.join(', ')} ms while rayclass built twice over icosphere:5; ` +
                `bar '${bar[1]}'; cancel kept kd-slide with kdtree`);
            return null;
        });

        await check('long build done in the worker: its walks, a new ray and the build mode as sidx-step\'s; l lands on a leaf', async () => {
            await p.eval(`sidxLab._holdJobs(false), sidxLab.openLink('#scene=teapot&accel=kdtree-median&mode=3d'), 0`);
            let s = await until(p, 'kdtree-median over the teapot from the worker', (x) => !x.job && x.accel === 'kdtree-median', 60000);
            if (!s.remote || s.error) return `remote ${s.remote}, error '${s.error}'`;
            let why = await compareTrace(p, s);
            if (why) return why;
            // a new ray: traced by the worker that holds the tree
            const ray = [-2.5, 1.2, 0.4, 1, -0.05, -0.1];
            await p.eval(`sidxLab.setRay(${JSON.stringify(ray)})`);
            s = await until(p, 'the new ray traced', (x) => !x.tracing && JSON.stringify(x.ray) === JSON.stringify(ray.map(Math.fround)));
            why = await compareTrace(p, s);
            if (why) return 'new ray: ' + why;
            // the first leaf the walk enters, by l, against the native build's leaves
            const build = native(['--accel', 'kdtree-median', 'teapot', '--build', '--json']).split('\n').filter((l) => l.includes('"build_'));
            const leaves = new Set(build.filter((l) => l.includes('"build_leaf"')).map((l) => JSON.parse(l).node));
            await press(p, 'Home');
            await until(p, 'Home', (x) => x.step === 0);
            await press(p, 'l');
            s = await until(p, 'l: a leaf', (x) => x.step > 0);
            const first = s.events.findIndex((e) => e.type === 'node_enter' && leaves.has(e.node));
            if (s.curType !== 'node_enter' || s.step !== first + 1) return `l went to step ${s.step} (${s.curLine}), the first leaf entered is step ${first + 1}`;
            const leafNode = s.events[first].node;
            // the build mode: over its limit of events, it says so
            await press(p, '2');
            s = await until(p, 'the build mode', (x) => x.mode === 'build');
            const info = await p.eval(`document.getElementById('info').textContent`);
            if (s.count !== 0 || !/build has \d+ events: the build mode replays at most \d+/.test(info)) return `the build mode of ${build.length} events: ${s.count} steps, '${info}'`;
            // with max_depth 10 (5094 build events), also built in the worker: its build mode has sidx-step's events
            const rc = native(['--accel', 'kdtree-median', 'teapot', '--build', '--json', '--max-depth', '10']).split('\n').filter((l) => l.includes('"build_')).length;
            await p.eval(`sidxLab.openLink('#scene=teapot&accel=kdtree-median&max_depth=10&mode=build'), 0`);
            s = await until(p, 'the build mode with the worker\'s events', (x) => !x.job && x.knobs.max_depth === 10 && x.count > 0, 60000);
            if (!s.remote || s.count !== rc) return `max_depth 10: remote ${s.remote}, the build mode has ${s.count} steps, sidx-step --build ${rc} events`;
            await press(p, 'Home');
            await press(p, 'l');
            s = await until(p, 'l in the build mode', (x) => x.cur > 0);
            if (s.curType !== 'build_leaf') return `l in the build mode lands on ${s.curType} (${s.curLine})`;
            const buildSteps = s.count, buildLeaf = s.cur;
            // a ray set while a rebuild runs (the build's answer held until it is set) is the
            // one shown when the rebuild is done, traced through the new tree
            const ray2 = [-2.5, 1.0, -0.3, 1, 0.02, 0.08], want2 = JSON.stringify(ray2.map(Math.fround));
            await p.eval(`sidxLab._holdJobs(true), sidxLab.openLink('#scene=teapot&accel=kdtree-median&max_depth=12&mode=3d'), 0`);
            await until(p, 'the rebuild under way', (x) => x.job);
            await p.eval(`sidxLab.setRay(${JSON.stringify(ray2)})`);
            await until(p, 'the ray traced through the tree kept meanwhile', (x) => !x.tracing && JSON.stringify(x.ray) === want2);
            await p.eval('sidxLab._holdJobs(false), 0');
            s = await until(p, 'the rebuild done', (x) => !x.job && !x.tracing && x.knobs.max_depth === 12, 60000);
            if (JSON.stringify(s.ray) !== want2) return `the ray set during the rebuild, ${want2}, was replaced by ${JSON.stringify(s.ray)}`;
            why = await compareTrace(p, s);
            if (why) return 'the ray set during the rebuild: ' + why;
            console.log(`        teapot, kdtree-median built in the worker: two rays as sidx-step's; l -> step ${first + 1} (leaf node ${leafNode}); ` +
                `its build mode states its limit; with max_depth 10: ${buildSteps} build steps, l -> ${buildLeaf}; ` +
                `a ray set during a rebuild kept and traced through the new tree`);
            await p.eval(`sidxLab.openLink('#scene=kd-slide&accel=kdtree')`);
            return null;
        });

        await check('the stack\'s t-intervals drawn along the ray; jumps by leaf and by event type in every mode', async () => {
            let s = await p.eval(`sidxLab.openLink('#scene=kd-slide&accel=kdtree&mode=2d&ray=0,4.2,0,1,0.15,0&step=13')`);
            if (s.stack.length !== 2 || s.intervals.length !== 2) return `at step 13: stack ${JSON.stringify(s.stack)}, intervals drawn ${s.intervals.length}`;
            for (let k = 0; k < 2; ++k) {
                const iv = s.intervals[k], st = s.stack[s.stack.length - 1 - k];
                if (iv.node !== st.node || iv.t_near !== st.t_near || iv.t_far !== st.t_far) return `interval ${k}: ${JSON.stringify(iv)}, the stack's ${JSON.stringify(st)}`;
                // the bar's colour on the canvas, halfway along it
                const px = await p.eval(`(() => { const c = document.getElementById('view'), d = c.width / c.getBoundingClientRect().width;
                    return [...c.getContext('2d').getImageData(Math.round(${(iv.x0 + iv.x1) / 2} * d), Math.round(${(iv.y0 + iv.y1) / 2} * d), 1, 1).data]; })()`);
                const want = [1, 3, 5].map((i) => parseInt(iv.color.slice(i, i + 2), 16));
                if (want.some((v, i) => Math.abs(v - px[i]) > 40)) return `interval ${k} (node ${iv.node}): the canvas has rgb ${px.slice(0, 3)} halfway along it, not ${iv.color}`;
            }
            await shot(p, 'stack-intervals');
            const keys = await p.eval(`document.getElementById('keys').textContent`);
            if (!/l \/ L .*leaf/.test(keys) || !/t \/ T .*type/.test(keys)) return 'the keys\' list does not name l / L and t / T';
            // l and L in 2D and 3D: the leaves L2 and L4 of the slide's tree, and back
            const seen = [];
            for (const mode of ['1', '3']) {
                await press(p, mode);
                await press(p, 'Home');
                await until(p, 'Home', (x) => x.step === 0);
                for (const [key, want] of [['l', 5], ['l', 13], ['L', 5]]) {
                    await press(p, key);
                    s = await until(p, `${key} to step ${want}`, (x) => x.step === want);
                    if (s.curType !== 'node_enter' || !/\[L\d\]/.test(s.curLine)) return `${key} in mode ${s.mode} lands on '${s.curLine}'`;
                }
                seen.push(s.mode);
            }
            // t by a chosen type: a triangle test in 3D, a split in the build mode
            await choose(p, '#evtype', 'prim_test');
            await press(p, 'Home');
            await until(p, 'Home', (x) => x.step === 0);
            await press(p, 't');
            s = await until(p, 't', (x) => x.step > 0);
            if (s.curType !== 'prim_test' || s.step !== 6) return `t (prim_test) in 3D went to step ${s.step}: ${s.curLine}`;
            await press(p, '2');
            await until(p, 'build mode', (x) => x.mode === 'build');
            await choose(p, '#evtype', 'build_split');
            await press(p, 'Home');
            await press(p, 't');
            s = await until(p, 't in the build mode', (x) => x.cur > 0);
            if (s.curType !== 'build_split' || !/split node 0/.test(s.curLine)) return `t (build_split) in the build mode: ${s.curType} '${s.curLine}'`;
            await press(p, 'l');
            s = await until(p, 'l in the build mode', (x) => x.curType === 'build_leaf');
            console.log(`        at step 13 the stack's two intervals drawn, their colours on the canvas; l, l, L -> 5, 13, 5 in ${seen.join(' and ')}; ` +
                `t -> prim_test at 6; in the build mode t -> a split, l -> '${s.curLine}'`);
            await p.eval(`sidxLab.openLink('#scene=kd-slide&accel=kdtree')`);
            return null;
        });

        await check('presets: each lesson\'s preset opens with its caption, its walks equal sidx-step; PageDown, PageUp', async () => {
            const presets = await p.eval('sidxLab.presets()');
            if (presets.length < 15) return `only ${presets.length} presets`;
            const ex0 = p.exceptions.length;
            let events = 0;
            for (const pr of presets) {
                const nn = (pr.n < 10 ? '0' : '') + pr.n;
                const s = await p.eval(`sidxLab.openLink('#lesson=${nn}')`);
                const q = Object.fromEntries(pr.link.split('&').map((kv) => kv.split('=')));
                if (s.lesson !== pr.n || s.scene !== q.scene || s.accel !== q.accel || (s.accel2 || '') !== (q.accel2 || '') ||
                    s.error || s.notes.length || s.caught.length || p.exceptions.length > ex0)
                    return `lesson ${nn}: lesson ${s.lesson}, ${s.scene} ${s.accel} ${s.accel2}, error '${s.error}', notes ${JSON.stringify(s.notes)} ${s.caught}`;
                const cap = await p.eval(`document.getElementById('caption').textContent`);
                if (!cap.includes(pr.title) || !/lesson=\d\d/.test(await p.eval('location.hash'))) return `lesson ${nn}: the caption says '${cap}'`;
                if (q.step !== undefined && s.step !== Number(q.step)) return `lesson ${nn}: at step ${s.step}, not ${q.step}`;
                let why = await compareTrace(p, s);
                if (why) return `lesson ${nn}: ${why}`;
                if (q.accel2) {
                    why = traceDiff(traceOnly(s.events2 || []), traceOnly(nativeTrace(q.accel2, s.scene, s.ray, knobArgs(s.knobs))));
                    if (why) return `lesson ${nn}, ${q.accel2}: ${why}`;
                }
                events += s.events.length + (s.events2 || []).length;
            }
            await p.eval(`sidxLab.openLink('#lesson=${(presets[0].n < 10 ? '0' : '') + presets[0].n}')`);
            await press(p, 'PageDown');
            let s = await until(p, 'PageDown: the second preset', (x) => x.lesson === presets[1].n);
            await press(p, 'PageUp');
            s = await until(p, 'PageUp: the first preset', (x) => x.lesson === presets[0].n);
            await shot(p, 'preset-' + presets[0].n);
            console.log(`        ${presets.length} presets (lessons ${presets.map((x) => x.n).join(' ')}): ${events} events equal sidx-step's; PageDown, PageUp`);
            await p.eval(`sidxLab.openLink('#scene=kd-slide&accel=kdtree')`);
            return null;
        });

        await check(`fuzz: ${FUZZ_LINKS} random addresses and ${FUZZ_FILES} random OBJ files through the page`, async () => {
            const gen = fs.readFileSync(path.join(__dirname, 'fuzz_gen.js'), 'utf8');
            const r = await p.eval(`(async () => {
                const module = { exports: {} };
                (function (module) { ${gen} })(module);
                const G = module.exports, t0 = performance.now();
                const home = () => document.dispatchEvent(new KeyboardEvent('keydown', { key: 'Home', bubbles: true }));
                function problem(what, input) {
                    const s = sidxLab.state();
                    if (window.sidxErrors.length) return what + ': script error ' + window.sidxErrors.join('; ');
                    if (s.caught.length) return what + ': ' + s.caught.join('; ');
                    if (!s.scene || !s.accel) return what + ': no scene or structure open (' + s.scene + ', ' + s.accel + ')';
                    home();
                    const h = sidxLab.state();
                    if (h.cur !== 0) return what + ': Home leaves the stepper at ' + h.cur;
                    return '';
                }
                for (let i = 0; i < ${FUZZ_LINKS}; ++i) {
                    const hash = G.address(G.rng(${FUZZ_SEED} * 7919 + i));
                    try { sidxLab.openLink(hash); } catch (e) { return 'address ' + i + ' ' + JSON.stringify(hash) + ': threw ' + e.message; }
                    const why = problem('address ' + i + ' ' + JSON.stringify(hash));
                    if (why) return why;
                }
                sidxLab.openLink('#scene=kd-slide&accel=kdtree');
                const box = document.getElementById('viewbox');
                for (let i = 0; i < ${FUZZ_FILES}; ++i) {
                    const rr = G.rng(${FUZZ_SEED} * 104729 + i), text = G.obj(rr), n0 = sidxLab.state().loads;
                    const dt = new DataTransfer();
                    dt.items.add(new File([text], rr.pick(['f.obj', 'g.obj', 'h.ply']), { type: 'text/plain' }));
                    box.dispatchEvent(new DragEvent('drop', { dataTransfer: dt, bubbles: true, cancelable: true }));
                    const t1 = performance.now();
                    while (sidxLab.state().loads === n0) {
                        if (performance.now() - t1 > 5000) return 'file ' + i + ' ' + JSON.stringify(text).slice(0, 300) + ': not loaded in 5 s';
                        await new Promise((res) => setTimeout(res, 0));
                    }
                    const why = problem('file ' + i + ' ' + JSON.stringify(text).slice(0, 300));
                    if (why) return why;
                }
                return 'ok ' + Math.round(performance.now() - t0);
            })()`, 600000);
            if (!r.startsWith('ok ')) return r;
            const s = await state(p);
            console.log(`        ${FUZZ_LINKS} addresses and ${FUZZ_FILES} files (seed ${FUZZ_SEED}) in ${r.slice(3)} ms: no script error, ` +
                `no exception caught, Home answered after each; last: ${s.scene}, ${s.accel}`);
            await p.eval(`sidxLab.openLink('#scene=kd-slide&accel=kdtree')`);
            return null;
        });

        if (p.exceptions.length) bad('no script errors', p.exceptions.join('; '));
    } finally {
        await b.close();
    }

}

if (!fs.existsSync(PAGE)) {
    console.log(`web-page: skipped: no ${PAGE} (make web builds it)`);
    process.exit(0);
}
main().then(() => {
    if (summary.length) console.log('web-page: the page\'s timings (printed, not checked): ' + summary.join(', '));
    console.log(failures ? `web-page: ${failures} check(s) failed` : 'web-page: all checks passed');
    process.exit(failures ? 1 : 0);
}, (e) => {
    console.log('  FAIL  ' + e.message);
    process.exit(1);
});
