// web_freeze_bench.js — how the lab page behaves during its longest work:
// opening a 49,152-triangle OBJ with kdtree-median, rayclass or bvh, and a
// link to rayclass over the icosphere at detail 5 (20,480 triangles).
// For each: the time until the page shows the result, the longest gap of
// a 10 ms heartbeat on the page's thread, and how long a key pressed
// 0.5 s into the work waited (the page's own timings().key).  With
// "cancel", Esc is pressed 1 s in and the time back to the view before is
// measured.  A case steps:ACCEL opens the OBJ with ACCEL and then times
// three keys (Home, End, Left) on the walk shown: each key's wait and
// handling, the walk redrawn.  The figures go to docs/performance.md,
// "The web lab".
//
//   node docs/web_freeze_bench.js PAGE OBJ [CASES] [cancel]
//     PAGE   build/web/sidx-lab.html
//     OBJ    a 49k-triangle OBJ: the Stanford bunny's first 49,152 faces,
//            awk '/^v /{print;next} /^f /{if (++n <= 49152) print}' \
//                ../shared/scenes/bunny.obj > /tmp/bunny49k.obj
//     CASES  default obj:kdtree-median,obj:rayclass,obj:bvh,link:icosphere:5:rayclass
'use strict';
const cdp = require('../tests/web/cdp.js');
const path = require('path');
const PAGE = 'file://' + path.resolve(process.argv[2] || 'build/web/sidx-lab.html');
const OBJ = path.resolve(process.argv[3] || '/tmp/bunny49k.obj');
const NAME = path.basename(OBJ);
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
const HEARTBEAT = `window.__lt = window.__lt || (() => { const a = []; try { new PerformanceObserver((l) => {
    for (const e of l.getEntries()) a.push(Math.round(e.duration)); }).observe({ entryTypes: ['longtask'] }); } catch (e) { /* none */ } return a; })();
  window.__lt.length = 0; window.__gap = 0; window.__last = performance.now(); clearInterval(window.__hb);
  window.__hb = setInterval(() => { const t = performance.now(); window.__gap = Math.max(window.__gap, t - window.__last); window.__last = t; }, 10); 0`;
async function key(p, k, vk) {
    const base = { key: k, code: k, windowsVirtualKeyCode: vk };
    await p.send('Input.dispatchKeyEvent', Object.assign({ type: 'rawKeyDown' }, base));
    await p.send('Input.dispatchKeyEvent', Object.assign({ type: 'keyUp' }, base));
}
(async () => {
    const b = await cdp.launch({ timeoutMs: 600000, lifeMs: 1800000 });
    const esc = process.argv[5] === 'cancel';
    try {
        for (const c of (process.argv[4] || 'obj:kdtree-median,obj:rayclass,obj:bvh,link:icosphere:5:rayclass').split(',')) {
            const [kind, ...rest] = c.split(':');
            const accel = kind === 'obj' || kind === 'steps' ? rest[0] : null;
            const p = await b.newPage(null);
            await p.goto(PAGE + '#scene=teapot&accel=bvh&mode=3d');
            await p.eval('sidxLab.ready', 60000);
            if (accel) {     /* the structure chosen on the teapot first (in a worker where that is long) */
                await p.eval(`(() => { const e = document.getElementById('accel'); e.value = ${JSON.stringify(accel)};
                    e.dispatchEvent(new Event('change')); })(), 0`);
                for (let i = 0; i < 600; ++i) {
                    const x = await p.eval('sidxLab.state()');
                    if (!x.busy && !x.painting && x.accel === accel) break;
                    await sleep(100);
                }
            }
            await sleep(300);
            await p.eval(HEARTBEAT);
            const n0 = (await p.eval('sidxLab.state()')).loads, t0 = Date.now();
            if (accel) await p.setFiles('#obj-file', [OBJ]);
            else await p.eval(`setTimeout(() => sidxLab.openLink('#scene=${rest[0]}:${rest[1]}&accel=${rest[2]}&mode=3d'), 0), 0`);
            await sleep(500);
            await key(p, 'Home', 36);
            if (esc) { await sleep(500); await key(p, 'Escape', 27); }
            let s;
            for (;;) {
                s = await p.eval('sidxLab.state()', 600000);
                const done = accel ? s.loads > n0 && s.scene === NAME : s.scene.startsWith(rest[0]);
                if (!s.busy && !s.painting && (done || esc)) break;
                await sleep(50);
            }
            const wall = Date.now() - t0;
            await sleep(200);
            if (kind === 'steps') {
                const keys = [];
                for (const [k, vk] of [['Home', 36], ['End', 35], ['ArrowLeft', 37]]) {
                    await key(p, k, vk);
                    await sleep(500);
                    keys.push(Math.round(await p.eval('sidxLab.timings().key')));
                }
                console.log(`${c}: ${s.events.length} events; Home, End, Left took ${keys.join(', ')} ms`);
                await p.send('Target.closeTarget', { targetId: p.targetId }).catch(() => null);
                continue;
            }
            const gap = await p.eval('window.__gap'), t = await p.eval('sidxLab.timings()');
            const lt = (await p.eval('window.__lt.slice()')).sort((x, y) => y - x).slice(0, 3);
            console.log(`${c}${esc ? ' (Esc at 1 s)' : ''}: ${wall} ms to ${s.scene} with ${s.accel}; the page's thread held at most ` +
                `${gap.toFixed(0)} ms (longest tasks ${lt.join(', ')} ms); a key pressed at 0.5 s answered after ${t.key ? t.key.toFixed(0) : '?'} ms; error '${s.error}'`);
            await p.send('Target.closeTarget', { targetId: p.targetId }).catch(() => null);
        }
    } finally {
        await b.close();
    }
})().catch((e) => { console.error(e); process.exit(1); });
