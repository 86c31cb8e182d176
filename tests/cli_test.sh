#!/usr/bin/env bash
# The command-line program as a user meets it: bad input gives a clear message, a non-zero
# exit and no output files; good input writes the frame and both reports.
. "$(dirname "$0")/cli_lib.sh"

expect_error "unknown scene 'nope'" render --scene nope --out "$tmp/a"
expect_error "no such file" render --firmware /nonexistent.pp5 --out "$tmp/b"
printf '{"renderer": {"cont": 4}}' > "$tmp/bad.json"
expect_error "unknown key 'renderer.cont'" render --config "$tmp/bad.json" --out "$tmp/c"
printf '{"gp": {"count": "many"}}' > "$tmp/bad2.json"
expect_error "'gp.count' must be an integer" render --config "$tmp/bad2.json" --out "$tmp/c"
expect_error "out of range" render --set renderer.count=99 --out "$tmp/c"
expect_error "not BEFORE:AFTER" asm --rewrites epsilon_folded
expect_error "give a program, or --rewrites" asm
expect_error "give a program, or --rewrites" asm phong --rewrites epsilon_folded_squares:epsilon_folded
expect_error "unknown scene 'nope'" asm phong --scene nope
printf 'field z 24\nproc triangle\n  qload z, nowhere\nend\n' > "$tmp/bad.pp5"
expect_error "bad.pp5:3:" render --firmware "$tmp/bad.pp5" --out "$tmp/d"
expect_error "no frame parameter 'nope'" highlight --param nope=1 --out "$tmp/e"
expect_error "value 'wide' of key 'frame.delta' is not a number" render --param delta=wide --out "$tmp/e"
expect_error "highlight_opacity' = 999" highlight --param highlight_opacity=999 --out "$tmp/e"
expect_error "unknown scene 'nope'" highlight --scenes two-triangles nope --out "$tmp/e"
expect_error "not a highlighting program" highlight --firmware phong --out "$tmp/e"
[ -e "$tmp/e" ] && fail "highlight wrote output after bad input"
# Mesh and scene files (tests/data): each bad one names the file, the line or key.
data="$(dirname "$0")/data"
expect_error "nan.obj: face 0, corner 2: z is NaN, expected a finite number" render --scene "$data/bad/nan.obj" --out "$tmp/e"
expect_error "truncated.stl: binary STL declares 4 triangles" render --scene "$data/bad/truncated.stl" --out "$tmp/e"
expect_error "limit is 4000000" render --scene "$data/bad/absurd_count.off" --out "$tmp/e"
expect_error "key 'meshes\[0\].scale' must be a number" render --scene "$data/bad/wrong_type.json" --out "$tmp/e"
expect_error "not valid JSON" render --scene "$data/bad/syntax.json" --out "$tmp/e"
for d in a b c d e; do [ -e "$tmp/$d/frame.png" ] && fail "partial output in $tmp/$d"; done
"$bin" render --scene "$data/meshes/concave.obj" --firmware flat --set screen.width=128 \
  --set screen.height=128 --out "$tmp/mesh" >"$tmp/mesh.log" 2>&1 || fail "mesh render failed: $(cat "$tmp/mesh.log")"
grep -q "1 triangulated" "$tmp/mesh.log" || fail "no mesh load report"
grep -q "coefficient overflow" "$tmp/mesh.log" || fail "no set-up drop report"
[ -s "$tmp/mesh/frame.png" ] || fail "mesh render wrote no frame"

"$bin" render --scene two-triangles --set screen.width=256 --set screen.height=128 \
  --out "$tmp/ok" >"$tmp/ok.log" 2>&1 || fail "render failed: $(cat "$tmp/ok.log")"
for f in frame.png regions.png config.json stats.json; do [ -s "$tmp/ok/$f" ] || fail "missing $f"; done
grep -q "of 208 bits" "$tmp/ok.log" || fail "no bit-budget table"
grep -q "projected throughput" "$tmp/ok.log" || fail "no throughput"
ls "$tmp/ok" | grep -q tmp && fail "temporary file left behind"
# What stats.json holds: every statistic described, and a written file printed with units.
"$bin" stats --describe >"$tmp/describe.md" || fail "stats --describe failed"
grep -q '^| `renderer.N.busy_cycles` | integer | array cycles | ' "$tmp/describe.md" \
  || fail "stats --describe: no renderer.N.busy_cycles row"
