// lab_fuzz.js — random addresses and OBJ files through the lab's WebAssembly module.
//
//   node tests/web/lab_fuzz.js build/web/sidx-lab.js [COUNT [SEED]]
//
// COUNT inputs (default 1000) from tests/web/fuzz_gen.js, half addresses and
// half OBJ files.  An address's parts go to the module as the page passes
// them: its scene name to sidx_lab_open_scene, its structure and knobs (as
// the JSON object the page writes, and now and then raw text) to
// sidx_lab_build, its ray to sidx_lab_trace, its camera to the camera ray
// and an 8 x 8 heat map.  An OBJ goes to sidx_lab_open_obj, then one
// structure is built over it and two rays traced.  Every answer must be
// JSON (JSON.parse), every failed call must say why (sidx_lab_error), and
// the module must not throw or abort.  Exit 0 all held, 1 a failure (its
// seed and index printed; the same input comes back from the same seed).
'use strict';
const path = require('path');
const G = require('./fuzz_gen');

const MODULE = process.argv[2];
const COUNT = Number(process.argv[3] || 1000);
const SEED = Number(process.argv[4] || 1);

function decode(x) { try { return decodeURIComponent(x); } catch (e) { return null; } }

require(path.resolve(MODULE))().then((M) => {
    const S = (name, args, vals) => M.ccall(name, 'string', args || [], vals || []);
    const I = (name, args, vals) => M.ccall(name, 'number', args, vals);
    const N7 = ['number', 'number', 'number', 'number', 'number', 'number', 'number'];
    let answers = 0, refused = 0, opened = 0, traces = 0;
    const t0 = Date.now();
    function json(what, text) {
        try { JSON.parse(text); } catch (e) { throw new Error(what + ' is not JSON (' + e.message + '): ' + text.slice(0, 200)); }
        ++answers;
    }
    function rc(what, r) {
        if (r !== 0) {
            ++refused;
            if (!S('sidx_lab_error')) throw new Error(what + ' failed with ' + r + ' and no message');
        }
        return r;
    }
    function num(x) { const v = Number(x); return x !== null && x !== undefined && String(x).trim() !== '' ? v : NaN; }
    function buildAndTrace(r, accel, knobs, rays) {
        const slot = r.below(2);
        if (rc('build ' + accel + ' ' + knobs, I('sidx_lab_build', ['number', 'string', 'string'], [slot, accel, knobs])) === 0) {
            json('build', S('sidx_lab_build_json', ['number'], [slot]));
            if (r.chance(0.3)) json('build events', S('sidx_lab_build_events_json', ['number'], [slot]));
        }
        for (const ray of rays) {
            const v = ray.concat([0, 0, 0, 0, 0, 0]).slice(0, 6).map(num);
            if (rc('trace', I('sidx_lab_trace', N7, [slot].concat(v))) === 0) ++traces;
            json('trace', S('sidx_lab_trace_json', ['number'], [slot]));
        }
        json('diverge', S('sidx_lab_diverge_json'));
    }
    const KNOBS = ['bins', 'c_trav', 'c_tri', 'leaf_size', 'max_depth', 'lambda', 'mailbox', 'empty_bonus', 'optimize'];
    for (let i = 0; i < COUNT; ++i) {
        const r = G.rng(SEED * 1000003 + i);
        let input = '';
        try {
            if (i % 2 === 0) {
                input = G.address(r);
                const q = {};
                for (const kv of input.slice(1).split('&')) {
                    const k = kv.indexOf('=');
                    if (k <= 0) continue;
                    const key = decode(kv.slice(0, k)), val = decode(kv.slice(k + 1));
                    if (key !== null && val !== null) q[key] = val;
                }
                const scene = q.scene || 'kd-slide';
                if (rc('open ' + scene, I('sidx_lab_open_scene', ['string'], [scene])) === 0) ++opened;
                json('scene', S('sidx_lab_scene_json'));
                json('structures', S('sidx_lab_structures'));
                // the knobs as the page writes them (numbers), or the address's text as it came
                const k = {};
                for (const n of KNOBS) if (q[n] !== undefined) k[n] = r.chance(0.8) && isFinite(+q[n]) ? +q[n] : q[n];
                const knobs = r.chance(0.9) ? JSON.stringify(k) : G.numberText(r) + (q.bins || '{');
                buildAndTrace(r, q.accel || 'bvh', knobs, [(q.ray || '').split(','), [0, 4.2, 0, 1, 0.15, 0]]);
                const cam = (q.cam || '0.6,0.35,1').split(',').map(num);
                json('camera ray', S('sidx_lab_camera_ray', N7, [cam[0], cam[1], cam[2], 8, 8, 4.5, 4.5]));
                rc('heat', I('sidx_lab_heatmap', N7, [r.below(2), cam[0], cam[1], cam[2], 8, 8, r.below(3)]));
                json('heat', S('sidx_lab_heatmap_json'));
            } else {
                input = G.obj(r);
                const bytes = Buffer.from(input, 'utf8');
                const p = M._malloc(bytes.length + 1);
                M.HEAPU8.set(bytes, p);
                const name = r.pick(['f.obj', 'f.OBJ', 'f.ply', 'f.txt']);
                const ok = rc('obj', I('sidx_lab_open_obj', ['number', 'number', 'string'], [p, bytes.length, name])) === 0;
                M._free(p);
                json('scene', S('sidx_lab_scene_json'));
                if (ok) {
                    ++opened;
                    const accel = r.pick(['bvh', 'kdtree', 'grid', 'bsp', 'octree', 'bvh8', 'rayclass', 'grid-irregular', 'kdtree-median', 'brute']);
                    buildAndTrace(r, accel, r.chance(0.5) ? '' : '{"leaf_size":1}',
                        [[0, 0, -10, 0, 0, 1], [G.numberText(r), 0, 0, 1, G.numberText(r), 0.5]]);
                    json('obj text', JSON.stringify(S('sidx_lab_scene_obj')));
                }
            }
        } catch (e) {
            console.log(`lab-fuzz: FAILED at seed ${SEED} input ${i}: ${e.message}\n  input: ${JSON.stringify(input).slice(0, 400)}`);
            process.exit(1);
        }
    }
    console.log(`lab-fuzz: ${COUNT} inputs (${Math.ceil(COUNT / 2)} addresses, ${Math.floor(COUNT / 2)} OBJ files, seed ${SEED}): ` +
        `${answers} answers all JSON, ${refused} calls refused with a message, ${opened} scenes opened, ${traces} rays traced, ` +
        `${Date.now() - t0} ms`);
}, (e) => {
    console.log('lab-fuzz: FAILED: the module did not load: ' + e.message);
    process.exit(1);
});
