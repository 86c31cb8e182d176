#!/usr/bin/env bash
# Every kind of HTML report, opened in headless Chromium (tests/browser_check.py): a frame's
# (bit-level pixels and event timing), a timing-only frame's (analytic: no image, no
# timeline), a sweep's and the analyses' (extremes; csg, scanconvert and highlight, with
# their tables and images). Fails on a console error, a request
# outside the page, an image that does not decode or is blank, a blank first screen, a table that does
# not sort or a plot that draws nothing. Skips (77) where Chromium is not installed
# (scripts/install-deps.sh test installs Debian's chromium).
# Usage: tests/report_browser_test.sh PP5SIM [SCREENSHOT_DIR]
. "$(dirname "$0")/cli_lib.sh"
shots="${2:-}"
command -v chromium >/dev/null || { echo "SKIP: no chromium (scripts/install-deps.sh test)"; exit 77; }
small=(--set screen.width=256 --set screen.height=256 --set gp.count=4 --set renderer.count=4)

"$bin" render --scene torus "${small[@]}" -j 2 --out "$tmp/frame" --report >"$tmp/log" 2>&1 \
  || fail "render --report: $(cat "$tmp/log")"
grep -q "wrote $tmp/frame/report.html" "$tmp/log" || fail "render did not say it wrote report.html"
"$bin" render --scene sphere "${small[@]}" --fidelity analytic --out "$tmp/analytic" --report \
  >"$tmp/log" 2>&1 || fail "render --fidelity analytic --report: $(cat "$tmp/log")"
grep -q "No image" "$tmp/analytic/report.html" || fail "the analytic report does not say it has no image"
"$bin" sweep --scene two-triangles --set screen.width=128 --set screen.height=128 \
  --grid gp.count=1,2 --grid renderer.count=1,2 -j 1 --out "$tmp/sweep" >"$tmp/log" 2>&1 \
  || fail "sweep: $(cat "$tmp/log")"
"$bin" sweep aggregate "$tmp/sweep" --report >"$tmp/log" 2>&1 || fail "aggregate --report: $(cat "$tmp/log")"
# The same page straight from the sweep (--report aggregates after the runs).
"$bin" sweep --scene two-triangles --set screen.width=128 --set screen.height=128 \
  --grid gp.count=1,2 --grid renderer.count=1,2 -j 1 --out "$tmp/sweep2" --report >"$tmp/log" 2>&1 \
  || fail "sweep --report: $(cat "$tmp/log")"
[ -s "$tmp/sweep2/report.html" ] || fail "sweep --report wrote no report.html"
diff <(cut -d, -f1-3 "$tmp/sweep/sweep.csv") <(cut -d, -f1-3 "$tmp/sweep2/sweep.csv") >/dev/null \
  || fail "sweep --report and sweep aggregate give different rows"
mkdir -p "$tmp/extremes"
"$bin" extremes -j 2 --report "$tmp/extremes/report.html" >"$tmp/log" 2>&1 \
  || fail "extremes --report: $(cat "$tmp/log")"
"$bin" csg --application parity -s plane-slab -p parity --set screen.width=128 \
  --set screen.height=128 -j 2 --out "$tmp/csg" --report >"$tmp/log" 2>&1 \
  || fail "csg --report: $(cat "$tmp/log")"
[ -s "$tmp/csg/csg-parity.csv" ] || fail "csg --report wrote no csg-parity.csv"
grep -q '<img' "$tmp/csg/report.html" || fail "the csg report has no image"
"$bin" scanconvert -s two-triangles --set screen.width=128 --set screen.height=128 -j 2 \
  --out "$tmp/scanconvert" --report >"$tmp/log" 2>&1 || fail "scanconvert --report: $(cat "$tmp/log")"
[ -s "$tmp/scanconvert/scanconvert.csv" ] || fail "scanconvert --report wrote no scanconvert.csv"
"$bin" highlight --scenes two-triangles --firmware epsilon threshold --speed-scene '' \
  --compare-order none --set screen.width=128 --set screen.height=128 -j 2 --out "$tmp/highlight" \
  --report >"$tmp/log" 2>&1 || fail "highlight --report: $(cat "$tmp/log")"
# The truth once, then each program's image beside its overlay.
[ "$(grep -o '<img' "$tmp/highlight/report.html" | wc -l)" -eq 3 ] \
  || fail "the highlight report has $(grep -o '<img' "$tmp/highlight/report.html" | wc -l) images, not 3"
pages=()
for kind in frame analytic sweep sweep2 extremes csg scanconvert highlight; do pages+=("$tmp/$kind/report.html"); done

# Self-contained: no address outside the page in any of them.
for f in "${pages[@]}"; do
  [ -s "$f" ] || fail "no $f"
  if grep -Eo '(src|href)="[a-z]+:[^"]{0,30}' "$f" | grep -v '="data:' | grep -q .; then
    fail "$f links outside itself: $(grep -Eo '(src|href)="[a-z]+:[^"]{0,30}' "$f" | grep -v '="data:' | head -3)"
  fi
done
args=()
[ -n "$shots" ] && args=(--screenshots "$shots")
timeout 300 python3 "$(dirname "$0")/browser_check.py" "${args[@]}" \
  "${pages[@]}" || fail "the browser found faults (above)"
echo "report_browser_test: passed"
