// web_module.js — sidx-lab's script (viz/sidx_lab.c) through the WebAssembly
// module in Node: the same calls, printed the same way, so that
// tests/run_web_module.sh can compare the module's answers with the native
// build's byte for byte.
//
//   node tests/web_module.js build/web/sidx-lab.js SCRIPT
//
// Exit status: 0 ok, 1 the module or a file cannot be read, 2 a line that is
// no command (the same rules as sidx-lab).
"use strict";
const fs = require("fs");
const path = require("path");

if (process.argv.length !== 4) {
  process.stderr.write("usage: node web_module.js MODULE.js SCRIPT\n");
  process.exit(2);
}
const SidxLab = require(path.resolve(process.argv[2]));
const script = fs.readFileSync(process.argv[3], "utf8");

// FNV-1a over the counts' bytes, little-endian (sidx-lab's fnv1a).
function fnv1a(counts) {
  let h = 0xcbf29ce484222325n;
  const prime = 0x100000001b3n, mask = 0xffffffffffffffffn;
  for (const v of counts)
    for (let k = 0; k < 4; ++k) {
      h ^= BigInt((v >>> (8 * k)) & 0xff);
      h = (h * prime) & mask;
    }
  return h.toString(16).padStart(16, "0");
}

// k numbers after the command, as strtod reads them; null unless exactly k.
function numbers(rest, k) {
  const parts = rest.split(/[ \t]+/).filter((s) => s.length);
  if (parts.length !== k) return null;
  const v = parts.map(Number);
  return v.some((x) => Number.isNaN(x)) ? null : v;
}

SidxLab().then((M) => {
  const S = (name, args, vals) => M.ccall(name, "string", args || [], vals || []);
  const I = (name, args, vals) => M.ccall(name, "number", args, vals);
  const N7 = ["number", "number", "number", "number", "number", "number", "number"];
  const out = [];
  const status = (rc) => out.push("rc " + rc + " " + S("sidx_lab_error"));
  const lines = script.split("\n");
  for (let i = 0; i < lines.length; ++i) {
    const line = lines[i].replace(/[\r ]+$/, "").replace(/^[ \t]+/, "");
    if (!line || line[0] === "#") continue;
    out.push("> " + line);
    const m = /^(\S+)[ \t]*(.*)$/.exec(line);
    const cmd = m[1], rest = m[2];
    let v;
    if (cmd === "scenes" && !rest) {
      out.push(S("sidx_lab_scenes"));
    } else if (cmd === "structures" && !rest) {
      out.push(S("sidx_lab_structures"));
    } else if (cmd === "open" && rest) {
      status(I("sidx_lab_open_scene", ["string"], [rest]));
      out.push(S("sidx_lab_scene_json"));
    } else if (cmd === "obj" && rest) {
      let bytes;
      try {
        bytes = fs.readFileSync(rest);
      } catch (e) {
        process.stderr.write("web_module.js: cannot read " + rest + ": " + e.message + "\n");
        process.stdout.write(out.join("\n") + "\n");
        process.exit(1);
      }
      const p = M._malloc(bytes.length || 1);
      M.HEAPU8.set(bytes, p);
      status(I("sidx_lab_open_obj", ["number", "number", "string"], [p, bytes.length, path.basename(rest)]));
      M._free(p);
      out.push(S("sidx_lab_scene_json"));
    } else if (cmd === "saveobj" && rest) {
      const text = S("sidx_lab_scene_obj");
      fs.writeFileSync(rest, text);
      out.push(Buffer.byteLength(text) + " bytes");
    } else if (cmd === "build" && (v = /^(-?\d+)[ \t]+(\S+)[ \t]*(.*)$/.exec(rest))) {
      const slot = Number(v[1]);
      status(I("sidx_lab_build", ["number", "string", "string"], [slot, v[2], v[3]]));
      out.push(S("sidx_lab_build_json", ["number"], [slot]));
    } else if (cmd === "events" && (v = numbers(rest, 1))) {
      out.push(S("sidx_lab_build_events_json", ["number"], [v[0]]));
    } else if (cmd === "trace" && (v = numbers(rest, 7))) {
      status(I("sidx_lab_trace", N7, v));
      out.push(S("sidx_lab_trace_json", ["number"], [v[0]]));
    } else if (cmd === "diverge" && !rest) {
      out.push(S("sidx_lab_diverge_json"));
    } else if (cmd === "heat" && (v = numbers(rest, 7))) {
      const rc = I("sidx_lab_heatmap", N7, v);
      status(rc);
      out.push(S("sidx_lab_heatmap_json"));
      if (rc === 0) {
        const p = M.ccall("sidx_lab_heatmap_data", "number", [], []);
        out.push("hash " + fnv1a(new Uint32Array(M.HEAPU8.buffer, p, v[4] * v[5])));
      }
    } else if (cmd === "camray" && (v = numbers(rest, 7))) {
      out.push(S("sidx_lab_camera_ray", N7, v));
    } else if (cmd === "bench" && (v = numbers(rest, 7))) {
      out.push(S("sidx_lab_bench", N7, v));
    } else {
      process.stdout.write(out.join("\n") + "\n");
      process.stderr.write("web_module.js: line " + (i + 1) + ": not a command: " + lines[i] + "\n");
      process.exit(2);
    }
  }
  process.stdout.write(out.join("\n") + "\n");
});
