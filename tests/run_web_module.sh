#!/bin/sh
# run_web_module.sh — the WebAssembly lab's answers against the native build's.
#
#   BUILD=build sh tests/run_web_module.sh        (make test-run does this)
#
# Runs the ray set tests/data/web/lab_rays.txt (the lecture scenes
# kd-slide and flat2d, the icosphere and the teapot; twenty structures
# with and without knobs; rays, the first step where two walks part,
# heat maps, bad files, a scene over the page's limit) through the lab's
# entry layer twice: natively (sidx-lab) and in the module the page
# embeds (build/web/sidx-lab.js, in Node: tests/web_module.js).  Every
# answer must agree byte for byte, except build and heat-map times and
# memory sizes (32-bit pointers in WebAssembly).  The built-in scenes,
# the teapot among them, are the same floats on both sides.  Also checks
# that a build's light answer is its full event list (the build mode's)
# less the SAH candidates, that the camera rays agree, that a trace's
# events are sidx-step --json's for the same ray and their lines
# sidx-step's (node labels too), that the page is one file under 3 MB
# holding the module, and that the ray set exercised what it names; then
# random addresses and OBJ files through the module (tests/web/lab_fuzz.js).
# Without node or without the module (make test builds it where emscripten
# is installed) it says so in one line and passes.  Run from the repository root.

BUILD=${BUILD:-build}
# the module lives beside the native tree: build/web (build/san/.. -> build/web)
case $BUILD in
*/san | */tsan) WEB=$(dirname "$BUILD")/web ;;
*) WEB=$BUILD/web ;;
esac
WEB=${WEB_DIR:-$WEB}
LAB=$BUILD/bin/sidx-lab
STEP=$BUILD/bin/sidx-step
RAYS=tests/data/web/lab_rays.txt
MAX_BYTES=3145728
LIMIT=${LIMIT:-600} # seconds: a hang detector, not a speed check

if ! command -v node >/dev/null 2>&1; then
    echo "web-module: skipped: node is not installed (Debian's emscripten brings it)"
    exit 0
fi
# another tree (BUILDDIR=build/clang) compares against the module make web built
[ -f "$WEB/sidx-lab.js" ] || [ -n "$WEB_DIR" ] || WEB=build/web
if [ ! -f "$WEB/sidx-lab.js" ]; then
    echo "web-module: skipped: no $WEB/sidx-lab.js (make web builds it with Debian's emscripten; make test does)"
    exit 0
fi
for p in "$LAB" "$STEP"; do
    if [ ! -x "$p" ]; then
        echo "web-module: FAILED: no $p"
        exit 1
    fi
done

TMP=${TMPDIR:-/tmp}/sidx-web-module-$$
mkdir -p "$TMP" || exit 1
trap 'rm -rf "$TMP"' EXIT
trap 'exit 1' INT TERM HUP
fail=0
ok() { echo "  ok    $1"; }
bad() {
    echo "  FAIL  $1"
    fail=1
}
# the answers with what may differ between runs and builds masked
mask() { sed -E 's/"(build_ms|ms|cpu_ms|mrays_per_s|bytes)":[0-9.e+-]*/"\1":T/g' "$1"; }

# 1. the page: one file, the module inside, under the limit
page=$WEB/sidx-lab.html
if [ -f "$page" ]; then
    size=$(wc -c <"$page")
    if [ "$size" -le $MAX_BYTES ] && grep -q 'data:application/octet-stream;base64,' "$page" &&
        ! grep -q '<script[^>]*src=' "$page"; then
        ok "page: $page, $size bytes (limit $MAX_BYTES), the module inlined, no script file"
    else
        bad "page: $page is $size bytes or does not inline the module"
    fi
else
    bad "page: no $page"
fi

# 2. the ray set, natively and in the module
sed "s|@TMP@|$TMP|g" "$RAYS" >"$TMP/rays.txt"
"$LAB" "$TMP/rays.txt" >"$TMP/native.txt" 2>"$TMP/native.err" || bad "sidx-lab failed: $(head -3 "$TMP/native.err")"
timeout "$LIMIT" node tests/web_module.js "$WEB/sidx-lab.js" "$TMP/rays.txt" >"$TMP/web.txt" 2>"$TMP/web.err" ||
    bad "the module failed in node: $(head -3 "$TMP/web.err")"