"$bin" stats "$tmp/ok/stats.json" >"$tmp/stats.txt" || fail "stats FILE failed"
grep -q '^setup.packets = [0-9]* count$' "$tmp/stats.txt" || fail "stats FILE: no setup.packets"
grep -q '^timing.bottleneck = ' "$tmp/stats.txt" || fail "stats FILE: no timing.bottleneck"
expect_error "give --describe or a stats.json file" stats
printf '{"frame": {"bogus": 1}}' > "$tmp/bogus.json"
expect_error "'frame.bogus' is not a statistic" stats "$tmp/bogus.json"
# A program may be given as a path (here one relative to the working folder, with a '/'):
# its images are named by the path with '/' made '_', in the scene's folder.
mkdir -p "$tmp/rw" && cp "$(dirname "$0")/../firmware/rewrites/epsilon.pp5" "$tmp/rw/eps.pp5"
(cd "$tmp" && "$bin" highlight --scenes two-triangles --firmware exactmatch epsilon rw/eps.pp5 \
  --speed-scene '' --set screen.width=256 --set screen.height=256 --out "$tmp/hl" --report) \
  >"$tmp/hl.log" 2>&1 || fail "highlight failed: $(cat "$tmp/hl.log")"
grep -q "| epsilon | two-triangles |" "$tmp/hl.log" || fail "no epsilon row in the table"
grep -q "| rw/eps.pp5 | two-triangles |" "$tmp/hl.log" || fail "no row for the program path"
for f in highlight.md highlight.csv highlight-truth.csv highlight-summary.csv \
  highlight-curves-two-triangles.csv report.html \
  two-triangles/epsilon.png two-triangles/epsilon-overlay.png two-triangles/rw_eps.pp5.png \
  two-triangles/rw_eps.pp5-overlay.png; do
  [ -s "$tmp/hl/$f" ] || fail "highlight did not write $f"
done
# Its CSV is the Markdown table's rows, with the values (not the text) in the cells.
[ "$(head -1 "$tmp/hl/highlight.csv")" = "program,scene,truth_pixels,flagged_pixels,recall,recall_ceiling,precision,width_mean,width_sd,coverage,order_change,bits_used,spilled,polygons_per_second,polygons_per_second_compiled" ] \
  || fail "highlight.csv's heading: $(head -1 "$tmp/hl/highlight.csv")"
[ "$(grep -c '^epsilon,two-triangles,' "$tmp/hl/highlight.csv")" -eq 1 ] || fail "highlight.csv: $(cat "$tmp/hl/highlight.csv")"
grep -q '<table' "$tmp/hl/report.html" || fail "highlight's report.html has no table"
# The truth's recall ceiling: below 1 (the band spills past the triangles' outline), and the
# same in the table by program.
ceiling=$(grep '^two-triangles,' "$tmp/hl/highlight-truth.csv" | cut -d, -f5)
awk -v c="$ceiling" 'BEGIN { exit !(c > 0.9 && c < 1) }' || fail "highlight-truth.csv: $(cat "$tmp/hl/highlight-truth.csv")"
[ "$(grep '^epsilon,two-triangles,' "$tmp/hl/highlight-summary.csv" | cut -d, -f4)" = "$ceiling" ] \
  || fail "highlight-summary.csv: $(cat "$tmp/hl/highlight-summary.csv")"
# scanconvert --significand-bits: one table whose rows at each width are the rows of a run
# with gp.significand_bits set to it; a width outside the key's range is refused, nothing written.
"$bin" scanconvert -s two-triangles --set screen.width=128 --set screen.height=128 -j 2 \
  --significand-bits 62,10 --out "$tmp/scp" >"$tmp/scp.log" 2>&1 || fail "scanconvert --significand-bits: $(cat "$tmp/scp.log")"
