#!/usr/bin/env bash
# The accuracy study of docs/accuracy.md: each preset's solution, shown by
# `runtime screenshot --mono` at 8x the truth's size (box-filtered by
# `solver compare` to the truth's pixel footprints), against a path-traced
# truth from `solver reference` at mean relative standard error <= 0.5%.
#
# Usage: tools/accuracy/study.sh OUT_DIR SCENE TRUTH.exr [camera flags...]
#   e.g. tools/accuracy/study.sh out/acc config/cornell_box.toml out/acc/truth.exr
# The truth is made first with (same camera flags):
#   solver reference SCENE -o TRUTH.exr --size 64x64 --target-error 0.005 --seed 1
# Prints one line per preset (solve seconds, MARE, relative RMSE, HDR-FLIP, mean
# bias) and writes OUT_DIR/PRESET.json (all of compare's figures, the
# per-material table included) and OUT_DIR/PRESET-heat.png (signed error).
set -euo pipefail
out=$1 scene=$2 truth=$3; shift 3
mkdir -p "$out"
bin=${BIN:-target/release}
size=$(python3 -c "import sys; print('%dx%d' % (8 * int(sys.argv[1]), 8 * int(sys.argv[2])))" \
  $("$bin/solver" compare "$truth" "$truth" --flip none --json |
    python3 -c "import json,sys; d=json.load(sys.stdin); print(d['width'], d['height'])"))
for preset in ${PRESETS:-draft medium final}; do
  start=$(date +%s.%N)
  "$bin/solver" solve "$scene" -o "$out/$preset.sol" --preset "$preset" >"$out/$preset.solve.log" 2>&1
  seconds=$(python3 -c "print(f'{$(date +%s.%N) - $start:.1f}')")
  "$bin/runtime" screenshot "$out/$preset.sol" --mono --size "$size" "$@" --out "$out/$preset" >/dev/null 2>&1
  "$bin/solver" compare "$out/$preset.exr" "$truth" --json --heatmap "$out/$preset-heat.png" \
    >"$out/$preset.json" 2>/dev/null
  python3 - "$out/$preset.json" "$preset" "$seconds" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
flip = s.get("flip") or {}
print(f"{sys.argv[2]:7s} solve {sys.argv[3]:>6s} s  MARE {100*s['mare']:.2f}%  "
      f"rel. RMSE {100*s['relative_rmse']:.2f}%  HDR-FLIP {flip.get('mean', float('nan')):.4f}  "
      f"mean {100*(s['test_mean']/s['reference_mean']-1):+.2f}%")
PY
done