mask "$TMP/native.txt" >"$TMP/native.m"
mask "$TMP/web.txt" >"$TMP/web.m"
lines=$(wc -l <"$TMP/native.m")
if cmp -s "$TMP/native.m" "$TMP/web.m"; then
    ok "module = native: $lines lines, $(wc -c <"$TMP/native.m") bytes of answers, byte for byte"
else
    line=$(cmp "$TMP/native.m" "$TMP/web.m" 2>&1 | sed -n 's/.* line \([0-9]*\).*/\1/p')
    bad "module != native, first at line ${line:-?} of the answers:"
    [ -n "$line" ] && {
        echo "        native: $(sed -n "${line}p" "$TMP/native.m" | cut -c1-200)"
        echo "        module: $(sed -n "${line}p" "$TMP/web.m" | cut -c1-200)"
    }
fi

# 3. the ray set did what it says (a comparison of two empty outputs proves nothing)
count() { grep -c "$1" "$TMP/web.txt"; }
traces=$(grep -A1 '^> trace' "$TMP/web.txt" | grep -c '^rc 0')
hits=$(grep -c '^{"slot":[01],"accel":"[a-z0-9-]*","ray":.*"hit":{"prim"' "$TMP/web.txt")
parted=$(grep -c '^{"step":[1-9]' "$TMP/web.txt")
same=$(grep -c '^{"step":0,' "$TMP/web.txt")
if [ "$traces" -ge 150 ] && [ "$hits" -ge 100 ] && [ "$parted" -ge 20 ] && [ "$same" -ge 1 ]; then
    ok "ray set: $traces traces ($hits hits), walks parting $parted times, identical $same times"
else
    bad "ray set: $traces traces, $hits hits, $parted partings, $same identical walks (too few)"
fi
if grep -q "^rc 7 scene 'grid:512' has 524288 triangles; the page holds at most 50000" "$TMP/web.txt" &&
    grep -q '^rc 5 bad_index.obj:6: vertex index 4 out of range' "$TMP/web.txt" &&
    grep -q "^rc 1 knobs: --bins wants a whole number from 2" "$TMP/web.txt"; then
    ok "errors: the scene limit, a malformed OBJ's line and a bad knob, in the library's words"
else
    bad "errors: the module's messages for the scene limit, a bad OBJ or a bad knob are missing"
fi
# a build's answer (the page's rebuild) = its full event list (the build mode's) less the candidates
light=$(node -e '
const L = require("fs").readFileSync(process.argv[1], "utf8").split("\n");
const last = {};
let n = 0, cands = 0, bad = "";
for (let i = 0; i < L.length; ++i) {
  let m = /^> build (\d) /.exec(L[i]);
  if (m) { last[m[1]] = L[i + 2] === "null" ? null : JSON.parse(L[i + 2]); continue; }
  m = /^> events (\d)$/.exec(L[i]);
  if (!m) continue;
  const full = L[i + 1] === "null" ? null : JSON.parse(L[i + 1]), b = last[m[1]];
  if (!full !== !b) { bad = "line " + (i + 1) + ": an events answer without its build or the reverse"; break; }
  if (!full) continue;
  const c = full.build.filter((e) => e[0] === 2).length;
  cands += c;
  if (JSON.stringify(full.build.filter((e) => e[0] !== 2)) !== JSON.stringify(b.build) || b.build.some((e) => e[0] === 2) ||
      c !== b.cand_kept || full.cand_kept !== b.cand_kept || full.cand_total !== b.cand_total) {
    bad = "line " + (i + 1) + ": the build answer is not the full list less its " + c + " candidates"; break;
  }
  ++n;
}
console.log(bad ? "BAD " + bad : n + " " + cands);' "$TMP/web.txt")
case $light in
BAD*) bad "build answers: ${light#BAD }" ;;
*) set -- $light
    if [ "${1:-0}" -ge 4 ] && [ "${2:-0}" -ge 20000 ]; then
        ok "build answers: $1 are their full event lists less the candidates ($2 candidates in the full lists)"
    else
        bad "build answers: only ${1:-0} full lists with ${2:-0} candidates compared"
    fi ;;
esac
cams=$(grep -c '^{"o":\[' "$TMP/web.txt")
[ "$cams" -ge 6 ] && ok "camera rays: $cams compared bit for bit (9 significant digits)" || bad "camera rays: only $cams"
heats=$(count '^hash ')
[ "$heats" -ge 5 ] && ok "heat maps: $heats compared by hash" || bad "heat maps: only $heats"

