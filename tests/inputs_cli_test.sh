#!/usr/bin/env bash
# Silent acceptances turned into errors or warnings, and messages that name the input and
# print untrusted text escaped (sim/app, common/escape.hpp).
. "$(dirname "$0")/cli_lib.sh"
bin=$(readlink -f "$bin")
small=(--set screen.width=128 --set screen.height=128 --set gp.count=2 --set renderer.count=1)
cd "$tmp" || fail "no scratch folder"

# pp5sim stats reads what this binary writes at every fidelity level.
"$bin" render --scene two-triangles "${small[@]}" --fidelity analytic --out an >/dev/null 2>&1 \
  || fail "analytic render"
"$bin" stats an/stats.json > an.txt 2>&1 || fail "stats refused an analytic stats.json: $(cat an.txt)"
grep -q "^analytic.busiest_seconds = .* simulated seconds" an.txt || fail "stats said: $(head -3 an.txt)"

# sweep --grid checks each value against the configuration with --set applied.
"$bin" sweep --scene two-triangles --set gp.depth_bits=26 --grid frame.threshold=20000000 \
  --print-commands >/dev/null 2>&1 || fail "a threshold valid at 26 depth bits was refused"
expect_error "--grid frame.threshold=1000000: .*out of range \[0, 65535\] depth units (at gp.depth_bits = 16)" \
  sweep --scene two-triangles --set gp.depth_bits=16 --grid frame.threshold=1000000 --print-commands

# A frame parameter given both by --set and --param is refused (--param ran last whatever
# the order).
expect_error "--param highlight_opacity=20: frame.highlight_opacity is also given by --set" render \
  --scene two-triangles "${small[@]}" --param highlight_opacity=20 --set frame.highlight_opacity=10 \
  --out pp

# A configuration key given flat and nested is refused like a repeated key.
echo '{"renderer.count": 4, "renderer": {"count": 8}}' > twice.json
expect_error "twice.json: key 'renderer.count' is given twice" config --config twice.json

# A folder named like a built-in scene does not shadow it; the warning says so.
mkdir torus
"$bin" render --scene torus "${small[@]}" --out shadow > shadow.log 2>&1 || fail "torus shadowed: $(cat shadow.log)"
grep -q "warning: 'torus' is the built-in scene; the folder of that name" shadow.log \
  || fail "no warning about the folder: $(cat shadow.log)"

# A mesh that set-up cannot resolve gives a warning, not a silent black frame.
printf 'v 0 0 0\nv 1e20 0 0\nv 0 1e20 0\nf 1 2 3\n' > huge.obj
"$bin" render --scene huge.obj "${small[@]}" --out huge > huge.log 2>&1 || fail "huge.obj failed"
grep -q "warning: nothing was drawn: set-up dropped all 1 triangles" huge.log \
  || fail "no warning for a mesh at 1e20: $(cat huge.log)"
"$bin" render --scene two-triangles "${small[@]}" --out tt 2>&1 | grep -q "nothing was drawn" \
  && fail "a drawn frame warned that nothing was drawn"

# An exception inside the simulation is the message, not SystemC's "uncaught exception".
printf 'field z 24\nfield red 8\nfield green 8\nfield blue 8\noutput red green blue\noption passes highlight_opacity\nproc triangle\n  eall\nend\n' > passes.pp5
out=$("$bin" render --scene two-triangles "${small[@]}" --firmware ./passes.pp5 \
  --param highlight_opacity=0 --out passes 2>&1) && fail "passes 0 accepted"
echo "$out" | grep -q "^pp5sim: error: ./passes.pp5: option passes highlight_opacity: the frame parameter is 0, expected 1 to 64$" \
  || fail "passes said: $out"
echo "$out" | grep -q "E549\|uncaught\|sc_except" && fail "SystemC's frame leaked: $out"

# A file named as firmware that is not a program: its first line is not printed back.
printf 'root:$y$j9T$SECRET:19000:0:99999:7:::\n' > shadow.pp5
out=$("$bin" asm shadow.pp5 2>&1) && fail "a non-program assembled"
echo "$out" | grep -q "SECRET" && fail "the file's first line was printed: $out"
echo "$out" | grep -q "shadow.pp5:1: not a firmware program" || fail "asm said: $out"
# Bytes that are not text are escaped, and long words cut short.
printf 'field z 24\n\xff\xfe\x01bad 1\n' > bytes.pp5
out=$("$bin" asm bytes.pp5 2>&1) && fail "bytes assembled"
echo "$out" | grep -q "'\\\\xff\\\\xfe\\\\x01bad' outside a procedure" || fail "asm said: $(echo "$out" | cat -v)"
printf 'field z 24\n%s 1\n' "$(head -c 100000 /dev/zero | tr '\0' 'w')" > long.pp5
out=$("$bin" asm long.pp5 2>&1) && fail "long assembled"
[ "${#out}" -lt 600 ] || fail "a 100,000-byte word was printed whole (${#out} bytes)"
# sweep plot: an inf (or nan) in the CSV is refused by name, not drawn as an endless axis.
printf 'gp.count,triangles_per_second\n1,1000\n2,inf\n' > inf.csv
expect_error "inf.csv: column 'triangles_per_second' has 'inf', which is not a finite number" \
  sweep plot inf.csv -o inf.svg
printf 'gp.count,triangles_per_second\n1,1e-300\n2,1e300\n' > wide.csv
expect_error "wide.csv: triangles_per_second runs from 1e-300 to 1e+300, 601 decades" \
  sweep plot wide.csv -o wide.svg
[ -e inf.svg ] || [ -e wide.svg ] && fail "a plot was written"
echo "inputs_cli: all checks passed"
