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

# Every error message is escaped and cut short where it is printed (main), whatever part of
# it came from an input: a control byte prints as \xHH, a 1 MB word as 80 bytes and its length.
out=$("$bin" config --set $'gp.\x1b[31mcount=1' 2>&1) && fail "an unknown key was accepted"
printf '%s' "$out" | LC_ALL=C grep -q $'\x1b' && fail "a raw escape byte was printed: $(echo "$out" | cat -v)"
echo "$out" | grep -qF "unknown key 'gp.\x1b[31mcount'" || fail "config said: $out"
python3 -c "import json; print(json.dumps({'meshes': [{'builtin': 'torus', 'k' * 1000000: 1}]}))" > longkey.json
out=$("$bin" render --scene longkey.json "${small[@]}" --out lk 2>&1) && fail "a 1 MB key was accepted"
[ "${#out}" -lt 600 ] || fail "a 1 MB key was printed whole (${#out} bytes)"
echo "$out" | grep -q "unknown key 'meshes\[0\].kkkk.*\.\.\. (1000010 bytes)'" || fail "render said: ${out:0:300}"

# JSON: a NUL byte ended the document and the rest was ignored.
printf '{"meshes": [{"builtin": "torus"}]}\0{"garbage"' > nul.json
expect_error "nul.json: a NUL byte at byte 34: not JSON text" render --scene nul.json "${small[@]}" --out nj

# Indices are shown as written and refused before a reader can wrap them: -1 read into an
# unsigned number printed as 2^64 - 1 (OFF) or 2^32 - 1 (PLY); 2^64 - 1 read signed as -1.
printf 'OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 -1\n' > neg.off
expect_error "neg.off:6: face 0: vertex index '-1' is not an index from 0 to 2" render --scene neg.off "${small[@]}" --out ng
ply_head='ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n'
printf "${ply_head}3 0 1 -1\n" > neg.ply
expect_error "neg.ply:13: face 0: vertex index '-1' is not an index from 0 to 2147483647" render --scene neg.ply "${small[@]}" --out ng
printf '{"meshes": [{"vertices": [[0,0,0],[1,0,0],[0,1,0]], "triangles": [[0,1,18446744073709551615]]}]}' > u64.json
expect_error "key 'meshes\[0\].triangles\[0\]\[2\]' is 18446744073709551615, outside \[0, 3)" render --scene u64.json "${small[@]}" --out ng
"$bin" render --scene two-triangles "${small[@]}" --out st >/dev/null 2>&1 || fail "two-triangles"
sed 's/"frame": *{/"frame": {"forged": 18446744073709551615, /' st/stats.json > u64stats.json
grep -q forged u64stats.json || fail "could not forge stats.json"
expect_error "statistic 'frame.forged' = 18446744073709551615: out of range" stats u64stats.json

# Text formats hold text: a NUL or a control byte is refused with its line (assimp stopped at
# a NUL and dropped the rest); text after a PLY body or an STL's last solid is not ignored.
printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n\0\0v 5 5 5\n' > nul.obj
expect_error "nul.obj:5: byte 0x00 at column 1 is not text; OBJ is a text format" render --scene nul.obj "${small[@]}" --out nt
printf "${ply_head}3 0 1 2\n3 0 1 2\n" > extra.ply
expect_error "extra.ply:14: text after the last element the header declares ('3 0 1 2')" render --scene extra.ply "${small[@]}" --out nt
printf 'solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid x\nfoo\n' > trail.stl
expect_error "trail.stl:10: expected 'solid' or the end of the file after 'endsolid', got 'foo'" render --scene trail.stl "${small[@]}" --out nt
printf 'solid x\x01\nendsolid x\n' > ctl.stl
expect_error "ctl.stl:1: byte 0x01 at column 8 is not text; an ASCII STL" render --scene ctl.stl "${small[@]}" --out nt
printf 'OFF\n3 1 0\n0 0 0\n1 0 \xff\n0 1 0\n3 0 1 2\n' > byte.off
expect_error "byte.off:4: vertex 1: expected a number, got '?'" render --scene byte.off "${small[@]}" --out nt
printf 'ATOM      1  CA  ALA A   1      11.104   6.134  -6.504  1.00  0.00           C\n\0\1junk\n' > nul.pdb
expect_error "nul.pdb:2: byte 0x00 at column 1 is not text; PDB is a text format" render --scene nul.pdb "${small[@]}" --out nt
# mmCIF: a table without a column the reader needs read as "no atoms"; the column is named.
printf 'data_x\nloop_\n_atom_site.group_PDB\n_atom_site.id\n_atom_site.type_symbol\n_atom_site.label_atom_id\n_atom_site.label_alt_id\n_atom_site.label_comp_id\n_atom_site.label_asym_id\n_atom_site.label_seq_id\n_atom_site.Cartn_x\n_atom_site.Cartn_y\n_atom_site.occupancy\n_atom_site.B_iso_or_equiv\n_atom_site.auth_seq_id\nATOM 1 C CA . ALA A 1 1.0 2.0 1.0 0.0 1\n' > noz.cif
expect_error "noz.cif: the _atom_site table lacks the column _atom_site.Cartn_z (the mmCIF reader needs" render --scene noz.cif "${small[@]}" --out nt
[ -e nt ] || [ -e ng ] || [ -e nj ] && fail "a refused input left an output folder"

