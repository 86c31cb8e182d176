#!/usr/bin/env bash
# pp5sim animate: every output of a small animation, the same bytes on 1 and 2 host threads,
# bad keyframes refused with no output, and trace/snapshot --frame K looking at frame K.
. "$(dirname "$0")/cli_lib.sh"
root="$(dirname "$0")/.."
small=(--set screen.width=128 --set screen.height=128 --set renderer.count=2)
torus=(--scene torus --frames 3 --tessellation 48 12 "${small[@]}")

"$bin" animate "${torus[@]}" -j 1 --out "$tmp/a1" >"$tmp/a1.log" 2>&1 ||
  fail "animate failed: $(cat "$tmp/a1.log")"
for f in frame-0000.png frame-0001.png frame-0002.png animation.gif frames.csv regions.png \
  stats.json config.json timeline.json; do
  [ -s "$tmp/a1/$f" ] || fail "no $f"
done
[ -e "$tmp/a1/frame-0003.png" ] && fail "a fourth frame"
grep -q "turning in the zw-plane of 4-space: 3 frames" "$tmp/a1.log" || fail "$(cat "$tmp/a1.log")"
# frames.csv: a header with units and one row per frame; frames overlap (a frame's set-up
# starts before the frame before has ended), and a frame's time is from the end of the one before.
[ "$(wc -l <"$tmp/a1/frames.csv")" -eq 4 ] || fail "frames.csv: $(cat "$tmp/a1/frames.csv")"
head -1 "$tmp/a1/frames.csv" | grep -q "^frame,animation_seconds,start_ms,frame_ms," || fail "header"
python3 - "$tmp/a1" <<'PY' || fail "frames.csv, stats.json or timeline.json do not agree"
import csv, json, sys
d = sys.argv[1]
rows = list(csv.DictReader(open(d + "/frames.csv")))
stats = json.load(open(d + "/stats.json"))
assert [int(r["frame"]) for r in rows] == [0, 1, 2]
for k, r in enumerate(rows):
    s = stats["frames"][k]
    assert abs(float(r["frame_ms"]) - s["frame"]["simulated_seconds"] * 1e3) < 1e-5, r
    assert r["bottleneck"] == s["timing"]["bottleneck"]
    assert abs(float(r["latency_ms"]) - float(r["end_ms"]) + float(r["start_ms"])) < 1e-5, r
    if k:
        prev = rows[k - 1]
        assert abs(float(r["end_ms"]) - float(prev["end_ms"]) - float(r["frame_ms"])) < 1e-5, r
        assert float(r["start_ms"]) < float(prev["end_ms"]), (prev, r)
# The frames differ: the torus turned.
assert len({r["renderer_busy_cycles"] for r in rows}) > 1 or len({r["frame_ms"] for r in rows}) > 1
# The timeline spans every frame, and marks each.
ev = json.load(open(d + "/timeline.json"))["traceEvents"]
frames = [e for e in ev if e.get("name", "").startswith("frame ") and e.get("ph") == "X"]
assert len(frames) == 3, frames
end = float(rows[2]["end_ms"])
assert max(e["ts"] + e.get("dur", 0) for e in ev if "ts" in e) >= end * 1e3 - 1
assert any(e.get("ts", 0) > float(rows[2]["start_ms"]) * 1e3 and e.get("pid") == 3 for e in ev)
# Frame slices overlap on the frames track (two rows), and GP set-up of a frame runs while a
# Renderer still works on the frame before.
spans = sorted((e["ts"], e["ts"] + e["dur"]) for e in frames)
assert spans[1][0] < spans[0][1], spans
geometry = [e for e in ev if e.get("pid") == 1 and e.get("name") == "geometry of frame 1"]
renderer = [e for e in ev if e.get("pid") == 3 and e.get("ph") == "X"]
assert geometry and any(r["ts"] < geometry[0]["ts"] < r["ts"] + r["dur"] for r in renderer)
assert stats["summary"]["frames"] == 3
assert stats["summary"]["run"]["overlapped_frames"] == 2
PY
# The GIF: three frames, and an ordinary decoder (gdk-pixbuf) opens it where one is installed.
[ "$(head -c 6 "$tmp/a1/animation.gif")" = "GIF89a" ] || fail "not a GIF89a"
if command -v gdk-pixbuf-thumbnailer >/dev/null; then
  gdk-pixbuf-thumbnailer -s 128 "$tmp/a1/animation.gif" "$tmp/gif0.png" && [ -s "$tmp/gif0.png" ] ||
    fail "gdk-pixbuf cannot read animation.gif"
fi

# The same bits on 2 threads.
"$bin" animate "${torus[@]}" -j 2 --out "$tmp/a2" >/dev/null 2>&1 || fail "animate -j 2 failed"
for f in frame-0000.png frame-0001.png frame-0002.png animation.gif regions.png timeline.json; do
  cmp -s "$tmp/a1/$f" "$tmp/a2/$f" || fail "$f differs between -j 1 and -j 2"
