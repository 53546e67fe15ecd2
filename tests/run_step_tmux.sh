#!/bin/sh
# run_step_tmux.sh — sidx-step's full-screen stepper in a real terminal.
#
#   BUILD=build sh tests/run_step_tmux.sh        (make test-run does this)
#
# Starts sidx-step inside tmux, detached (its own server socket,
# no configuration file, a fixed 120x32 screen), types keys with
# `tmux send-keys` and reads the screen back with `tmux capture-pane -p`.
# Checks that one step forward and one back redraws the same screen, that
# g K Enter shows step K (the K-th line of the --all output), that --break
# push and c stop on stack pushes, l on a leaf, and that q ends the
# program.  Needs no terminal of its own (runs under CI with stdin from
# /dev/null); every wait gives up after $WAIT tenths of a second.  Without
# tmux it says so in one line and passes.  Run from the repository root.

BUILD=${BUILD:-build}
STEP=$BUILD/bin/sidx-step
SCENE=tests/data/viz/tiny.obj
RAY=8,0.2,0.2,-1,0,0
WAIT=${WAIT:-100}

if ! command -v tmux >/dev/null 2>&1; then
    echo "step-tmux: skipped: tmux is not installed (make deps installs it)"
    exit 0
fi
if [ ! -x "$STEP" ]; then
    echo "step-tmux: FAILED: no $STEP"
    exit 1
fi

SOCK=sidx-step-test-$$
T="tmux -L $SOCK -f /dev/null"
TMP=${TMPDIR:-/tmp}/sidx-step-test-$$
mkdir -p "$TMP" || exit 1
cleanup() { $T kill-server >/dev/null 2>&1; rm -rf "$TMP"; }
trap cleanup EXIT
trap 'exit 1' INT TERM HUP
fail=0

ok() { echo "  ok    $1"; }
bad() { echo "  FAIL  $1"; fail=1; }

# start NAME ARGS...: sidx-step ARGS in a new detached tmux screen NAME
start() {
    name=$1
    shift
    $T new -d -s "$name" -x 120 -y 32 "$STEP $*" </dev/null || { bad "tmux new $name"; return 1; }
}

screen() { $T capture-pane -p -t "$1" 2>/dev/null; }

# until_ok COMMAND...: run it every tenth of a second until it succeeds, $WAIT times at most
until_ok() {
    n=0
    until "$@"; do
        [ $n -ge "$WAIT" ] && return 1
        sleep 0.1
        n=$((n + 1))
    done
}

shows() { screen "$1" | grep -qF -- "$2"; }
gone() { ! $T has -t "$1" 2>/dev/null; }
# wait_for NAME TEXT: until the screen of NAME shows TEXT (fixed string)
wait_for() { until_ok shows "$1" "$2"; }

# current NAME: the row of the current step (marked '>'); step_of NAME: its number
current() { screen "$1" | grep '^>'; }
# lands NAME TEXT ROW WHAT: the screen shows TEXT with ROW in the current row
# (both waited for: the title may be drawn before the rows below it)
shows_row() { shows "$1" "$2" && current "$1" | grep -qF -- "$3"; }
lands() {
    if until_ok shows_row "$1" "$2" "$3"; then
        ok "$4: $(current "$1" | cut -c1-60)"
    else
        bad "$4: wanted '$3' in the current row, got '$(current "$1")'"
    fi
}
step_of() { current "$1" | awk '{print $2}'; }
moved() { [ "$(step_of "$1")" != "$2" ]; }

# the K-th event line of the plain output, without its indentation
nth_event() { "$STEP" --accel "$1" $SCENE --ray $RAY --leaf-size 1 --all </dev/null | sed -n "$2p" | sed 's/^ *//'; }

echo "step-tmux: sidx-step in tmux $(tmux -V | cut -d' ' -f2)"
# a screen that outlives the others, so the server does not exit between them
$T new -d -s hold "sleep 300" </dev/null || { echo "step-tmux: FAILED: tmux cannot start a server"; exit 1; }

# ---- forward, back, go to step ----
start fb --accel bvh $SCENE --ray $RAY --leaf-size 1 || exit 1
total=$("$STEP" --accel bvh $SCENE --ray $RAY --leaf-size 1 --all </dev/null | wc -l | tr -d ' ')
lands fb "step 1/$total " "ray 0 begin" "starts at step 1 of $total"
$T send-keys -t fb n n n n
wait_for fb "step 5/$total " || bad "four n keys did not reach step 5"
screen fb >"$TMP/at5"
for keys in "Enter b" "Right Left"; do
    $T send-keys -t fb ${keys% *}
    wait_for fb "step 6/$total " || bad "${keys% *} did not reach step 6"
    $T send-keys -t fb ${keys#* }
    if wait_for fb "step 5/$total " && screen fb | cmp -s - "$TMP/at5"; then
        ok "$keys: forward then back shows step 5 again, the same screen"
    else
        bad "$keys: the screen of step 5 differs"
        screen fb | diff "$TMP/at5" - | head -10
    fi
done
want=$(nth_event bvh 12)
$T send-keys -t fb g 12 Enter
lands fb "step 12/$total " "$want" "g 12 Enter shows step 12: $want"
$T send-keys -t fb a
lands fb "step $total/$total " "ray 0 end" "a runs to the end"
$T send-keys -t fb q
if until_ok gone fb; then ok "q ends it"; else bad "q did not end sidx-step"; fi

# ---- --break push, l, C (kd-tree, the deck's kD-Tree Traversal slides) ----
start br --accel kdtree $SCENE --ray $RAY --leaf-size 1 --break push || exit 1
lands br "break: stack_push" "push node" "--break push stops on a push"
if screen br | grep -q "^Stack: .*\["; then ok "the Stack line lists the pushed node"; else bad "no Stack line with a node"; fi
# which steps these are depends on the tree: wait for the step to change,
# then read what the current row shows
at=$(step_of br)
$T send-keys -t br l
if until_ok moved br "$at" && current br | grep -qF " leaf ["; then
    ok "l stops on a leaf entered: step $at -> $(step_of br)"
else
    bad "l: wanted ' leaf [' in the current row, got '$(current br)'"
fi
at=$(step_of br)
$T send-keys -t br C
if until_ok moved br "$at" && current br | grep -qF "push node"; then
    ok "C goes back to the push: step $at -> $(step_of br)"
else
    bad "C: wanted 'push node' in the current row, got '$(current br)'"
fi
$T send-keys -t br q
until_ok gone br || bad "q did not end sidx-step"

# ---- c in a trace with several pushes (bvh) ----
start bc --accel bvh $SCENE --ray $RAY --leaf-size 1 --break push || exit 1
wait_for bc "break: stack_push"
first=$(step_of bc)
$T send-keys -t bc c
if until_ok moved bc "$first" && current bc | grep -qF "push node"; then
    ok "c goes from the push at step $first to the next push at step $(step_of bc)"
else
    bad "c: current row is '$(current bc)'"
fi
$T send-keys -t bc q

if [ $fail -ne 0 ]; then
    echo "step-tmux: FAILED"
    exit 1
fi
echo "step-tmux: all checks passed"
