#!/usr/bin/env bash
# The set-up benchmark (docs/benchmarks.md, "Set-up"): pre-shot cost of the office family at 30k/100k/300k triangles: wall seconds
# from launch to the set-up's summary line (import + set-up), and the summary.
# PATTERN names another line to stop at (a build without the summary: "at the start").
set -euo pipefail
solver=${SOLVER:-target/release/solver}
scenegen=${SCENEGEN:-target/release/scenegen}
dir=${DIR:-/tmp/office-bench}
mkdir -p "$dir"
for n in 30000 100000 300000; do
  name=office$((n / 1000))k
  [ -e "$dir/$name.toml" ] || "$scenegen" office --triangles $n -o "$dir" --name $name > /dev/null
  rm -f "$dir/$name.sol" "$dir/$name.sol.checkpoint"
  start=$(date +%s.%N)
  line=$("$solver" solve "$dir/$name.toml" -o "$dir/$name.sol" --preset draft --max-shots 1 2>&1 \
    | grep -m1 "${PATTERN:-solver: set-up }" || true)
  end=$(date +%s.%N)
  echo "$n $(echo "$end - $start" | bc) | $line"
  pkill -f "$dir/$name.toml" 2>/dev/null || true
  rm -f "$dir/$name.sol" "$dir/$name.sol.checkpoint"
done
