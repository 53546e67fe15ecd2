// view_page_test.js — the DevTools client (cdp.js) on sidx-view --html's page.
//
//   node tests/web/view_page_test.js [BUILD]    (tests/run_web_page.sh runs it)
//
// Checks the client itself on the recorded page every SDL2 build writes,
// with the same real input events the lab's test sends: End and Left keys
// step to the last step and back (#state against the line count of
// sidx-step --json for the same ray), key 3 switches to 3D, a mouse drag
// on the canvas orbits it (the screenshot changes), and a script error
// thrown in the page comes back as an error.  Exit 0 passed, 1 failed.
'use strict';

const cdp = require('./cdp');
const { execFileSync } = require('child_process');
const crypto = require('crypto');
const fs = require('fs');
const os = require('os');
const path = require('path');

const BUILD = process.argv[2] || process.env.BUILD || 'build';
const VIEW = path.resolve(BUILD, 'bin/sidx-view');
const STEP = path.resolve(BUILD, 'bin/sidx-step');
const SCREENS = path.resolve(BUILD, 'web/screens');
const RAY = '0,4.2,0,1,0.15,0';

let failures = 0;
const ok = (n) => console.log('  ok    ' + n);
const bad = (n, why) => { console.log('  FAIL  ' + n + ': ' + why); failures++; };
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

// The page's #state lines as an object.
async function pageState(p) {
    const text = await p.eval(`document.getElementById('state').textContent`);
    const s = {};
    for (const line of text.split('\n')) {
        const i = line.indexOf('=');
        if (i > 0) s[line.slice(0, i)] = line.slice(i + 1);
    }
    return s;
}

async function key(p, k, code) {
    await p.send('Input.dispatchKeyEvent', { type: 'rawKeyDown', key: k, code: code || k, windowsVirtualKeyCode: 0 });
    if (k.length === 1) await p.send('Input.dispatchKeyEvent', { type: 'char', key: k, text: k });
    await p.send('Input.dispatchKeyEvent', { type: 'keyUp', key: k, code: code || k });
}

async function untilState(p, what, pred) {
    const t0 = Date.now();
    let s;
    while (!pred(s = await pageState(p))) {
        if (Date.now() - t0 > 10000) throw new Error(`waited 10 s for ${what}; #state: ${JSON.stringify(s)}`);
        await sleep(50);
    }
    return s;
}

const hash = (f) => crypto.createHash('sha1').update(fs.readFileSync(f)).digest('hex');

async function main() {
    const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'sidx-view-page-'));
    const page = path.join(dir, 'kd-slide.html');
    execFileSync(VIEW, ['--scene', 'kd-slide', '--accel', 'kdtree', '--ray', RAY, '--html', page],
        { stdio: ['ignore', 'ignore', 'inherit'], timeout: 60000 });
    const lines = execFileSync(STEP, ['--accel', 'kdtree', 'kd-slide', '--ray', RAY, '--json', '--all'],
        { encoding: 'utf8', timeout: 60000 }).split('\n').filter((l) => l.trim()).length;

    const b = await cdp.launch({ timeoutMs: 20000, lifeMs: 120000 });
    try {
        const p = await b.newPage('file://' + page);
        const s0 = await untilState(p, 'status=ready', (s) => s.status === 'ready');
        if (Number(s0.steps) === lines) ok(`the page has sidx-step's ${lines} steps`);
        else bad('steps', `the page has ${s0.steps}, sidx-step --json ${lines} lines`);

        await key(p, 'End');
        let s = await untilState(p, 'the last step', (x) => x.step === String(lines));
        await key(p, 'ArrowLeft');
        await key(p, 'ArrowLeft');
        s = await untilState(p, 'two steps back', (x) => x.step === String(lines - 2));
        ok(`End then Left Left: step ${s.step} of ${s.steps}`);

        await key(p, '3', 'Digit3');
        await untilState(p, 'mode 3d', (x) => x.mode === '3d');
        const a = await p.screenshot(path.join(SCREENS, 'view-3d.png'));
        const ha = hash(a);
        const bx = await p.box('#scene');
        await p.drag(bx.x + bx.w * 0.5, bx.y + bx.h * 0.5, bx.x + bx.w * 0.8, bx.y + bx.h * 0.6, 6);
        await sleep(100);
        const hb = hash(await p.screenshot(path.join(SCREENS, 'view-3d-orbited.png')));
        if (ha !== hb) ok('a mouse drag orbits the 3D view (the screenshot changes)');
        else bad('drag', 'the 3D view looks the same after a drag');

        try {
            await p.eval('undefinedName + 1');
            bad('errors', 'a page exception did not come back');
        } catch (e) {
            if (/undefinedName/.test(e.message)) ok('a page exception comes back as an error');
            else bad('errors', e.message);
        }
        const st = await pageState(p);
        if (st.errors !== '0' || p.exceptions.length) bad('no script errors', JSON.stringify(st) + ' ' + p.exceptions.join('; '));
    } finally {
        await b.close();
        fs.rmSync(dir, { recursive: true, force: true });
    }
}

if (!fs.existsSync(VIEW)) {
    console.log(`view-page: skipped: no ${VIEW} (built without SDL2)`);
    process.exit(0);
}
main().then(() => {
    console.log(failures ? `view-page: ${failures} check(s) failed` : 'view-page: all checks passed');
    process.exit(failures ? 1 : 0);
}, (e) => {
    console.log('  FAIL  ' + e.message);
    process.exit(1);
});
