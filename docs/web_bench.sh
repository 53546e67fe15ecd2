#!/bin/sh
# web_bench.sh — the web lab's speed, natively (sidx-lab) and in the
# WebAssembly module (build/web/sidx-lab.js in Node), on the same calls:
# primary rays without a hook (Mrays/s), rebuilds after a knob change, one
# recorded trace, a 256×256 heat map of the teapot.  The figures go to
# docs/performance.md, "The web lab".
#
#   sh docs/web_bench.sh [BUILD [WEB]]      (after make build and make web)
#
# The times are the entry layer's own (build_ms, ms: C's monotonic clock
# around the library call), plus, in Node, the wall time of the whole
# call the page makes for a new ray (trace, its JSON, JSON.parse).
BUILD=${1:-build}
WEB=${2:-$BUILD/web}
TMP=${TMPDIR:-/tmp}/sidx-web-bench-$$
mkdir -p "$TMP" || exit 1
trap 'rm -rf "$TMP"' EXIT

cat >"$TMP/bench.txt" <<'EOF'
open teapot
build 0 bvh8
bench 0 0.6 0.4 1 256 256 5
build 1 kdtree
bench 1 0.6 0.4 1 256 256 5
build 0 bvh
bench 0 0.6 0.4 1 256 256 5
build 0 bvh4
bench 0 0.6 0.4 1 256 256 5
build 0 bvh8 {"bins":16}
build 0 bvh {"bins":16}
build 1 kdtree {"c_trav":2}
build 1 kdtree-binned {"bins":16}
trace 0 6.3 1.5 2 -6 -0.2 -2
trace 1 6.3 1.5 2 -6 -0.2 -2
heat 0 0.6 0.4 1 256 256 0
heat 1 0.6 0.4 1 256 256 0
open kd-slide
build 0 kdtree {"leaf_size":2}
build 1 bvh {"bins":8}
build 0 kdtree-median {"max_depth":4}
trace 0 0 4.2 0 1 0.15 0
trace 1 0 4.2 0 1 0.15 0
EOF
sed -i "s|@TMP@|$TMP|g" "$TMP/bench.txt"
# each side RUNS times; the best time of each call counts (a shared machine)
RUNS=${RUNS:-3}
i=0
while [ $i -lt "$RUNS" ]; do
    i=$((i + 1))
    "$BUILD/bin/sidx-lab" "$TMP/bench.txt" >"$TMP/native$i.txt" || exit 1
    node tests/web_module.js "$WEB/sidx-lab.js" "$TMP/bench.txt" >"$TMP/web$i.txt" || exit 1
done

# one line per timed call: what, native, wasm (the best of the runs)
awk '
FNR == 1 { side = FILENAME ~ /native/ ? "n" : "w"; k = 0 }
/^> / { what = substr($0, 3); k++; name[k] = what; next }
{
  v = ""; unit = " ms"; hi = 0
  if (match($0, /"mrays_per_s":[0-9.]+/)) { v = substr($0, RSTART + 14, RLENGTH - 14); unit = " Mrays/s"; hi = 1 }
  else if (match($0, /"build_ms":[0-9.]+/)) v = substr($0, RSTART + 11, RLENGTH - 11)
  else if (name[k] ~ /^(trace|heat)/ && match($0, /"ms":[0-9.]+/)) v = substr($0, RSTART + 5, RLENGTH - 5)
  if (v == "") next
  key = side k
  if (!(key in best) || (hi ? v + 0 > best[key] : v + 0 < best[key])) best[key] = v + 0
  u[k] = unit; if (k > n) n = k
}
END {
  printf "%-44s %16s %16s\n", "call", "native", "wasm (node)"
  for (i = 1; i <= n; i++) if (("n" i) in best)
    printf "%-44s %16s %16s\n", name[i], sprintf("%.3f", best["n" i]) u[i], sprintf("%.3f", best["w" i]) u[i]
}' "$TMP"/native*.txt "$TMP"/web*.txt

# the page's whole call for a new ray, in Node: trace + its JSON + JSON.parse
node -e '
const SidxLab = require(require("path").resolve(process.argv[1]));
SidxLab().then((M) => {
  const N7 = ["number","number","number","number","number","number","number"];
  M.ccall("sidx_lab_open_scene", "number", ["string"], ["teapot"]);
  for (const a of ["bvh8", "kdtree"]) {
    M.ccall("sidx_lab_build", "number", ["number","string","string"], [0, a, ""]);
    const n = 200, t0 = process.hrtime.bigint();
    let ev = 0;
    for (let i = 0; i < n; ++i) {
      M.ccall("sidx_lab_trace", "number", N7, [0, 6.3, 1.5, 2, -6, -0.2 - i * 0.001, -2]);
      ev += JSON.parse(M.ccall("sidx_lab_trace_json", "string", ["number"], [0])).events.length;
    }
    const ms = Number(process.hrtime.bigint() - t0) / 1e6 / n;
    console.log("page call for a new ray (teapot, " + a + ", " + (ev / n).toFixed(0) + " events): " + ms.toFixed(3) + " ms");
  }
  // primary rays in CPU time (the machine may be shared): the best of 3
  for (const a of ["bvh8", "bvh4", "kdtree", "bvh"]) {
    M.ccall("sidx_lab_build", "number", ["number","string","string"], [0, a, ""]);
    let best = 0;
    for (let k = 0; k < 3; ++k) {
      const c0 = process.cpuUsage();
      const r = JSON.parse(M.ccall("sidx_lab_bench", "string", N7, [0, 0.6, 0.4, 1, 256, 256, 5]));
      const c = process.cpuUsage(c0), ms = (c.user + c.system) / 1e3;
      best = Math.max(best, r.rays / ms / 1e3);
    }
    console.log("wasm cpu " + a + " " + best.toFixed(3));
  }
});' "$WEB/sidx-lab.js" >"$TMP/cpu.txt"
grep -v "^wasm cpu" "$TMP/cpu.txt"

# the same rays natively, in the process's CPU time
for a in bvh8 bvh4 kdtree bvh; do
    printf 'open teapot\nbuild 0 %s\nbench 0 0.6 0.4 1 256 256 5\nbench 0 0.6 0.4 1 256 256 5\nbench 0 0.6 0.4 1 256 256 5\n' "$a" |
        "$BUILD/bin/sidx-lab" | sed -n 's/.*"rays":\([0-9]*\).*"cpu_ms":\([0-9.]*\).*/\1 \2/p' |
        awk -v a="$a" '{ m = $1 / $2 / 1e3; if (m > best) best = m } END { printf "native cpu %s %.3f\n", a, best }'
done >>"$TMP/cpu.txt"
echo "primary rays, teapot, 256x256 x5, CPU time (best of 3):"
awk '/cpu/ { v[$1 " " $3] = $4; if (!seen[$3]++) order[++n] = $3 }
END { for (i = 1; i <= n; i++) { a = order[i]; printf "  %-8s native %8.3f Mrays/s   wasm %8.3f Mrays/s   wasm/native %.2f\n", a, v["native " a], v["wasm " a], v["wasm " a] / v["native " a] } }' "$TMP/cpu.txt"
