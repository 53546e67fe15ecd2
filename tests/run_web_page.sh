#!/bin/sh
# run_web_page.sh — the web pages in headless Chromium, driven through the
# DevTools protocol with real mouse and key events (tests/web/).
#
#   BUILD=build sh tests/run_web_page.sh        (make test-run does this)
#
# First the protocol client on sidx-view --html's recorded page
# (tests/web/view_page_test.js), then the lab page BUILD/web/sidx-lab.html
# (tests/web/lab_test.js; WEB is BUILD/web unless WEB_DIR is set):
# rays from the address, dragged in 2D and clicked in 3D, knobs,
# structures, a bad OBJ, heat map, side by side and the page offline, each
# against the native programs of BUILD.  Screenshots go to WEB/screens/.
# Without node or chromium it says so in one line and passes; without the
# built lab page (make web, which needs emscripten) that part says so in
# one line.  Each part is stopped after a fixed time if it hangs.

BUILD=${BUILD:-build}
export BUILD
# the page make web writes for this tree (WEB_DIR=DIR names another)
WEB=${WEB_DIR:-$BUILD/web}

if ! command -v node >/dev/null 2>&1; then
    echo "web-page: skipped: node is not installed (make deps installs nodejs)"
    exit 0
fi
if ! command -v chromium >/dev/null 2>&1 && ! command -v chromium-browser >/dev/null 2>&1; then
    echo "web-page: skipped: chromium is not installed (make deps installs it)"
    exit 0
fi

fail=0
timeout -k 5 180 node tests/web/view_page_test.js "$BUILD" || fail=1
if [ -f "$WEB/sidx-lab.html" ]; then
    timeout -k 5 600 node tests/web/lab_test.js "$BUILD" "$WEB" || fail=1
else
    echo "web-page: lab page skipped: no $WEB/sidx-lab.html (make web builds it, with emscripten)"
fi
exit $fail