"$bin" scanconvert -s two-triangles --set screen.width=128 --set screen.height=128 -j 2 \
  --set gp.significand_bits=10 --out "$tmp/sc10" >"$tmp/sc10.log" 2>&1 || fail "scanconvert: $(cat "$tmp/sc10.log")"
[ "$(grep -c '^| 62 | two-triangles |' "$tmp/scp.log")" -eq 2 ] || fail "no 62-bit rows: $(cat "$tmp/scp.log")"
diff <(grep '^10,' "$tmp/scp/scanconvert-precision.csv" | cut -d, -f3-6) \
  <(tail -n +2 "$tmp/sc10/scanconvert.csv" | cut -d, -f2-5) >/dev/null \
  || fail "the 10-bit rows differ from a run at gp.significand_bits=10: $(cat "$tmp/scp/scanconvert-precision.csv")"
expect_error "significand-bits 3: .*out of range \[4, 62\]" scanconvert -s two-triangles \
  --significand-bits 24,3 --out "$tmp/scp-bad"
[ -e "$tmp/scp-bad" ] && fail "scanconvert --significand-bits wrote output after bad input"
expect_error "significand-bits: 24 is given twice" scanconvert -s two-triangles \
  --significand-bits 24,10,24 --out "$tmp/scp-twice"
[ -e "$tmp/scp-twice" ] && fail "scanconvert --significand-bits wrote output after a repeated width"
# validate and fidelity write their CSVs through the report's tables: the files of every
# value, not the shown tables (no record.csv).
"$bin" validate --no-sensitivity --joint 2 --out "$tmp/val" >"$tmp/val.log" 2>&1 || fail "validate: $(cat "$tmp/val.log")"
[ "$(ls "$tmp/val" | tr '\n' ' ')" = "joint.csv validate.csv validate.md " ] || fail "validate wrote: $(ls "$tmp/val")"
head -1 "$tmp/val/validate.csv" | grep -q '^figure,source,published,published_value,simulated,unit,difference,status' \
  || fail "validate.csv's heading: $(head -1 "$tmp/val/validate.csv")"
[ "$(wc -l < "$tmp/val/joint.csv")" -eq 3 ] || fail "joint.csv: $(cat "$tmp/val/joint.csv")"
"$bin" fidelity --scene two-triangles --runs 1 --no-analytic-grids --set screen.width=128 \
  --set screen.height=128 --out "$tmp/fid" >"$tmp/fid.log" 2>&1 || fail "fidelity: $(cat "$tmp/fid.log")"
[ "$(ls "$tmp/fid" | tr '\n' ' ')" = "fidelity.csv fidelity.md sustained.csv sustained.md " ] \
  || fail "fidelity wrote: $(ls "$tmp/fid")"
# spheres reads a tessellation's visibility from the --firmware that draws it: a program whose
# triangles keep the farther depth (so none is ever drawn over the cleared z) shows no sphere
# at any intersection-curve pixel of the tessellation (the built-in reader would find them).
sed 's/^  qcmp.lt z, depth$/  qcmp.gt z, depth/' "$(dirname "$0")/../firmware/programs/phong.pp5" \
  > "$tmp/farthest.pp5"
grep -q 'qcmp.gt z, depth' "$tmp/farthest.pp5" || fail "phong.pp5 no longer has 'qcmp.lt z, depth'"
"$bin" spheres --set screen.width=128 --set screen.height=128 --tessellations 8x4 \
  --firmware "$tmp/farthest.pp5" -j 2 >"$tmp/sp.log" 2>&1 || fail "spheres failed: $(cat "$tmp/sp.log")"
grep -Eq '^\| 8x4 \(48 triangles\) .*\| ([1-9][0-9]*) of \1 \|$' "$tmp/sp.log" \
  || fail "spheres: the tessellation's visibility is not the --firmware's: $(grep '^| 8x4' "$tmp/sp.log")"
