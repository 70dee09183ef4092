#!/usr/bin/env bash
# lmanim beside Blender Cycles on the four study scenes (STUDY.md, "Beside
# Blender Cycles"): per scene, lmanim's Whitted frame (to fit Cycles' light
# units on), Cycles at 1-64 spp with and without OpenImageDenoise
# (cycles_render.py), LMM1 over a fly-through that returns to the study's
# view every 6 frames (flight.py), then `lmanim study` with Whitted, the
# LMM1 sweep and area, and every Cycles and LMM1 sequence as a --candidate,
# all measured against one reference in one run. Writes the tables to
# docs/study/cycles/tables.md and each scene's CSV and plots beside it;
# the frames stay under ./study-cycles.
#
# Run from the repository root. Needs Python 3.11 for the `bpy` wheel; the
# first run makes a virtual environment with it under target/bpy-venv
# (about 400 MB) and later runs reuse it. Environment:
#   SCENES="box leaves street wall"   the study scenes to run
#   METHODS=whitted,lmm1,area         lmanim's methods to sweep
#   REUSE_REFERENCE=1                 measure against study-cycles/<scene>/study/reference.exr
#                                     from an earlier run instead of rendering it again
#   PYTHON=python3.11                 the interpreter for the venv
set -euo pipefail
here=docs/study/cycles
scenes=${SCENES:-box leaves street wall}
methods=${METHODS:-whitted,lmm1,area}
bpy_version=5.0.1
venv=target/bpy-venv
size=(--width 320 --height 180)

if ! "$venv/bin/python" -c "import bpy, sys; sys.exit(bpy.app.version_string != '$bpy_version')" 2>/dev/null; then
  "${PYTHON:-python3.11}" -m venv "$venv"
  "$venv/bin/pip" install --quiet "bpy==$bpy_version"
fi
cargo build --release --quiet
lmanim=target/release/lmanim
for s in $scenes; do
  [ -f "animations/study-$s.gltf" ] || cargo run --release --quiet --example make_animations
done

for s in $scenes; do
  scene=animations/study-$s.gltf
  work=study-cycles/$s
  mkdir -p "$work/cycles" "$work/flight"
  echo "== $s: lmanim's Whitted frame, for the light units" >&2
  "$lmanim" "$scene" "${size[@]}" --method whitted --exr-float --no-cache --quiet \
      --out "$work/whitted.exr"
  echo "== $s: Cycles" >&2
  "$venv/bin/python" "$here/cycles_render.py" "$scene" "$work/whitted.exr" "$work/cycles" 2>&1 |
      { grep -v -e '| INFO:' -e '^Fra:' -e 'CUEW' -e '^Saved:' -e '^ *Time:' || true; } >&2
  echo "== $s: LMM1 over the fly-through" >&2
  { read -r frames; read -r returns; } < <(python3 "$here/flight.py" "$scene" "$work/flight/path.ron")
  "$lmanim" "$scene" "${size[@]}" --camera-path "$work/flight/path.ron" --frames "$frames" \
      --method lmm1 --exr-float --no-cache --quiet --stats "$work/flight/stats.json" \
      --out "$work/flight/lmm1.####.exr"
  flight=$(python3 - "$work/flight" "$returns" <<'PY'
import json, os, sys
folder, returns = sys.argv[1], [int(f) for f in sys.argv[2].split(",")]
frames = json.load(open(os.path.join(folder, "stats.json")))["frames"]
seconds = sum(f["seconds"] for f in frames) / len(frames)
paths = ",".join(os.path.abspath(os.path.join(folder, f"lmm1.{f:04}.exr")) for f in returns)
print(f"lmm1-flight {len(returns)} returns={seconds:.6f}:{paths}")
PY
)
  candidates=(--candidate "$flight")
  while read -r line; do candidates+=(--candidate "$line"); done < "$work/cycles/candidates.txt"
  against=()
  if [ -n "${REUSE_REFERENCE:-}" ] && [ -f "$work/study/reference.exr" ]; then
    cp "$work/study/reference.exr" "$work/reference.exr"
    against=(--reference "$work/reference.exr")
  fi
  echo "== $s: lmanim study" >&2
  "$lmanim" study "$scene" "${size[@]}" --methods "$methods" "${against[@]}" \
      "${candidates[@]}" --out "$work/study" --quiet
  cp "$work/study/study.csv" "$here/$s.csv"
  cp "$work/study/study.png" "$here/$s-study.png"
  cp "$work/study/crops.png" "$here/$s-crops.png"
  cp "$work/cycles/cycles.json" "$here/$s-cycles.json"
done
python3 "$here/tables.py" study-cycles $scenes > "$here/tables.md"
cat "$here/tables.md"