done
diff <(cut -d, -f1-16 "$tmp/a1/frames.csv") <(cut -d, -f1-16 "$tmp/a2/frames.csv") >/dev/null ||
  fail "frames.csv differs between -j 1 and -j 2 (beyond host_ms)"

# Into the same folder again, fewer frames and a report: the earlier run's extra frame goes.
"$bin" animate --scene torus --frames 2 --tessellation 48 12 "${small[@]}" --report \
  --out "$tmp/a2" >"$tmp/r.log" 2>&1 || fail "animate --report failed: $(cat "$tmp/r.log")"
[ -e "$tmp/a2/frame-0002.png" ] && fail "a frame of the earlier run was left"
[ -s "$tmp/a2/frame-0001.png" ] || fail "no frame-0001.png"
grep -q 'data:image/gif;base64,' "$tmp/a2/report.html" || fail "the report holds no animation"
grep -q 'id="frame-1"' "$tmp/a2/report.html" || fail "the report holds no frame 1"
grep -q 'id="timeline-chart"' "$tmp/a2/report.html" || fail "no timeline"

# A scene file's keyframes; bad ones are refused, naming the key, with no output.
"$bin" animate --scene "$root/examples/scenes/orbit.json" --frames 2 "${small[@]}" \
  --out "$tmp/orbit" >/dev/null 2>&1 || fail "the orbit example failed"
[ -s "$tmp/orbit/frame-0001.png" ] || fail "no orbit frame"
cat >"$tmp/bad.json" <<'JSON'
{"meshes": [{"builtin": "two-triangles"}],
 "animation": {"camera": [{"frame": 3, "eye": [0, 0, 5], "target": [0, 0, 0]},
                          {"frame": 1, "eye": [1, 0, 5], "target": [0, 0, 0]}]}}
JSON
expect_error "bad.json: key 'animation.camera\[1\].frame' must be greater than the previous key's frame 3" \
  animate --scene "$tmp/bad.json" "${small[@]}" --out "$tmp/bad"
[ -e "$tmp/bad" ] && fail "a refused animation left $tmp/bad"

# trace record --frame K: frame K's pixel, as animate drew it.
"$bin" trace record "${small[@]}" --scene torus --tessellation 48 12 --frame 2 \
  --animation-frames 3 --pixel 64,64 -o "$tmp/t.pp5t" >"$tmp/t.log" 2>&1 ||
  fail "trace --frame failed: $(cat "$tmp/t.log")"
want=$(python3 - "$tmp/a1/frame-0002.png" <<'PY'
import struct, sys, zlib
d = open(sys.argv[1], "rb").read(); pos = 8; idat = b""
while pos < len(d):
    n, = struct.unpack(">I", d[pos:pos + 4]); t = d[pos + 4:pos + 8]; c = d[pos + 8:pos + 8 + n]
    pos += 12 + n
    if t == b"IHDR": w, h = struct.unpack(">II", c[:8])
    if t == b"IDAT": idat += c
raw = zlib.decompress(idat); stride = w * 3; prev = bytearray(stride); i = 0
for y in range(h):
    f = raw[i]; line = bytearray(raw[i + 1:i + 1 + stride]); i += 1 + stride
    for x in range(stride):
        a = line[x - 3] if x >= 3 else 0; b = prev[x]; c = prev[x - 3] if x >= 3 else 0
        if f == 1: line[x] = (line[x] + a) & 255
        elif f == 2: line[x] = (line[x] + b) & 255
        elif f == 3: line[x] = (line[x] + (a + b) // 2) & 255
        elif f == 4:
            p = a + b - c; pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
            line[x] = (line[x] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
    if y == 64: print("({}, {}, {})".format(*line[64 * 3:64 * 3 + 3])); break
    prev = line
PY
)
grep -q "frame colour of pixel 64,64: $want" "$tmp/t.log" ||
  fail "trace --frame 2 saw $(grep 'frame colour' "$tmp/t.log"), frame-0002.png has $want"
"$bin" trace record "${small[@]}" --scene torus --tessellation 48 12 --frame 0 \
  --animation-frames 3 --pixel 64,64 -o "$tmp/t0.pp5t" >"$tmp/t0.log" 2>&1 || fail "trace --frame 0"
"$bin" trace snapshot "${small[@]}" --scene torus --tessellation 48 12 --frame 1 \
  --animation-frames 3 --region 0 -o "$tmp/s1.pp5m" >/dev/null 2>&1 || fail "snapshot --frame 1"
[ -s "$tmp/s1.pp5m" ] || fail "no snapshot"
expect_error "animation-frames needs --frame" trace record "${small[@]}" --animation-frames 3 \
  --pixel 1,1 -o "$tmp/x.pp5t"
echo "animate CLI: ok"