# 4. a trace's events are sidx-step --json's (the page's "line" and "box" aside)
step_check() { # name scene accel ray knobflags...
    name=$1 scene=$2 accel=$3 ray=$4
    shift 4
    printf '%s %s\nbuild 0 %s %s\ntrace 0 %s\n' "$( [ -f "$scene" ] && echo obj || echo open)" "$scene" "$accel" \
        "$KNOBS" "$(echo "$ray" | tr ',' ' ')" >"$TMP/one.txt"
    # the trace's JSON: the lines after "> trace ..." and its "rc 0" line
    timeout "$LIMIT" node tests/web_module.js "$WEB/sidx-lab.js" "$TMP/one.txt" |
        awk '/^> trace/ { t = 1; getline; next } t' >"$TMP/one.json"
    # each event's text as the module wrote it, less the page's "box" and "line" (no re-serialising)
    node -e '
const s = require("fs").readFileSync(process.argv[1], "utf8").trimEnd();
const body = s.slice(s.indexOf("\"events\":[") + 10, -2);
for (const e of body.split(",\n"))
  console.log(e.replace(/,"box":\[[^\]]*\]/, "").replace(/,"line":"(?:[^"\\]|\\.)*"\}$/, "}"));' "$TMP/one.json" \
        >"$TMP/one.page"
    "$STEP" --accel "$accel" "$scene" --ray "$ray" --json --all "$@" >"$TMP/one.step"
    n=$(wc -l <"$TMP/one.step")
    if [ "$n" -gt 3 ] && cmp -s "$TMP/one.page" "$TMP/one.step"; then
        ok "sidx-step --json = module: $name, $n events"
    else
        bad "sidx-step --json != module: $name ($n events)"
    fi
    # each event's "line" (the page's event list) is sidx-step's line, node labels and all
    node -e '
const t = JSON.parse(require("fs").readFileSync(process.argv[1], "utf8"));
for (const e of t.events) console.log(e.line);' "$TMP/one.json" >"$TMP/one.lines"
    "$STEP" --accel "$accel" "$scene" --ray "$ray" --all "$@" >"$TMP/one.text"
    labels=$(grep -c '  \[[A-Z][A-Z0-9]*\]$' "$TMP/one.text")
    if [ "$n" -gt 3 ] && cmp -s "$TMP/one.lines" "$TMP/one.text"; then
        ok "sidx-step's lines = module's: $name ($labels with a node label)"
    else
        bad "sidx-step's lines != module's: $name, first at $(cmp "$TMP/one.lines" "$TMP/one.text" 2>&1 | sed -n 's/.* line //p')"
    fi
    [ -z "$WANT_LABELS" ] || [ "$labels" -ge "$WANT_LABELS" ] || bad "$name: only $labels labelled lines"
}
KNOBS="" WANT_LABELS=10 step_check "kd-slide, the slide's kd-tree" kd-slide kdtree 0,4.2,0,1,0.15,0
WANT_LABELS= KNOBS='{"bins":8,"mailbox":false}' step_check "kd-slide, grid with knobs" kd-slide grid 0,4.2,0,1,0.15,0 --bins 8 --no-mailbox
WANT_LABELS= KNOBS="" step_check "teapot, bvh8" teapot bvh8 6.3,1.5,2,-6,-0.2,-2
WANT_LABELS= KNOBS='{"traversal":"naive"}' step_check "teapot, kdtree naive" teapot kdtree 6.3,1.5,2,-6,-0.2,-2 --traversal naive

# 5. random addresses and OBJ files through the module (tests/web/lab_fuzz.js): every
# answer JSON, every refusal with a message; LAB_FUZZ=N for more (by hand: 20000)
if out=$(timeout "$LIMIT" node tests/web/lab_fuzz.js "$WEB/sidx-lab.js" "${LAB_FUZZ:-1000}" "${LAB_FUZZ_SEED:-1}" 2>&1); then
    ok "$(echo "$out" | tail -1 | sed 's/^lab-fuzz: //')"
else
    bad "$(echo "$out" | tail -3)"
fi

if [ $fail -ne 0 ]; then
    echo "web-module: FAILED"
    exit 1
fi
echo "web-module: the WebAssembly module answers as the native library does"
