#!/usr/bin/env bash
# pp5sim trace as a user meets it (the README's "Tracing a pixel"): record one pixel of the
# torus, ask why it has its colour, diff it against another firmware program, export a VCD
# that GTKWave's vcd2fst accepts; bad input gives a message, a non-zero exit and no file.
. "$(dirname "$0")/cli_lib.sh"

"$bin" trace record --pixel 500,400 -o "$tmp/phong.pp5t" >"$tmp/rec.log" 2>&1 ||
  fail "record failed: $(cat "$tmp/rec.log")"
"$bin" trace record --pixel 500,400 --firmware gouraud -o "$tmp/gouraud.pp5t" >/dev/null 2>&1 ||
  fail "record gouraud failed"
colour=$(sed -n 's/^frame colour of pixel 500,400: (\(.*\))$/\1/p' "$tmp/rec.log")
[ -n "$colour" ] || fail "record did not print the pixel's colour: $(cat "$tmp/rec.log")"
"$bin" trace why "$tmp/phong.pp5t" >"$tmp/why.txt" || fail "why failed"
grep -q "colour (r, g, b) = ($colour)" "$tmp/why.txt" || fail "why's colour is not the frame's ($colour)"
grep -q "last written by triangle" "$tmp/why.txt" || fail "why names no triangle"
"$bin" trace diff "$tmp/phong.pp5t" "$tmp/gouraud.pp5t" >"$tmp/diff.txt" || fail "diff failed"
grep -q "first divergence after packet" "$tmp/diff.txt" || fail "diff found no divergence"
"$bin" trace history "$tmp/phong.pp5t" --fields z | grep -q "qload z, depth" || fail "history"
"$bin" trace bitmap "$tmp/phong.pp5t" | grep -q "memory map" || fail "bitmap"
"$bin" trace vcd "$tmp/phong.pp5t" -o "$tmp/p.vcd" >/dev/null || fail "vcd failed"
if command -v vcd2fst >/dev/null 2>&1; then
  vcd2fst "$tmp/p.vcd" "$tmp/p.fst" >/dev/null 2>&1 || fail "vcd2fst rejected the VCD"
else
  echo "WARN: vcd2fst (gtkwave) not installed; the VCD was not checked by a reader"
fi
"$bin" trace snapshot --pixel 500,400 --png z --png covered -o "$tmp/r.pp5m" >/dev/null ||
  fail "snapshot failed"
for f in r.pp5m r-z.png r-covered.png; do [ -s "$tmp/$f" ] || fail "missing $f"; done
rm "$tmp/r-z.png"
"$bin" trace snapshot --from "$tmp/r.pp5m" --png z >/dev/null || fail "snapshot --from failed"
[ -s "$tmp/r-z.png" ] || fail "snapshot --from wrote no image"

head -c 3000 "$tmp/phong.pp5t" >"$tmp/cut.pp5t"
expect_error "cut.pp5t: truncated at byte 3000" trace why "$tmp/cut.pp5t"
expect_error "not a pp5sim trace" trace history "$tmp/p.vcd"
expect_error "outside the 1280 x 1024 screen" trace record --pixel 1280,0 -o "$tmp/bad1.pp5t"
expect_error "'zz' is not a field" trace record --pixel 1,1 --fields z,zz -o "$tmp/bad2.pp5t"
expect_error "empty range" trace record --pixel 1,1 --instructions 9:3 -o "$tmp/bad3.pp5t"
expect_error "choose one of those" trace snapshot --pixel 500,400 --after 3 -o "$tmp/bad4.pp5m"
# Numbers that an int would wrap are refused, naming the argument (2^32 + 5 is not pixel 5).
expect_error "--pixel X '4294967301': is out of range, expected an integer from 0 to" \
  trace record --pixel 4294967301,5 -o "$tmp/bad5.pp5t"
expect_error "--rect WIDTH '2147483647': is out of range" trace record \
  --rect 0,0,2147483647,2147483647 -o "$tmp/bad6.pp5t"
expect_error "--instructions '9223372036854775807': is out of range" trace record --pixel 1,1 \
  --instructions 9223372036854775807 -o "$tmp/bad7.pp5t"
expect_error "--pixel X '4294967301': is out of range" trace why "$tmp/phong.pp5t" --pixel 4294967301,5
for f in bad1.pp5t bad2.pp5t bad3.pp5t bad4.pp5m bad5.pp5t bad6.pp5t bad7.pp5t; do [ -e "$tmp/$f" ] && fail "partial output $f"; done
ls "$tmp" | grep -q '\.tmp$' && fail "temporary file left behind"
echo "trace cli: passed"
