#!/bin/sh
# run_sandbox.sh — the students' code contained, for root and for a user.
#
#   BUILD=build sh tests/run_sandbox.sh        (make test-run does this)
#
# A class of two: "hostile" solves 14_bsp_painter but first tries, in
# every case, to write ../../NAME (above its directory), a file in /tmp
# and one in the class folder, to read the reference solution, to connect
# to a listener on 127.0.0.1, to fork 20 processes and to reach every
# process with kill(-1, 0) (signal 0: nothing is sent); "borrower" hands in
# 01_ray_triangle calling the library's own tests.  sidx-check --class
# runs it as root and as the user nobody (setpriv; run as a user, the test
# runs it as that user only).  Contained, nothing is written or read,
# nothing connects, no fork succeeds, kill(-1) finds no process, and the student's report and the
# class summary list every attempt and the borrowed answer.  Then the same
# class with --unsafe, the sandbox off: the files appear, the reference is
# read, the connection is made, kill(-1) finds processes (as root the forks
# succeed too) and the
# report says NOT CONTAINED — each check above can fail.  As root, also:
# where the sandbox cannot be set up (user namespaces refused to the user,
# in a user namespace whose limit is 0) class mode refuses to run, and a
# single check says so on its first line; an 8 GB malloc under the memory
# limit is reported as out of memory.  About 6 s of CPU.

BUILD=${BUILD:-build}
CHECK=$BUILD/bin/sidx-check
case $BUILD in
*/san | */tsan) echo "sandbox: skipped under the sanitizers (ASan takes no memory limit; the sandbox is the same code)"; exit 0 ;;
esac
SOL=lessons/exercises/solutions
if [ ! -d "$SOL" ]; then echo "sandbox: skipped (no $SOL: a hand-out tree)"; exit 0; fi
if [ ! -x "$CHECK" ]; then echo "sandbox: no $CHECK"; exit 1; fi
command -v python3 >/dev/null || { echo "sandbox: skipped (no python3 for the listener)"; exit 0; }

T=$(mktemp -d /tmp/sidx-sandbox-test-XXXXXX) || exit 1
REL=sidx-sandbox-escape-$$.txt # ../../REL from the case's directory, /tmp/sidx-check-run-*/case-*: /tmp/REL
LPID=
trap 'rm -rf "$T" "/tmp/$REL"; [ -n "$LPID" ] && kill $LPID 2>/dev/null' EXIT
chmod 755 "$T"
C=$T/class
mkdir -p "$C/hostile" "$C/borrower" "$T/out" "$T/rep"
chmod 1777 "$C" "$T/out" "$T/rep"
fail=0
bad() { echo "sandbox: FAIL: $*"; fail=1; }

# a listener on 127.0.0.1 that accepts every connection
python3 -c '
import socket, sys
s = socket.socket(); s.bind(("127.0.0.1", 0)); s.listen(64)
s.settimeout(300)  # stops by itself once nothing has connected for 5 minutes
print(s.getsockname()[1], flush=True)
while True:
    c, _ = s.accept(); c.close()
' >"$T/port" 2>/dev/null &
LPID=$!
n=0
while [ ! -s "$T/port" ] && [ $n -lt 300 ]; do sleep 0.1; n=$((n + 1)); done # 30 s: a loaded machine
PORT=$(cat "$T/port")
[ -n "$PORT" ] || { echo "sandbox: FAIL: no listener"; exit 1; }

REF=$(pwd)/$SOL/14_bsp_painter.c
python3 - "$SOL/14_bsp_painter.c" "$C/hostile/14_bsp_painter.c" "../../$REL" "$T/out/escape-tmp.txt" \
    "$C/escape-class.txt" "$REF" "$PORT" <<'EOF' || exit 1
import sys
src, dst, rel, tmpf, classf, ref, port = sys.argv[1:]
s = open(src).read()
esc = r'''#include <signal.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
static void escape(void)
{
    int wrote = 0, read = 0, connected = 0, forks = 0, signalled = 0;
    const char *out[] = {"REL", "TMPF", "CLASSF"};
    for (int k = 0; k < 3; ++k) {
        FILE *f = fopen(out[k], "w");
        if (f) wrote += fputs("escaped\n", f) >= 0, fclose(f);
    }
    FILE *f = fopen("REF", "r");
    if (f) read = 1, fclose(f);
    const int s = socket(AF_INET, SOCK_STREAM, 0);
    struct sockaddr_in a;
    memset(&a, 0, sizeof a);
    a.sin_family = AF_INET;
    a.sin_port = htons(PORT);
    a.sin_addr.s_addr = htonl(0x7f000001);
    if (s >= 0 && connect(s, (struct sockaddr *)&a, sizeof a) == 0) connected = 1;
    if (s >= 0) close(s);
    for (int k = 0; k < 20; ++k) { /* a fork loop */
        const pid_t p = fork();
        if (p == 0) {
            pause();
            _exit(0);
        }
        if (p < 0) break;
        ++forks;
    }
    signalled = kill(-1, 0) == 0; /* signal 0: asks whether any other process is in reach, sends nothing */
    printf("escape: wrote %d read %d connected %d forks %d signalled %d\n", wrote, read, connected, forks, signalled);
}
'''
for k, v in (("REL", rel), ("TMPF", tmpf), ("CLASSF", classf), ("REF", ref), ("PORT", port)):
    esc = esc.replace(k, v)