"$bin" --help | grep -q render || fail "--help does not list render"
# The extremes report: every synthetic case passes; a scene's failures are named, exit 1.
"$bin" extremes -j 2 >"$tmp/ext.log" 2>&1 || fail "extremes failed: $(cat "$tmp/ext.log")"
grep -q "PASS shared edges across a mesh" "$tmp/ext.log" || fail "no shared-edge case"
grep -q "0 failed" "$tmp/ext.log" || fail "extremes summary"
expect_error "FAIL scene: depth precision" extremes --no-synthetic --scene two-triangles \
  --set evaluator.fraction_bits=6 --set screen.width=256 --set screen.height=256

# Timeline and sweeps.
"$bin" render --scene two-triangles --set screen.width=256 --set screen.height=128 \
  --out "$tmp/tl" --timeline "$tmp/tl/timeline.json" >"$tmp/tl.log" 2>&1 || fail "timeline run failed"
grep -q '"traceEvents"' "$tmp/tl/timeline.json" || fail "no trace events"
grep -q "bottleneck:" "$tmp/tl.log" || fail "no bottleneck in the summary"
expect_error "unknown key 'gp.cont'" sweep --grid gp.cont=1,2 --out "$tmp/sw0"
expect_error "'renderer.count'" sweep --grid renderer.count=1,99 --out "$tmp/sw0"
expect_error "expected KEY=V1,V2" sweep --grid gp.count --out "$tmp/sw0"
expect_error "swept twice" sweep --grid gp.count=1 --grid gp.count=2 --out "$tmp/sw0"
[ -e "$tmp/sw0" ] && fail "a bad grid wrote output"
n=$("$bin" sweep --grid gp.count=1,2 --grid renderer.count=1,2,4 --scene two-triangles \
  --out "$tmp/sw1" --print-commands | grep -c " render ")
[ "$n" = 6 ] || fail "--print-commands printed $n commands, expected 6"
# --slurm writes the same commands to OUT/commands.txt and a submission script that bash
# accepts, with one array task per point (tests/slurm_test.sh runs it on a real Slurm).
"$bin" sweep --grid gp.count=1,2 --grid renderer.count=1,2,4 --scene two-triangles \
  --out "$tmp/sw1" --slurm "$tmp/sw1.sh" >/dev/null || fail "--slurm failed"
"$bin" sweep --grid gp.count=1,2 --grid renderer.count=1,2,4 --scene two-triangles \
  --out "$tmp/sw1" --print-commands | cmp -s - "$tmp/sw1/commands.txt" \
  || fail "commands.txt differs from --print-commands"
bash -n "$tmp/sw1.sh" || fail "the Slurm script is not valid bash"
grep -q -- "--array=0-5 " "$tmp/sw1.sh" || fail "the Slurm script has no array of 6 tasks"
grep -q -- "--dependency=afterok:" "$tmp/sw1.sh" || fail "the aggregation does not wait (afterok)"
expect_error "the folder $tmp/none does not exist" sweep --grid gp.count=1 --out "$tmp/sw1" \
  --slurm "$tmp/none/x.sh"
expect_error "excludes" sweep --grid gp.count=1 --slurm "$tmp/x.sh" --print-commands
# A printed command runs as is (as GNU parallel or a Slurm task would), and aggregate takes
# the finished runs and names the missing ones.
"$bin" sweep --grid gp.count=1,2 --scene two-triangles --set screen.width=256 \
  --set screen.height=128 --out "$tmp/sw2" --print-commands | head -1 | bash >/dev/null 2>&1 \
  || fail "a printed command failed"
"$bin" sweep aggregate "$tmp/sw2" >"$tmp/sw2.log" 2>&1 || fail "aggregate of a partial sweep failed"
grep -q "1 runs, 1 missing" "$tmp/sw2.log" || fail "aggregate said: $(cat "$tmp/sw2.log")"
"$bin" sweep --grid gp.count=1,2 --grid renderer.balancing=static,dynamic --scene two-triangles \
  --set screen.width=256 --set screen.height=128 --out "$tmp/sw" >/dev/null 2>&1 || fail "sweep failed"