# A scene's size is bounded before the geometry is built: 600 built-in spheres (2.4 M
# triangles, from a 14 KB file) and a 2048 x 2048 torus are refused, naming the input and
# the bound; within it, running out of memory names the scene and the bound too.
python3 -c "import json; print(json.dumps({'meshes': [{'builtin': 'sphere'}] * 600}))" > many.json
expect_error "many.json: key 'meshes\[504\]' (3968 triangles, 1986 vertices) makes the scene 2003840 triangles .*; a scene holds at most 2000000 triangles" \
  render --scene many.json "${small[@]}" --out big
expect_error "scene 'torus': a tessellation of 2048 x 2048 makes 8388608 triangles; a scene holds at most 2000000" \
  render --scene torus --tessellation 2048 2048 "${small[@]}" --out big
if ! { ldd "$bin" 2>/dev/null | grep -q libasan || grep -q __asan_init "$bin"; }; then
  python3 -c "import json; print(json.dumps({'meshes': [{'builtin': 'sphere'}] * 60}))" > sixty.json
  out=$( (ulimit -v 200000; "$bin" render --scene sixty.json --out big) 2>&1) && fail "ran in 200 MB"
  echo "$out" | grep -q "out of memory: .*the scene sixty.json holds 238080 triangles and 0 spheres (a scene holds at most 2000000 triangles" \
    || fail "out of memory said: $out"
fi
[ -e big ] && fail "a refused scene left an output folder"
# sweep aggregate: sweep.json names the folders it reads; a forged one reads nothing outside
# the sweep's folder, and a grid of runs not yet made is summed up, not listed a line each.
mkdir forged
printf '{"grid": {"gp.count": ["../../x"]}, "order": ["gp.count"], "scene": "s", "firmware": "f"}' > forged/sweep.json
expect_error "forged/sweep.json: 'grid.gp.count' holds '../../x', not a value once" sweep aggregate forged -o f.csv
printf '{"grid": {"gp.count": ["1"]}, "order": ["nope", "gp.count"], "scene": "s", "firmware": "f"}' > forged/sweep.json
expect_error "forged/sweep.json: 'order' names 'nope', not in 'grid'" sweep aggregate forged -o f.csv
python3 -c "import json; print(json.dumps({'grid': {'gp.count': [str(i) for i in range(50)]}, 'order': ['gp.count'], 'scene': 's', 'firmware': 'f'}))" > forged/sweep.json
out=$("$bin" sweep aggregate forged -o f.csv 2>&1) && fail "an empty sweep aggregated"
[ "$(echo "$out" | wc -l)" -le 12 ] || fail "50 missing runs printed $(echo "$out" | wc -l) lines"
echo "$out" | grep -q "and 40 more runs without them (50 of 50)" || fail "aggregate said: $out"
[ -e f.csv ] && fail "a refused aggregate wrote its CSV"
# trace snapshot --after -1 took the region's end (its default's stand-in) without a word.
expect_error "^pp5sim: error: --after" trace snapshot --scene two-triangles "${small[@]}" --region 0 --after -1 -o snap.pp5m
[ -e snap.pp5m ] && fail "a refused snapshot was written"
echo "inputs_cli: all checks passed"
