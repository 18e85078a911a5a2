#!/usr/bin/env bash
# The scale benchmark of issue 13: builds the release solver and scale-bench
# (tools/scenegen), then solves each generated family × size × preset under a
# wall-clock limit and writes the table, growth slopes and plots.
#
#   tools/scale/bench.sh                                   # everything, 30 min a run
#   tools/scale/bench.sh --sizes 1000,10000 --presets draft --limit-s 300
#
# Arguments are passed to scale-bench (see `scale-bench --help`): --families,
# --sizes, --presets, --limit-s, --grace-s, --threads, --seed, --out (default
# target/scale), --work, --keep, --solver-arg (repeatable: one more argument
# for every solve, e.g. --solver-arg=--shooters --solver-arg=patch, or
# --solver-arg=--max-shots --solver-arg=100 for the cost of the first shots of
# scenes too large to solve in full; the table does not show them, so record
# them with the figures). Results: OUT/scale.csv, OUT/scale.md,
# OUT/scale-cpu.svg, OUT/scale-rss.svg. Record figures in docs/scale.md with
# the commit, the machine and its load.
set -euo pipefail
cd "$(dirname "$0")/../.."
export CARGO_INCREMENTAL=0
cargo build --release -p solver --bin solver
cargo build --release -p scenegen --bin scale-bench
echo "bench.sh: commit $(git rev-parse --short HEAD), $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg)" >&2
exec target/release/scale-bench --solver target/release/solver "$@"