"$bin" sweep aggregate "$tmp/sw" -o "$tmp/sw.csv" >/dev/null || fail "aggregate failed"
[ "$(wc -l < "$tmp/sw.csv")" = 5 ] || fail "sweep.csv: expected a header and 4 rows"
head -1 "$tmp/sw.csv" | grep -q "^gp.count,renderer.balancing,frame_seconds" || fail "bad CSV header"
# csg names every scene it can make when one is unknown.
expect_error "no parity scene 'nope' (there are: plane-sphere, plane-boxes, plane-slab, boxes-overlap" csg -s nope
# CSG rendering needs a program with the CSG procedures and a scene with an expression.
expect_error "phong: CSG rendering needs a program that defines 'surface'" csg --application csg \
  --csg-scene box-or-ball --csg-program phong --set screen.width=64 --set screen.height=64 \
  --out "$tmp/csg-phong"
expect_error "scene 'plane-sphere' has no CSG expression to render" csg --application csg \
  --csg-scene plane-sphere --set screen.width=64 --set screen.height=64 --out "$tmp/csg-none"
# A failed run leaves no output folder, not even an empty one (nor the parents it made).
[ ! -e "$tmp/csg-none" ] || fail "a failed csg run left $tmp/csg-none"
expect_error "program 'csg_layers' does not define 'sphere_surface', which the spheres of solid 'left'" \
  csg --application csg --csg-scene quadric-lens --csg-program csg_layers --set screen.width=64 \
  --set screen.height=64 --out "$tmp/deep/er/csg-layers"
[ ! -e "$tmp/deep" ] || fail "a failed csg run left $tmp/deep"
expect_error "csg: a cross-section program leaves the shown depth in a field 'z' and the cap in a field 'inside'" \
  csg --application section --section-program csg --set screen.width=64 --set screen.height=64 \
  --out "$tmp/section-csg"
mkdir "$tmp/kept"
expect_error "no parity scene 'nope'" csg --application csg --csg-scene nope --out "$tmp/kept"
[ -d "$tmp/kept" ] || fail "a failed run removed a folder it did not make"
# aggregate of a file or a missing folder names it and says what it expected.
expect_error "sw.csv: is not a folder, expected the output folder of a 'pp5sim sweep' run" sweep aggregate "$tmp/sw.csv"
expect_error "nowhere: no such folder, expected the output folder" sweep aggregate "$tmp/nowhere"
"$bin" sweep plot "$tmp/sw.csv" -o "$tmp/sw.svg" >/dev/null || fail "plot failed"
grep -q "<polyline" "$tmp/sw.svg" || fail "no lines in the plot"
expect_error "no column 'nope'" sweep plot "$tmp/sw.csv" -y nope -o "$tmp/bad.svg"

# Frame parameters are keys of the configuration (issue 11; issue 18 section 4).
small=(--scene two-triangles --firmware threshold --set screen.width=128 --set screen.height=128)
"$bin" render --scene two-triangles --set screen.width=128 --set screen.height=128 \
  --set gp.depth_bits=8 --out "$tmp/d8" >"$tmp/d8.log" 2>&1 \
  || fail "--set gp.depth_bits=8 was refused: $(tail -1 "$tmp/d8.log")"
"$bin" sweep --grid gp.depth_bits=8,24 --scene two-triangles --set screen.width=128 \
  --set screen.height=128 --out "$tmp/swd" >/dev/null 2>&1 || fail "a sweep over gp.depth_bits failed"
expect_error "'frame.threshold' = 32768 is out of range \[0, 255\]" render "${small[@]}" \
  --set gp.depth_bits=8 --param threshold=32768 --out "$tmp/f"
for bad in ambient=-1 ambient=99999999 specular=-100000 light_x=3 epsilon_scale=1; do
  expect_error "key 'frame.${bad%%=*}' cannot be set: the GP computes it from" render "${small[@]}" \
    --param "$bad" --out "$tmp/f"
