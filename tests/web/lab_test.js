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
//   - the page from file:// with networking off (offline, and a dead proxy):
//     it starts and no request leaves it;
//   - the build mode: as many build steps as sidx-step --build's events
//     (kdtree and bvh on kd-slide), and at bvh's first split the SAH curve
//     drawn from the node's candidates, which the page asks for on entering;
//   - the heat map: 256 x 256, not empty, no error;
//   - side by side: the second structure's walk against sidx-step, the
//     counts shown for both against their traces, and the step where the
//     walks part against sidx-step --diff.
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
    const b = await cdp.launch({ timeoutMs: WAIT_MS, lifeMs: 540000 });
    try {
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

        if (p.exceptions.length) bad('no script errors', p.exceptions.join('; '));
    } finally {
        await b.close();
    }

    // A browser of its own: a dead proxy for every request and the
    // network emulated offline; the page must start from file:// alone.
    await check('offline: the page starts from file:// and asks the network for nothing', async () => {
        const b2 = await cdp.launch({ timeoutMs: WAIT_MS, lifeMs: 120000, proxy: '127.0.0.1:9' });
        try {
            const p2 = await open(b2, { offline: true });
            const s = await state(p2);
            if (s.error) return 'error: ' + s.error;
            const out = p2.requests.filter((u) => !/^(file|data|blob|about):/.test(u));
            if (out.length) return 'requests: ' + out.join(' ');
            await shot(p2, 'offline');
            console.log(`        requests: ${p2.requests.length} (${[...new Set(p2.requests.map((u) => u.split(':')[0]))].join(', ')})`);
            return null;
        } finally {
            await b2.close();
        }
    });
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
