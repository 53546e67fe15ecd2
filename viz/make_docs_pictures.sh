#!/bin/sh
# make_docs_pictures.sh — regenerate docs/img/: the Graphviz tree of every
# registered tree structure over the teapot (cut at depth 5, with one ray),
# and sidx-view screenshots of every structure on the 2D lecture scene
# (traversal half-way, and the build with the SAH curve; each shape drawn
# with its spine, the segment a ray in the plane hits), plus 3D and heat
# views of the teapot, the few further views the tutorial's lessons show
# (heat maps of the teapot in the stadium, the BVH's first level); and the
# web pages of the tutorial's main examples (sidx-view --html) into WEB_DIR,
# with a headless Chromium screenshot of one of them when chromium is installed.
#
#   sh viz/make_docs_pictures.sh [BUILD_DIR] [OUT_DIR] [WEB_DIR]
#                                          (defaults: build, docs/img, docs/web)
#
# Run from the repository root after `make`.  Needs no display: sidx-view
# renders headless.  Structures that do not emit a tree (brute, the uniform
# grid) get no tree picture; the script says so and goes on.
set -u

BUILD=${1:-build}
OUT=${2:-docs/img}
WEB=${3:-docs/web}
BIN=$BUILD/bin
for p in sidx-dot sidx-view; do
  if [ ! -x "$BIN/$p" ]; then
    echo "make_docs_pictures: $BIN/$p not found; run make first" >&2
    exit 1
  fi
done
mkdir -p "$OUT" || exit 1

# A ray from in front of the teapot, slightly downwards, through the body.
TEAPOT_RAY=0,0.6,4,0,-0.05,-1
failed=0

names=$("$BIN/sidx-dot" --list | awk '{print $1}')
for a in $names; do
  # wide trees (many children per node) get sidx-dot's default depth, binary trees 5 levels;
  # either way siblings past the page's width fold into one "... N more" box
  case $a in grid2|bvh4|bvh8|octree|quadtree|rayclass) depth="" ;; *) depth=5 ;; esac
  if "$BIN/sidx-dot" --accel "$a" teapot ${depth:+--depth $depth} --ray "$TEAPOT_RAY" -o "$OUT/tree-$a-teapot.svg" >/dev/null 2>"$OUT/.err"; then
    if [ "$(wc -c < "$OUT/tree-$a-teapot.svg")" -gt 2000000 ]; then
      rm -f "$OUT/tree-$a-teapot.svg"   # thousands of siblings: no one reads that picture
      echo "  (no tree picture for $a: too wide to draw)"
    else
      echo "  $OUT/tree-$a-teapot.svg"
    fi
  else
    echo "  (no tree picture for $a: $(cat "$OUT/.err"))"
  fi
  "$BIN/sidx-dot" --accel "$a" flat2d ${depth:+--depth 4} -o "$OUT/tree-$a-flat2d.svg" >/dev/null 2>&1 &&
    echo "  $OUT/tree-$a-flat2d.svg"

  # 2D traversal: the screenshot at the middle of the recorded events
  total=$("$BIN/sidx-view" --accel "$a" --screenshot "$OUT/view2d-$a.png" --size 1100x700 |
          sed -n 's|.*step [0-9]*/\([0-9]*\)).*|\1|p')
  if [ -n "$total" ]; then
    half=$((total / 2))
    "$BIN/sidx-view" --accel "$a" --step "$half" --screenshot "$OUT/view2d-$a.png" --size 1100x700 >/dev/null &&
      echo "  $OUT/view2d-$a.png (step $half of $total)"
  else
    echo "  sidx-view failed for $a" >&2
    failed=1
  fi
  # build, a third of the way through
  btotal=$("$BIN/sidx-view" --accel "$a" --mode build --screenshot "$OUT/build2d-$a.png" |
           sed -n 's|.*step [0-9]*/\([0-9]*\)).*|\1|p')
  if [ -n "$btotal" ] && [ "$btotal" -gt 0 ]; then
    "$BIN/sidx-view" --accel "$a" --mode build --step $((btotal / 3)) --screenshot "$OUT/build2d-$a.png" >/dev/null &&
      echo "  $OUT/build2d-$a.png"
  fi
done

for a in bvh kdtree; do
  echo "$names" | grep -qx "$a" || continue
  "$BIN/sidx-view" --accel "$a" --scene teapot --mode 3d --level 3 --screenshot "$OUT/view3d-$a-teapot.png" >/dev/null &&
    echo "  $OUT/view3d-$a-teapot.png"
  "$BIN/sidx-view" --accel "$a" --scene teapot --mode heat --screenshot "$OUT/heat-$a-teapot.png" >/dev/null &&
    echo "  $OUT/heat-$a-teapot.png"