done
expect_error "'frame.delta' = 2000 is out of range" render "${small[@]}" --set frame.delta=2000 --out "$tmp/f"
[ -e "$tmp/f" ] && fail "a refused frame parameter wrote output"
# --param NAME is --set frame.NAME, and a config file's "frame" section is the same again.
"$bin" render "${small[@]}" --param threshold=8192 --out "$tmp/p1" >/dev/null 2>&1 || fail "--param failed"
"$bin" render "${small[@]}" --set frame.threshold=8192 --out "$tmp/p2" >/dev/null 2>&1 || fail "--set frame failed"
printf '{"frame": {"threshold": 8192}}' > "$tmp/frame.json"
"$bin" render "${small[@]}" --config "$tmp/frame.json" --out "$tmp/p3" >/dev/null 2>&1 || fail "config frame failed"
"$bin" render "${small[@]}" --out "$tmp/p0" >/dev/null 2>&1 || fail "default threshold render failed"
cmp -s "$tmp/p1/frame.png" "$tmp/p2/frame.png" || fail "--param and --set frame. differ"
cmp -s "$tmp/p1/frame.png" "$tmp/p3/frame.png" || fail "--param and the config file differ"
cmp -s "$tmp/p1/frame.png" "$tmp/p0/frame.png" && fail "threshold=8192 changed nothing (the test cannot tell)"
grep -q '"threshold": 8192' "$tmp/p1/config.json" || fail "config.json does not record frame.threshold"
# sweep takes --param, and passes it on to the commands it prints.
"$bin" sweep --grid gp.count=1,2 "${small[@]}" --param threshold=8192 --out "$tmp/swp" \
  --print-commands | grep -q -- "--set frame.threshold=8192" || fail "sweep --param not passed on"
"$bin" sweep --grid gp.count=1 "${small[@]}" --param threshold=8192 --out "$tmp/swp2" >/dev/null 2>&1 \
  || fail "sweep --param failed"
grep -q '"threshold": 8192' "$tmp/swp2/gp.count-1/config.json" || fail "the sweep run did not use --param"
# Duplicate JSON keys are refused, naming the file and the key.
printf '{"renderer": {"count": 8, "count": 4}}' > "$tmp/dup.json"
expect_error "dup.json: duplicate key 'count' in 'renderer'" render --config "$tmp/dup.json" --out "$tmp/f"

# Installable: cmake --install into a prefix, the prefix moved elsewhere, a named program
# renders from there (found beside the executable, not in the source tree).
cmake --install "$(dirname "$bin")" --prefix "$tmp/prefix" >"$tmp/install.log" 2>&1 \
  || fail "cmake --install failed: $(cat "$tmp/install.log")"
[ -x "$tmp/prefix/bin/pp5sim" ] || fail "no bin/pp5sim installed"
[ -s "$tmp/prefix/share/pp5sim/programs/phong.pp5" ] || fail "no programs installed"
# The examples the documentation's commands use, installed beside the programs.
for f in scenes/glass.json machines/half-machine.json meshes/knot.obj molecules/polyala-helix.pdb; do
  [ -s "$tmp/prefix/share/pp5sim/examples/$f" ] || fail "no examples/$f installed"
done
mv "$tmp/prefix" "$tmp/moved"
(cd "$tmp" && "$tmp/moved/bin/pp5sim" render --scene "$tmp/moved/share/pp5sim/examples/scenes/glass.json" \
  --set screen.width=128 --set screen.height=128 --fidelity timing --out "$tmp/inst-example" \
  >"$tmp/inst-example.log" 2>&1) || fail "an installed example failed: $(tail -3 "$tmp/inst-example.log")"
(cd "$tmp" && "$tmp/moved/bin/pp5sim" render --scene two-triangles --firmware gouraud \
  --set screen.width=128 --set screen.height=128 --out "$tmp/inst" >"$tmp/inst.log" 2>&1) \
  || fail "the moved installation failed: $(cat "$tmp/inst.log")"
grep -q "firmware $tmp/moved/share/pp5sim/programs/gouraud.pp5" "$tmp/inst.log" \
  || fail "the moved installation did not use its own programs: $(grep firmware "$tmp/inst.log")"
