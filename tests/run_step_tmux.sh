#!/bin/sh
# run_step_tmux.sh — sidx-step's full-screen stepper in a real terminal.
#
#   BUILD=build sh tests/run_step_tmux.sh        (make test-run does this)
#
# Starts sidx-step inside a detached tmux session (its own server socket,
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

# start NAME ARGS...: sidx-step ARGS in a new session NAME
start() {
    name=$1
    shift
    $T new-session -d -s "$name" -x 120 -y 32 "$STEP $*" </dev/null || { bad "tmux new-session $name"; return 1; }
}

screen() { $T capture-pane -p -t "$1" 2>/dev/null; }

# wait_for NAME TEXT: until the screen of NAME shows TEXT (fixed string)
wait_for() {
    n=0
    while [ $n -lt "$WAIT" ]; do
        screen "$1" | grep -qF -- "$2" && return 0
        sleep 0.1
        n=$((n + 1))
    done
    return 1
}

# current NAME: the row of the current step (marked '>')
current() { screen "$1" | grep '^>'; }

# the K-th event line of the plain output, without its indentation
nth_event() { "$STEP" --accel "$1" $SCENE --ray $RAY --leaf-size 1 --all </dev/null | sed -n "$2p" | sed 's/^ *//'; }

echo "step-tmux: sidx-step in tmux $(tmux -V | cut -d' ' -f2)"

# ---- forward, back, go to step ----
start fb --accel bvh $SCENE --ray $RAY --leaf-size 1 || exit 1
total=$("$STEP" --accel bvh $SCENE --ray $RAY --leaf-size 1 --all </dev/null | wc -l | tr -d ' ')
if wait_for fb "step 1/$total "; then ok "starts at step 1 of $total"; else bad "no 'step 1/$total' on the screen"; fi
$T send-keys -t fb n n n n
wait_for fb "step 5/$total " || bad "four n keys did not reach step 5"
screen fb >"$TMP/at5"
$T send-keys -t fb Enter
wait_for fb "step 6/$total " || bad "Enter did not reach step 6"
$T send-keys -t fb b
if wait_for fb "step 5/$total " && screen fb | cmp -s - "$TMP/at5"; then
    ok "forward then back shows step 5 again, the same screen"
else
    bad "forward then back: the screen of step 5 differs"
    screen fb | diff "$TMP/at5" - | head -10
fi
$T send-keys -t fb Right
wait_for fb "step 6/$total " || bad "Right did not reach step 6"
$T send-keys -t fb Left
if wait_for fb "step 5/$total " && screen fb | cmp -s - "$TMP/at5"; then ok "Right then Left: step 5 again"; else bad "Right then Left"; fi
want=$(nth_event bvh 12)
$T send-keys -t fb g 12 Enter
if wait_for fb "step 12/$total " && current fb | grep -qF -- "$want"; then
    ok "g 12 Enter shows step 12: $want"
else
    bad "g 12 Enter: wanted step 12 '$want', current row: $(current fb)"
fi
$T send-keys -t fb a
if wait_for fb "step $total/$total " && current fb | grep -qF "ray 0 end"; then ok "a runs to the end"; else bad "a did not reach the end"; fi
$T send-keys -t fb q
n=0
while $T has-session -t fb 2>/dev/null && [ $n -lt "$WAIT" ]; do
    sleep 0.1
    n=$((n + 1))
done
if $T has-session -t fb 2>/dev/null; then bad "q did not end sidx-step"; else ok "q ends it"; fi

# ---- --break push, c, l (kd-tree, the deck's kD-Tree Traversal slides) ----
start br --accel kdtree $SCENE --ray $RAY --leaf-size 1 --break push || exit 1
if wait_for br "break: stack_push" && current br | grep -q "push node"; then
    ok "--break push stops on a push: $(current br | cut -c1-60)"
else
    bad "--break push: current row is '$(current br)'"
fi
if screen br | grep -q "^Stack: .*\["; then ok "the Stack line lists the pushed node"; else bad "no Stack line with a node"; fi
$T send-keys -t br l
if wait_for br "step 5/" && current br | grep -q "enter.*| [0-9]* leaf"; then
    ok "l stops on a leaf entered: $(current br | cut -c1-70)"
else
    bad "l: current row is '$(current br)'"
fi
$T send-keys -t br C
if wait_for br "step 3/" && current br | grep -q "push node"; then ok "C goes back to the push"; else bad "C: $(current br)"; fi
$T send-keys -t br q

# ---- c in a trace with several pushes (bvh) ----
start bc --accel bvh $SCENE --ray $RAY --leaf-size 1 --break push || exit 1
wait_for bc "break: stack_push"
first=$(current bc | awk '{print $2}')
$T send-keys -t bc c
n=0
while [ "$(current bc | awk '{print $2}')" = "$first" ] && [ $n -lt "$WAIT" ]; do
    sleep 0.1
    n=$((n + 1))
done
if [ "$(current bc | awk '{print $2}')" != "$first" ] && current bc | grep -q "push node"; then
    ok "c goes from the push at step $first to the next push at step $(current bc | awk '{print $2}')"
else
    bad "c: current row is '$(current bc)'"
fi
$T send-keys -t bc q

if [ $fail -ne 0 ]; then
    echo "step-tmux: FAILED"
    exit 1
fi
echo "step-tmux: all checks passed"