done

# ---- pictures the tutorial's lessons show besides the ones above ----
# Lesson 08 (and 13): the teapot in the stadium, heat of steps per pixel,
# zoomed on the teapot: the grid spends thousands of steps in the one cell
# that holds the teapot, the BVH a few dozen everywhere.
for a in grid bvh; do
  echo "$names" | grep -qx "$a" || continue
  "$BIN/sidx-view" --accel "$a" --scene stadium --mode heat --zoom 3 --size 550x350 \
      --screenshot "$OUT/heat-$a-stadium.png" >/dev/null &&
    echo "  $OUT/heat-$a-stadium.png"
done
# Lesson 20: the grid's heat on the teapot beside the trees' (above).
if echo "$names" | grep -qx grid; then
  "$BIN/sidx-view" --accel grid --scene teapot --mode heat --screenshot "$OUT/heat-grid-teapot.png" >/dev/null &&
    echo "  $OUT/heat-grid-teapot.png"
fi
# Lessons 02 and 19: the two boxes below the BVH's root, around the object.
if echo "$names" | grep -qx bvh; then
  "$BIN/sidx-view" --accel bvh --scene teapot --mode 3d --level 1 --size 550x350 \
      --screenshot "$OUT/view3d-bvh-teapot-level1.png" >/dev/null &&
    echo "  $OUT/view3d-bvh-teapot-level1.png"
fi
# ---- end of the lessons' pictures ----
# deck 000 "kD-Tree Example" / "Traversal (1)-(11)": the slide's tree and ray, its nodes named
# as the slide names them (lesson 25)
if echo "$names" | grep -qx kdtree; then
  KD_SLIDE_RAY=0,4.2,0,1,0.15,0
  "$BIN/sidx-dot" --accel kdtree kd-slide --ray "$KD_SLIDE_RAY" -o "$OUT/tree-kdtree-kd-slide.svg" >/dev/null &&
    echo "  $OUT/tree-kdtree-kd-slide.svg"
  "$BIN/sidx-view" --accel kdtree --scene kd-slide --ray "$KD_SLIDE_RAY" --step 14 --size 1100x700 \
    --screenshot "$OUT/view2d-kdtree-kd-slide.png" >/dev/null && echo "  $OUT/view2d-kdtree-kd-slide.png"
fi

# Web pages: one self-contained HTML file each (build and traversal in one
# page), for the structures the tutorial steps through.
mkdir -p "$WEB" || exit 1
page() { # NAME ACCEL SCENE [sidx-view options...]
  name=$1 a=$2 scene=$3
  shift 3
  echo "$names" | grep -qx "$a" || return 0
  if "$BIN/sidx-view" --accel "$a" --scene "$scene" "$@" --html "$WEB/$name.html" >/dev/null; then
    echo "  $WEB/$name.html ($(wc -c < "$WEB/$name.html") bytes)"
  else
    echo "  sidx-view --html failed for $name" >&2
    failed=1
  fi
}
page bvh-flat2d bvh flat2d
page kdtree-flat2d kdtree flat2d
page grid-flat2d grid flat2d
page quadtree-flat2d quadtree flat2d
page bsp-flat2d bsp flat2d
page bvh-teapot bvh teapot --ray "$TEAPOT_RAY" --mode 3d --level 3
page kdtree-teapot kdtree teapot --ray "$TEAPOT_RAY" --mode 3d --level 3
if command -v chromium >/dev/null 2>&1 && [ -f "$WEB/kdtree-flat2d.html" ]; then
  profile=$(mktemp -d)
  chromium --headless --no-sandbox --disable-gpu --disable-quic --no-first-run --disable-background-networking \
    --disable-component-update --disable-sync --hide-scrollbars --user-data-dir="$profile" --window-size=1100,700 \
    --screenshot="$OUT/web-kdtree-flat2d.png" "file://$(cd "$WEB" && pwd)/kdtree-flat2d.html#step=20" >/dev/null 2>&1 &&
    echo "  $OUT/web-kdtree-flat2d.png (headless Chromium, step 20)"
  rm -rf "$profile"
else
  echo "  (no screenshot of a page: chromium is not installed)"
fi
rm -f "$OUT/.err"
exit $failed