# A mesh file loads the installation's own assimp module (sim/scene/assimp_reader.hpp), and a
# process that reads none never loads assimp at all.
[ -s "$tmp/moved/lib/pp5sim/libpp5_assimp.so" ] || fail "no lib/pp5sim/libpp5_assimp.so installed"
cube="$(cd "$data" && pwd)/meshes/cube.obj"
(cd "$tmp" && LD_DEBUG=files "$tmp/moved/bin/pp5sim" render --scene "$cube" \
  --fidelity timing --out "$tmp/inst-mesh" >"$tmp/inst-mesh.log" 2>&1) \
  || fail "the moved installation could not render a mesh: $(tail -3 "$tmp/inst-mesh.log")"
grep -q "file=$tmp/moved/lib/pp5sim/libpp5_assimp.so .*dynamically loaded" "$tmp/inst-mesh.log" \
  || fail "the moved installation did not load its own assimp module"
(LD_DEBUG=files "$bin" render --scene two-triangles --fidelity timing --set screen.width=128 \
  --set screen.height=128 --out "$tmp/no-mesh" >"$tmp/no-mesh.log" 2>&1) || fail "no-mesh run failed"
if grep -q "libassimp" "$tmp/no-mesh.log"; then fail "a run without a mesh file loaded assimp"; fi
# Without the module, a mesh file is a clear error naming it and where it was looked for, and
# nothing is written (PP5_ASSIMP_MODULE names the one file to load).
PP5_ASSIMP_MODULE="$tmp/absent/libpp5_assimp.so" expect_error \
  "cube.obj: reading a mesh file needs pp5sim's assimp module, libpp5_assimp.so, which could not be loaded; tried $tmp/absent/libpp5_assimp.so (absent)" \
  render --scene "$data/meshes/cube.obj" --out "$tmp/no-module"
[ ! -e "$tmp/no-module" ] || fail "a run that could not load the assimp module left output"
mkfifo "$tmp/module-fifo"
PP5_ASSIMP_MODULE="$tmp/module-fifo" expect_error "module-fifo (not a regular file)" \
  render --scene "$data/meshes/cube.obj" --out "$tmp/no-module"
head -c 4096 /dev/zero > "$tmp/not-elf.so"
PP5_ASSIMP_MODULE="$tmp/not-elf.so" expect_error "not-elf.so: invalid ELF header" \
  render --scene "$data/meshes/cube.obj" --out "$tmp/no-module"
# A shared object that is not the module, and a module of another interface, are refused.
printf 'int unrelated(void) { return 1; }\n' > "$tmp/other.c"
printf 'const int pp5_assimp_reader_interface = 999;\nvoid* pp5_new_assimp_reader(void) { return 0; }\n' \
  > "$tmp/stale.c"
for so in other stale; do
  cc -shared -fPIC -o "$tmp/$so.so" "$tmp/$so.c" || fail "cc could not build $so.so"
done
PP5_ASSIMP_MODULE="$tmp/other.so" expect_error "other.so (not pp5sim's assimp module)" \
  render --scene "$data/meshes/cube.obj" --out "$tmp/no-module"
PP5_ASSIMP_MODULE="$tmp/stale.so" expect_error "stale.so (interface 999, this pp5sim needs 1)" \
  render --scene "$data/meshes/cube.obj" --out "$tmp/no-module"
[ ! -e "$tmp/no-module" ] || fail "a run that could not load the assimp module left output"
# A bare name is the built-in program even when a file of that name is in the current
# directory; a path names the file.
abs_bin="$(cd "$(dirname "$bin")" && pwd)/$(basename "$bin")"
mkdir -p "$tmp/cwd" && printf 'this is not firmware\n' > "$tmp/cwd/phong"
(cd "$tmp/cwd" && "$abs_bin" render --scene two-triangles --firmware phong --set screen.width=128 \
  --set screen.height=128 --out "$tmp/cwd/out" >"$tmp/cwd.log" 2>&1) \
  || fail "a file named phong in the current directory was run: $(tail -2 "$tmp/cwd.log")"
grep -q "firmware .*/phong.pp5" "$tmp/cwd.log" || fail "not the built-in phong"
(cd "$tmp/cwd" && "$abs_bin" render --scene two-triangles --firmware ./phong --out "$tmp/cwd/bad" >"$tmp/cwd2.log" 2>&1) \
  && fail "./phong (not firmware) was accepted"