anchor = "{\n    paint(bsp, 0, 0, eye, ex);"
if anchor not in s: sys.exit("the solution of 14 changed: " + anchor)
open(dst, "w").write(esc + s.replace(anchor, "{\n    escape();\n    paint(bsp, 0, 0, eye, ex);", 1))
EOF
cp tests/exercises/borrowed/01_ray_triangle--calls.c "$C/borrower/01_ray_triangle.c"
chmod 644 "$C"/*/*.c

# as ID (root or nobody), contained (MODE "") or not (MODE --unsafe)
as() {
    id=$1
    shift
    if [ "$id" = root ] || [ "$id" = "$(id -un)" ]; then "$@"; else setpriv --reuid="$id" --regid=nogroup --clear-groups "$@"; fi
}
class() {
    id=$1
    mode=$2
    R=$T/rep/$id$mode
    rm -f "/tmp/$REL" "$T/out/escape-tmp.txt" "$C/escape-class.txt"
    as "$id" "$CHECK" --class "$C" --out "$R" --jobs 2 --timeout 5 $mode >"$T/log" 2>&1
    rc=$?
    [ "$rc" = 1 ] || { bad "$id$mode: class mode exit $rc, not 1:"; sed 's/^/  | /' "$T/log" | head -20; }
    [ -s "$R/summary.md" ] || bad "$id$mode: no summary"
    [ -s "$R/hostile.txt" ] || bad "$id$mode: no report of hostile"
}
# the report and the summary list every attempt
listed() {
    id=$1
    mode=$2
    R=$T/rep/$id$mode
    for what in "write    ../../$REL" "write    $T/out/escape-tmp.txt" "write    $C/escape-class.txt" \
        "read     $REF" "connect  127.0.0.1:$PORT" "process  fork"; do
        grep -qF "$what" "$R/hostile.txt" || bad "$id$mode: hostile's report does not list \"$what\""
    done
    for what in "**hostile**, \`14_bsp_painter\`: tried outside its directory: write ../../$REL" \
        "read $REF" "connect 127.0.0.1:$PORT" \
        "**borrower**, \`01_ray_triangle\`: borrowed answer: uses sidx_intersect_plane, which this exercise asks you to write"; do
        grep -qF "$what" "$R/summary.md" || bad "$id$mode: the class summary does not list \"$what\""
    done
}
contained() {
    id=$1
    class "$id" ""
    R=$T/rep/$id
    listed "$id" ""
    for f in "/tmp/$REL" "$T/out/escape-tmp.txt" "$C/escape-class.txt"; do
        [ ! -e "$f" ] || bad "$id: the hostile code wrote $f"
    done
    # ../../REL lands in the case's own directory, the sandbox's /: one write succeeds there
    grep -q "write    ../../$REL  (case 1, [0-9][0-9]* times: done inside its own directory)" "$R/hostile.txt" ||
        bad "$id: the write to ../../ is not reported as kept inside"
    grep -q "escape: wrote 1 read 0 connected 0 forks 0 signalled 0" "$R/hostile.txt" ||
        { bad "$id: the hostile code got out:"; grep "escape:" "$R/hostile.txt" | head -3; }
    grep -q "write    $T/out/escape-tmp.txt  (case 1, [0-9][0-9]* times: No such file or directory)" "$R/hostile.txt" ||
        bad "$id: the write to /tmp is not reported as refused"
    grep -q "connect  127.0.0.1:$PORT  (case 1, [0-9][0-9]* times: Network is unreachable)" "$R/hostile.txt" ||
        bad "$id: the connection is not reported as refused"
    grep -q "process  fork  (case 1, [0-9][0-9]* times: Resource temporarily unavailable)" "$R/hostile.txt" ||
        bad "$id: the fork loop is not reported as stopped"
    grep -q "signal   signal 0 to every process (kill -1)  (case 1, [0-9][0-9]* times: No such process)" "$R/hostile.txt" ||
        bad "$id: kill(-1) is not reported as reaching nothing"
    grep "^| hostile |" "$R/summary.md" | grep -qF "| pass (escape attempt) |" || bad "$id: the summary's table does not mark the attempt"
    grep -q "NOT CONTAINED" "$R/summary.md" "$R/hostile.txt" && bad "$id: contained, but the report says NOT CONTAINED"
}
# the sandbox off: the same attempts succeed, so the checks above can fail
uncontained() {
    id=$1
    class "$id" --unsafe
    R=$T/rep/$id--unsafe
    listed "$id" --unsafe
    for f in "/tmp/$REL" "$T/out/escape-tmp.txt" "$C/escape-class.txt"; do
        [ -e "$f" ] || bad "$id --unsafe: $f not written: the check that it is not cannot fail"
    done
    grep -q "escape: wrote 3 read 1 connected 1" "$R/hostile.txt" ||
        { bad "$id --unsafe: the attempts did not succeed without the sandbox:"; grep "escape:" "$R/hostile.txt" | head -2; }
    if [ "$id" = root ]; then # root: RLIMIT_NPROC does not bind, the sandbox's nobody is what stops the loop
        grep -q "escape: wrote 3 read 1 connected 1 forks 20 signalled 1" "$R/hostile.txt" || bad "root --unsafe: the fork loop was stopped all the same"
    else # a user: RLIMIT_NPROC stops the forks even uncontained; kill(-1) reaches its other processes
        grep -q "escape: wrote 3 read 1 connected 1 forks 0 signalled 1" "$R/hostile.txt" || bad "$id --unsafe: kill(-1) reached nothing"
    fi
    grep -q "NOT CONTAINED" "$R/hostile.txt" || bad "$id --unsafe: the report does not say NOT CONTAINED"
    grep -q "NOT CONTAINED (--unsafe)" "$R/summary.md" || bad "$id --unsafe: the summary does not say NOT CONTAINED"
}

ids=$(id -un)
if [ "$(id -u)" = 0 ]; then
    if setpriv --reuid=nobody --regid=nogroup --clear-groups sh -c "test -r '$CHECK' && test -r '$SOL/14_bsp_painter.c' && test -r lib/include/sidx/sidx.h && test -r '$BUILD/lib/libsidx.a'"; then
        ids="root nobody"
    else
        echo "sandbox: the user nobody cannot read the build ($BUILD) or the sources: run as root only"
    fi
fi
for id in $ids; do
    contained "$id"
    uncontained "$id"
done

if [ "$(id -u)" = 0 ]; then
    # Out of memory: a malloc of 8 GB under the limit, then written to
    python3 - "$SOL/03_ray_box.c" "$T/oom.c" <<'EOF' || exit 1
import re, sys
s = open(sys.argv[1]).read()
m = re.search(r'\nint ray_box\([^)]*\)\n\{\n', s)
open(sys.argv[2], "w").write("#include <stdlib.h>\n" + s[:m.end()] + "    char *big = malloc(8ul << 30);\n    big[0] = 1;\n" + s[m.end():])
EOF
    "$CHECK" 03_ray_box "$T/oom.c" >"$T/log" 2>&1
    grep -q "your code ran out of memory (the limit is 1024 MiB per case; malloc(8589934592) returned NULL)" "$T/log" ||
        { bad "the 8 GB malloc is not reported as out of memory:"; sed 's/^/  | /' "$T/log" | head -5; }
    # No sandbox possible: a user in a user namespace whose limit on new
    # ones is 0 (as on a system that refuses them to users)
    python3 - "$CHECK" "$C" "$T/rep/refused" "$SOL/01_ray_triangle.c" >"$T/log" 2>&1 <<'EOF'
import ctypes, os, sys
check, cls, out, sol = sys.argv[1:]
libc = ctypes.CDLL(None, use_errno=True)
r, w = os.pipe()
r2, w2 = os.pipe()
pid = os.fork()
if pid == 0:
    os.close(w)
    if libc.unshare(0x10000000) != 0: os._exit(3)  # CLONE_NEWUSER
    os.write(w2, b"x")
    os.read(r, 1)  # the parent has written the maps
    open("/proc/sys/user/max_user_namespaces", "w").write("0\n")
    os.setgroups([]); os.setresgid(65534, 65534, 65534); os.setresuid(65534, 65534, 65534)
    a = os.spawnv(os.P_WAIT, check, [check, "--class", cls, "--out", out])
    print("class-exit", a, flush=True)
    os.execv(check, [check, "01_ray_triangle", sol])
os.close(r)
os.read(r2, 1)  # the child is in its user namespace
for f, m in (("uid_map", "0 0 65535\n"), ("setgroups", "allow\n"), ("gid_map", "0 0 65535\n")):
    open("/proc/%d/%s" % (pid, f), "w").write(m)
os.write(w, b"x")
_, st = os.waitpid(pid, 0)
print("single-exit", os.waitstatus_to_exitcode(st))
EOF
    grep -q "^class-exit 2$" "$T/log" && grep -q "the sandbox cannot be set up here" "$T/log" ||
        { bad "class mode ran where the sandbox cannot be set up:"; sed 's/^/  | /' "$T/log" | head -8; }
    [ "$(grep -m1 '^sidx-check 01_ray_triangle' "$T/log" | cut -c1-60)" = "sidx-check 01_ray_triangle: NOT CONTAINED: the sandbox canno" ] ||
        { bad "uncontained, a single check does not say so first:"; sed 's/^/  | /' "$T/log" | head -8; }
fi
[ $fail = 0 ] && echo "sandbox: contained as $(echo $ids | sed 's/ / and as /'): writes outside, the reference, the network and forks refused and listed; each shown to get through with --unsafe"
exit $fail
