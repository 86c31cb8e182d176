#!/usr/bin/env bash
# Scene files with materials, lights and a firmware of their own, as `pp5sim render` meets
# them: the scene's program unless --firmware overrides it, and a warning when a program
# would ignore the scene's opacity or all but its first light.
. "$(dirname "$0")/cli_lib.sh"
data="$(dirname "$0")/data"
small=(--set screen.width=128 --set screen.height=128)

"$bin" render --scene "$data/scenes/glass_quads.json" "${small[@]}" --out "$tmp/own" \
  >"$tmp/own.log" 2>"$tmp/own.err" || fail "render failed: $(cat "$tmp/own.err")"
grep -q "firmware .*transparent.pp5" "$tmp/own.log" || fail "the scene's firmware was not used"
[ -s "$tmp/own.err" ] && fail "unexpected stderr: $(cat "$tmp/own.err")"
[ -s "$tmp/own/frame.png" ] || fail "no frame"

"$bin" render --scene "$data/scenes/glass_quads.json" --firmware gouraud "${small[@]}" \
  --out "$tmp/over" >"$tmp/over.log" 2>"$tmp/over.err" || fail "render failed: $(cat "$tmp/over.err")"
grep -q "firmware .*gouraud.pp5" "$tmp/over.log" || fail "--firmware did not override the scene's"
[ "$(wc -l <"$tmp/over.err")" -eq 1 ] || fail "expected a one-line warning, got: $(cat "$tmp/over.err")"
grep -q "^warning: scene 'glass-quads' has materials with opacity < 1, but firmware 'gouraud' has no 'opacity' expression: the opacity is ignored (use --firmware transparent)$" \
  "$tmp/over.err" || fail "wrong warning: $(cat "$tmp/over.err")"
grep -q "opacity is ignored" "$tmp/over.log" && fail "the warning went to stdout"

# An opaque scene: no warning whatever the program.
"$bin" render --scene two-triangles --firmware phong "${small[@]}" --out "$tmp/opaque" \
  >/dev/null 2>"$tmp/opaque.err" || fail "render failed"
[ -s "$tmp/opaque.err" ] && fail "unexpected stderr: $(cat "$tmp/opaque.err")"

# Two lights: a program that lights pixels itself without a `light` procedure sees only the
# first; the example scene's own program (transparent) warns about nothing.
example="$(dirname "$0")/../examples/scenes/glass.json"
"$bin" render --scene "$example" --firmware exactmatch "${small[@]}" --out "$tmp/em" \
  >/dev/null 2>"$tmp/em.err" || fail "render failed: $(cat "$tmp/em.err")"
grep -q "^warning: scene 'glass' has 2 lights, but firmware 'exactmatch' has no 'light' procedure: it shades with the first light only" \
  "$tmp/em.err" || fail "no light warning: $(cat "$tmp/em.err")"
grep -q "opacity is ignored" "$tmp/em.err" || fail "no opacity warning: $(cat "$tmp/em.err")"
for fw in phong gouraud; do
  "$bin" render --scene "$example" --firmware $fw "${small[@]}" --out "$tmp/$fw" >/dev/null \
    2>"$tmp/$fw.err" || fail "render failed"
  grep -q "lights, but" "$tmp/$fw.err" && fail "$fw sums the lights, yet: $(cat "$tmp/$fw.err")"
done
"$bin" render --scene "$example" "${small[@]}" --out "$tmp/ex" >/dev/null 2>"$tmp/ex.err" \
  || fail "example render failed: $(cat "$tmp/ex.err")"
[ -s "$tmp/ex.err" ] && fail "unexpected stderr: $(cat "$tmp/ex.err")"

printf '{"meshes": [{"builtin": "two-triangles", "material": "stone"}]}' >"$tmp/bad.json"
expect_error "bad.json: key 'meshes\[0\].material' names an unknown material 'stone'" \
  render --scene "$tmp/bad.json" --out "$tmp/bad"
printf '{"meshes": [{"builtin": "two-triangles"}], "firmware": "nope"}' >"$tmp/nofw.json"
expect_error "--firmware nope: no built-in program of that name" render --scene "$tmp/nofw.json" --out "$tmp/bad"
[ -e "$tmp/bad/frame.png" ] && fail "output after bad input"
"$bin" render --help | grep -q "transparent_threshold), never a file .*\[the scene file's \"firmware\", else phong\]" \
  || fail "render --help does not describe the default firmware"
# trace and sweep take scene files too, with the scene's program by default.
"$bin" trace record --scene "$data/scenes/glass_quads.json" "${small[@]}" --pixel 64,64 \
  --out "$tmp/glass.pp5t" >"$tmp/trace.log" 2>&1 || fail "trace failed: $(cat "$tmp/trace.log")"
grep -q "scene 'glass-quads'.*firmware .*transparent" "$tmp/trace.log" \
  || fail "trace did not use the scene's firmware: $(cat "$tmp/trace.log")"