grep -q "phong:1" "$tmp/cwd2.log" || fail "./phong was not read as a file: $(cat "$tmp/cwd2.log")"
expect_error "no built-in program of that name (built-in: accurate csg csg_accurate csg_layers epsilon" render --firmware nope --out "$tmp/f"

# scripts/check-includes on a tree of its own: an upward include fails with FILE:LINE, the
# same tree without it passes, and a cycle inside a layer is reported.
check="$(dirname "$0")/../scripts/check-includes"
mkdir -p "$tmp/layers/common" "$tmp/layers/firmware/isa" "$tmp/layers/models/a" "$tmp/layers/models/b" "$tmp/layers/tests"
printf '#pragma once\n' > "$tmp/layers/common/u.hpp"
printf '#include "common/u.hpp"\n#include <vector>\n#include "models/a/a.hpp"\n' > "$tmp/layers/firmware/isa/i.hpp"
printf '#include "models/b/b.hpp"\n' > "$tmp/layers/models/a/a.hpp"
printf '#include "models/a/a.hpp"\n#include "firmware/isa/i.hpp"\n' > "$tmp/layers/models/b/b.hpp"
printf '#include "models/a/a.hpp"\n' > "$tmp/layers/tests/t.cpp"
"$check" --root "$tmp/layers" >"$tmp/layers.log" 2>&1 && fail "check-includes passed an upward include"
grep -q '^firmware/isa/i.hpp:3: #include "models/a/a.hpp"' "$tmp/layers.log" || fail "check-includes said: $(cat "$tmp/layers.log")"
grep -q "directory cycle: models/a <-> models/b" "$tmp/layers.log" || fail "no directory cycle reported"
"$check" --root "$tmp/layers" --allow firmware/isa/i.hpp:models/a/a.hpp --dir-cycles=warn >"$tmp/layers.log" 2>&1 \
  || fail "check-includes --dir-cycles=warn failed a tree whose only fault is a cycle: $(cat "$tmp/layers.log")"
"$check" --root "$tmp/layers" --allow firmware/isa/i.hpp:models/a/a.hpp >/dev/null 2>&1 \
  && fail "check-includes passed a directory cycle (the default is to fail on one)"
"$check" --root "$tmp/layers" --allow firmware/isa/i.hpp:models/a/a.hpp --allow models/b/b.hpp:models/a/a.hpp >"$tmp/layers.log" 2>&1 \
  || fail "check-includes failed a clean tree: $(cat "$tmp/layers.log")"
# Fidelity levels (README "Fidelity levels"): timing only writes no image and removes an earlier
# one; a bad --fidelity item and a trace below the bit level are usage errors (status 2).
"$bin" render --scene two-triangles --out "$tmp/fid" >/dev/null || fail "render failed"
[ -f "$tmp/fid/frame.png" ] || fail "no frame.png at the bit level"
"$bin" render --scene two-triangles --fidelity timing --out "$tmp/fid" >"$tmp/fid.log" || fail "render --fidelity timing failed"
[ -f "$tmp/fid/frame.png" ] && fail "--fidelity timing left a frame.png"
grep -q "no frame.png" "$tmp/fid.log" || fail "render --fidelity timing did not say there is no image"
"$bin" render --scene two-triangles --fidelity pixels=wide --out "$tmp/fid" >/dev/null 2>&1 && fail "pixels=wide accepted"
"$bin" render --fidelity bitt --out "$tmp/fid" >/dev/null 2>"$tmp/fid.err"
[ $? -eq 2 ] || fail "--fidelity bitt: expected status 2"
grep -q "'bitt' is not a level" "$tmp/fid.err" || fail "--fidelity bitt: $(cat "$tmp/fid.err")"
"$bin" trace record --scene two-triangles --pixel 10,10 --set fidelity.pixels=word -o "$tmp/fid.pp5t" >/dev/null 2>"$tmp/fid.err"
[ $? -eq 2 ] || fail "trace at pixels=word: expected status 2"
grep -q "needs per-bit state" "$tmp/fid.err" || fail "trace at pixels=word: $(cat "$tmp/fid.err")"
echo "1 passed, 0 failed"
