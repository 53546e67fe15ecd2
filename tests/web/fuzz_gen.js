// fuzz_gen.js — random addresses and OBJ files for the lab, from a seed.
//
// The same generator runs in Node (tests/web/lab_fuzz.js: through the
// WebAssembly module) and in the page (tests/web/lab_test.js injects this
// text): a failing input is named by its seed and index and comes back
// the same in both.  Plain ES5 functions, no require.
//
//   const G = require('./fuzz_gen');
//   const r = G.rng(7);  G.address(r);  G.obj(r);
'use strict';

// xorshift32: small, fast and the same in every engine.
function rng(seed) {
    let s = (seed >>> 0) || 0x9e3779b9;
    const next = function () {
        s ^= s << 13; s >>>= 0;
        s ^= s >>> 17;
        s ^= s << 5; s >>>= 0;
        return s / 4294967296;
    };
    return {
        unit: next,
        below: function (n) { return Math.floor(next() * n); },
        pick: function (a) { return a[Math.floor(next() * a.length)]; },
        chance: function (p) { return next() < p; },
    };
}

// A number as text: ordinary, huge, tiny, signed zero, not finite, or no number at all.
function numberText(r) {
    return r.pick([
        () => String((r.unit() - 0.5) * 20),
        () => String(r.below(10)),
        () => r.pick(['0', '-0', '1', '-1', '0.5', '1e-45', '1e-30', '3e38', '-3e38', '3.5e38', '1e39', '-1e39',
                      '1e308', '1e999', 'nan', 'NaN', 'inf', '-inf', 'Infinity', '', ' ', '1e', '0x10', '1,5', '--1', '.']),
        () => String(Math.pow(10, r.below(80) - 40) * (r.chance(0.5) ? -1 : 1)),
    ])();
}

const SCENES = ['kd-slide', 'flat2d', 'cornell', 'icosphere', 'kd-slide', 'flat2d', 'Teapot', 'KD-SLIDE', 'nosuch',
                'x.obj', 'y.PLY', 'kd-slide:3', 'flat2d:0', 'cornell:x', 'icosphere:2', '', ':', 'kd-slide:', '%', '..'];
const ACCELS = ['brute', 'bvh', 'bvh-sweep', 'bvh-median', 'bvh-obb', 'grid', 'grid-nomailbox', 'kdtree', 'kdtree-binned',
                'kdtree-median', 'bsp', 'grid2', 'rayclass', 'grid-irregular', 'octree', 'quadtree', 'bvh4', 'bvh8',
                'BVH', 'nosuch', '', ' bvh', 'bvh\u0000'];
const KEYS = ['scene', 'accel', 'accel2', 'mode', 'cam', 'level', 'heat', 'ray', 'step', 'bstep', 'present',
              'bins', 'c_trav', 'c_tri', 'leaf_size', 'max_depth', 'lambda', 'mailbox', 'empty_bonus', 'optimize',
              'note', 'lesson', 'x', '', '__proto__', 'constructor', 'toString'];
const JUNK = ['%', '%%', '%zz', '%E0%A4%A', '100%', '%00', '%2', '\u00e9', '\u{1F600}', '<b>', '"', '\\', '&', '=', '==',
              '#', '?', '+', '%20', 'a%2Cb', '%3D', '\u2028'];

function junk(r) {
    let s = '';
    const n = 1 + r.below(4);
    for (let i = 0; i < n; ++i) s += r.chance(0.5) ? r.pick(JUNK) : String.fromCharCode(32 + r.below(95));
    return s;
}

function valueFor(r, key) {
    if (r.chance(0.15)) return junk(r);
    const nums = (k) => { const a = []; for (let i = 0; i < k; ++i) a.push(numberText(r)); return a.join(','); };
    switch (key) {
    case 'scene': return r.pick(SCENES);
    case 'accel': case 'accel2': return r.pick(ACCELS);
    case 'mode': return r.pick(['2d', '3d', 'build', 'heat', '3D', 'x', '']);
    case 'cam': return r.chance(0.5) ? nums(3) : r.pick(['0.6,0.35,1', '0,0,0', '1,2,60', '0,1.6,1', '1,1']);
    case 'heat': return r.pick(['steps', 'tris']) + ',' + r.pick(['8', '16', '32', '0', '-1', '1e9', '2048', 'x', '']);
    case 'ray':
        return r.chance(0.5) ? nums(r.chance(0.9) ? 6 : r.below(9))
            : r.pick(['0,4.2,0,1,0.15,0', '1,2,0,0,0,0', '0,0,0,1e39,0,0', '0,0,0,1e-46,0,0', '-1,1,0,1,0,0']);
    case 'step': case 'bstep': case 'level': return r.pick(['0', '1', '5', '99999999', '-1', '1.5', 'x', '']);
    case 'present': return r.pick(['0', '1', '2', 'yes']);
    case 'mailbox': return r.pick(['0', '1', 'false', '']);
    default: return numberText(r);
    }
}

// An address's hash: 0 to 9 parts, each key=value, now and then with no '=', repeated or broken.
function address(r) {
    const parts = [];
    const n = r.below(10);
    for (let i = 0; i < n; ++i) {
        const key = r.chance(0.9) ? r.pick(KEYS) : junk(r);
        if (r.chance(0.05)) { parts.push(key); continue; }
        let v = valueFor(r, key);
        // most values are escaped as a link would be; some arrive raw (a stray '%')
        if (r.chance(0.7)) v = encodeURIComponent(v);
        parts.push(key + '=' + v);
    }
    if (r.chance(0.1)) parts.push('');
    return '#' + parts.join('&');
}

// An OBJ file's text: vertices, faces (triangles, polygons, v/vt/vn forms, negative and
// out-of-range indices), comments, other statements, junk lines, CRLF or LF, maybe no
// last newline; now and then a PLY header.
function obj(r) {
    const lines = [];
    const nv = r.below(12);
    const eol = r.chance(0.2) ? '\r\n' : '\n';
    if (r.chance(0.05)) lines.push('ply', 'format ascii 1.0', 'element vertex ' + numberText(r));
    for (let i = 0; i < nv; ++i) {
        const v = r.chance(0.8) ? [0, 1, 2].map(() => String((r.unit() - 0.5) * r.pick([1, 10, 1e3, 1e30, 6e38]))) : [0, 1, 2].map(() => numberText(r));
        lines.push((r.chance(0.95) ? 'v ' : 'v  ') + v.join(' ') + (r.chance(0.05) ? ' 1' : ''));
    }
    const nf = r.below(8);
    for (let i = 0; i < nf; ++i) {
        const k = r.chance(0.8) ? 3 : r.below(7);
        const idx = [];
        for (let j = 0; j < k; ++j) {
            let x = r.chance(0.85) ? String(1 + r.below(Math.max(1, nv))) : r.pick(['0', '-1', '-' + (1 + r.below(5)), String(nv + 1), '99999999999', 'x', '']);
            if (r.chance(0.1)) x += r.pick(['/1', '//1', '/1/1', '/', '//']);
            idx.push(x);
        }
        lines.push('f ' + idx.join(' '));
    }
    const extra = r.below(4);
    for (let i = 0; i < extra; ++i) {
        lines.splice(r.below(lines.length + 1), 0, r.pick(['# comment', 'o thing', 'g group', 'usemtl m', 's off', 'vn 0 0 1',
                                                             'vt 0.5 0.5', 'mtllib x.mtl', '', '   ', junk(r), 'v', 'f', 'f 1 2']));
    }
    let text = lines.join(eol);
    if (r.chance(0.7)) text += eol;
    return text;
}

module.exports = { rng, address, obj, numberText };