"$bin" sweep --scene "$data/scenes/glass_quads.json" "${small[@]}" --grid renderer.count=1,2 \
  --out "$tmp/sweep" >"$tmp/sweep.log" 2>&1 || fail "sweep failed: $(cat "$tmp/sweep.log")"
grep -q '"firmware": ".*transparent' "$tmp/sweep/renderer.count-2/stats.json" \
  || fail "sweep did not use the scene's firmware"
# Duplicate keys anywhere in a scene file (its materials included) are refused by name.
printf '{"meshes": [{"builtin": "two-triangles", "material": "m"}], "materials": {"m": {"color": [1, 0, 0]}, "m": {"color": [0, 1, 0]}}}' >"$tmp/dupmat.json"
expect_error "dupmat.json: duplicate key 'm' in 'materials'" render --scene "$tmp/dupmat.json" --out "$tmp/bad"
printf '{"meshes": [{"builtin": "two-triangles", "scale": 1, "scale": 2}]}' >"$tmp/dupmesh.json"
expect_error "dupmesh.json: duplicate key 'scale' in 'meshes\[\]'" render --scene "$tmp/dupmesh.json" --out "$tmp/bad"
# Frame parameters in a scene file: the same as --param; computed ones and unknown names are
# refused naming the file and the key; the command line wins over the scene file.
printf '{"meshes": [{"builtin": "two-triangles"}], "firmware": "threshold", "parameters": {"threshold": 8192}}' >"$tmp/thr.json"
printf '{"meshes": [{"builtin": "two-triangles"}], "firmware": "threshold"}' >"$tmp/thr0.json"
"$bin" render --scene "$tmp/thr.json" "${small[@]}" --out "$tmp/t1" >/dev/null 2>&1 || fail "scene parameters failed"
"$bin" render --scene "$tmp/thr0.json" "${small[@]}" --param threshold=8192 --out "$tmp/t2" >/dev/null 2>&1 || fail "--param failed"
"$bin" render --scene "$tmp/thr.json" "${small[@]}" --param threshold=32768 --out "$tmp/t3" >/dev/null 2>&1 || fail "--param over the scene failed"
"$bin" render --scene "$tmp/thr0.json" "${small[@]}" --out "$tmp/t4" >/dev/null 2>&1 || fail "default render failed"
cmp -s "$tmp/t1/frame.png" "$tmp/t2/frame.png" || fail "the scene file's parameter differs from --param"
cmp -s "$tmp/t3/frame.png" "$tmp/t4/frame.png" || fail "--param did not win over the scene file"
cmp -s "$tmp/t1/frame.png" "$tmp/t4/frame.png" && fail "threshold=8192 changed nothing (the test cannot tell)"
printf '{"meshes": [{"builtin": "two-triangles"}], "parameters": {"ambient": 3}}' >"$tmp/amb.json"
expect_error "amb.json: key 'parameters.ambient' cannot be set: the GP computes it" render --scene "$tmp/amb.json" --out "$tmp/bad"
printf '{"meshes": [{"builtin": "two-triangles"}], "parameters": {"thresh": 3}}' >"$tmp/unk.json"
expect_error "unk.json: key 'parameters.thresh' is not a frame parameter" render --scene "$tmp/unk.json" --out "$tmp/bad"
printf '{"meshes": [{"builtin": "two-triangles"}], "parameters": {"delta": 5000}}' >"$tmp/rng.json"
expect_error "'frame.delta' = 5000 is out of range" render --scene "$tmp/rng.json" --out "$tmp/bad"
[ -e "$tmp/bad/frame.png" ] && fail "output after bad input"

# A scene's CSG expression is checked and normalised; a program without the CSG procedures
# says it draws the meshes as they are instead of passing their union off as the result.
"$bin" render --scene "$(dirname "$0")/../fuzz/corpus/scene/csg_spheres.json" "${small[@]}" \
  --out "$tmp/csg" >"$tmp/csg.log" 2>"$tmp/csg.err" || fail "render failed: $(cat "$tmp/csg.err")"
grep -q "^warning: scene 'csg_spheres' gives a CSG expression ([0-9]* products\{0,1\} after normalising), but firmware 'phong' does not draw CSG" \
  "$tmp/csg.err" || fail "no CSG warning: $(cat "$tmp/csg.err")"
# csg.pp5 draws it (the expression's solids, and the sphere in no solid), without the warning.
"$bin" render --scene "$(dirname "$0")/../fuzz/corpus/scene/csg_spheres.json" "${small[@]}" \
  --firmware csg --out "$tmp/csg2" >"$tmp/csg2.log" 2>"$tmp/csg2.err" ||
  fail "render --firmware csg failed: $(cat "$tmp/csg2.err")"
grep -q "CSG" "$tmp/csg2.err" && fail "CSG warning with csg.pp5: $(cat "$tmp/csg2.err")"
[ -s "$tmp/csg2/frame.png" ] || fail "no frame.png from csg.pp5"
echo "scene_cli: ok"
