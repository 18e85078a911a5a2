#!/usr/bin/env bash
# Speed unchanged by issue 40's refactor: builds the solver of the base commit
# (the last one before the refactor) beside this tree's, both in the release
# profile, and solves the same scenes with both. For each scene it measures
#   - instructions retired (user space), which hold under load: `perf stat -e
#     instructions:u` where the machine has hardware counters, else callgrind
#     (Cornell presets only: callgrind runs about 20 times slower than the
#     solve, hours for a 100k scene); one solve each on one thread, so that the
#     count is the work itself and not the spinning of idle worker threads;
#   - the median of N interleaved wall-clock solves (base, new, base, new, ...)
#     on every core, which does not hold under load: the 1-minute load average
#     is printed beside it.
# Then prints one table row per scene, and exits 1 when an instruction ratio
# (new / base) is outside 0.97..1.03. docs/lab/refactor-speed.md has the
# figures and says how to read them.
#
# NOT run by CI: the full set (three Cornell presets and three 100k scenes at
# medium, 2 x (1 + N) solves each) takes about an hour on a quiet 2-core
# machine and hours on a loaded one.
#
# Usage: bash scripts/same-speed.sh [BASE]   (BASE, or SAME_SPEED_BASE, defaults to the commit
# below). Needs the repository's history: a shallow clone cannot build BASE.
# Environment:
#   SAME_SPEED_SCENES     scenes to run, space-separated SCENE:PRESET (default:
#                         all six; SCENE is `cornell` or a scenegen family)
#   SAME_SPEED_RUNS       wall-clock solves per solver (default 5)
#   SAME_SPEED_COUNTER    perf, callgrind or none (default: perf if the
#                         counter works here, else callgrind for the Cornell
#                         presets and none for the 100k scenes)
#   SAME_SPEED_TRIANGLES  triangles of the scenegen scenes (default 100000)
#   SAME_SPEED_DIR        work folder (default target/same-speed)
set -euo pipefail
export LC_ALL=C
cd "$(dirname "$0")/.."

# 3f4b4d1: main before the refactor, the same base as scripts/same-results.sh.
base=${1:-${SAME_SPEED_BASE:-3f4b4d1}}
scenes=${SAME_SPEED_SCENES:-cornell:draft cornell:medium cornell:final cornell-boxes:medium spheres-room:medium floor-plan:medium}
runs=${SAME_SPEED_RUNS:-5}
triangles=${SAME_SPEED_TRIANGLES:-100000}
low=0.97
high=1.03

work=${SAME_SPEED_DIR:-target/same-speed}
mkdir -p "$work"
work=$(cd "$work" && pwd)

# The 1-minute load average, the figure printed beside each measurement.
load() { cut -d' ' -f1 /proc/loadavg; }

# Which instruction counter works here. A virtual machine without a PMU makes
# perf print "<not supported>" and still exit 0, so read the count itself.
counter=${SAME_SPEED_COUNTER:-}
if [ -z "$counter" ]; then
    counter=none
    if command -v perf >/dev/null &&
        perf stat -e instructions:u -x, -o "$work/probe.perf" true 2>/dev/null &&
        grep -Eq '^[0-9]+,' "$work/probe.perf"; then
        counter=perf
    elif command -v valgrind >/dev/null; then
        counter=callgrind
        echo "same-speed: no hardware instruction counter here (perf: <not supported>);" \
            "counting with callgrind, for the Cornell presets only" >&2
    else
        echo "same-speed: neither a hardware counter nor valgrind: wall clock only" >&2
    fi
fi
case $counter in
    perf | callgrind | none) ;;
    *)
        echo "same-speed: SAME_SPEED_COUNTER=$counter: expected perf, callgrind or none" >&2
        exit 1
        ;;
esac

source scripts/lib/base-solver.sh
build_base_solver "$base" "$work" "$work/base-target"
base_hash=$(cat "$work/base-commit")
echo "== same-speed: building this tree's solver and scenegen, release"
cargo build --release --locked -p solver -p scenegen
base_solver="$work/base-solver"
new_solver="$(pwd)/target/release/solver"
# What "new" is, named now: the tree may change while the solves run.
new_label="$(git rev-parse --short HEAD)$(git diff --quiet HEAD || echo ' + uncommitted changes')"
count_label="$counter"
[ "$counter" = none ] || count_label="$counter, one thread"

# The scene config of SCENE (generated once for a scenegen family; both
# solvers solve the same files).
scene_config() {
    local scene=$1
    if [ "$scene" = cornell ]; then
        echo "$(pwd)/config/cornell_box.toml"
        return
    fi
    local dir="$work/scenes"
    if [ ! -f "$dir/$scene-$triangles.toml" ]; then
        mkdir -p "$dir"
        target/release/scenegen "$scene" --triangles "$triangles" --name "$scene-$triangles" \
            -o "$dir" >&2
    fi
    echo "$dir/$scene-$triangles.toml"
}

# One solve: run_solve SOLVER CONFIG PRESET [FLAGS...], under the command in
# the array `wrap` (a counter, or nothing). Its output files are removed after
# it; its log stays in $work/last.log.
wrap=()
run_solve() {
    local solver=$1 config=$2 preset=$3
    shift 3
    local out="$work/out/solution.sol"
    mkdir -p "$work/out"
    rm -f "$out"*
    if ! "${wrap[@]}" "$solver" solve "$config" --preset "$preset" -o "$out" "$@" \
        >"$work/last.log" 2>&1; then
        echo "same-speed: solve failed: ${wrap[*]} $solver solve $config --preset $preset $*" >&2
        tail -n 20 "$work/last.log" >&2
        exit 1
    fi
    rm -f "$out"*
}

# Instructions retired by one solve on one thread: count SOLVER CONFIG PRESET.
# One thread, because idle rayon workers spin for a while before they sleep,
# and how long depends on the load; under callgrind, which runs one thread at
# a time, that spinning would be most of the count.
count() {
    local solver=$1 config=$2 preset=$3 file="$work/count.out" n
    rm -f "$file"
    case $counter in
        perf) wrap=(perf stat -e instructions:u -x, -o "$file" --) ;;
        callgrind)
            wrap=(valgrind --tool=callgrind --callgrind-out-file="$work/callgrind.out"
                --log-file="$file")
            ;;
    esac
    run_solve "$solver" "$config" "$preset" --threads 1
    wrap=()
    case $counter in
        # A hybrid CPU counts its core kinds on separate lines: add them.
        perf) n=$(awk -F, '$3 ~ /instructions/ && $1 ~ /^[0-9]+$/ { n += $1; f = 1 }
                END { if (f) printf "%.0f\n", n }' "$file") ;;
        callgrind) n=$(sed -n 's/.*Collected : *\([0-9][0-9]*\).*/\1/p' "$file") ;;
    esac
    if ! [[ $n =~ ^[0-9]+$ ]]; then
        echo "same-speed: no instruction count from $counter in $file:" >&2
        cat "$file" >&2
        exit 1
    fi
    echo "$n"
}

# Seconds of one solve on every core: wall SOLVER CONFIG PRESET.
wall() {
    local t0=$EPOCHREALTIME
    run_solve "$@"
    local t1=$EPOCHREALTIME
    awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.2f\n", b - a }'
}

median() {
    printf '%s\n' "$@" | sort -g |
        awk '{ v[NR] = $1 } END { print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2 }'
}

runs_log="$work/runs.tsv"
printf 'scene\tpreset\tsolver\tkind\tvalue\tload_1min\n' >"$runs_log"
rows=()
failed=0
for item in $scenes; do
    scene=${item%%:*}
    preset=${item#*:}
    config=$(scene_config "$scene")
    load0=$(load)
    base_n=- new_n=- ratio=-
    # Callgrind chosen for want of a counter counts the Cornell presets only;
    # SAME_SPEED_COUNTER=callgrind counts every scene, however long it takes.
    if [ "$counter" = perf ] || { [ "$counter" = callgrind ] &&
        { [ "$scene" = cornell ] || [ -n "${SAME_SPEED_COUNTER:-}" ]; }; }; then
        echo "== same-speed: $scene $preset: instructions ($counter, one thread), load $(load)" >&2
        base_n=$(count "$base_solver" "$config" "$preset")
        printf '%s\t%s\tbase\tinstructions\t%s\t%s\n' "$scene" "$preset" "$base_n" "$(load)" >>"$runs_log"
        new_n=$(count "$new_solver" "$config" "$preset")
        printf '%s\t%s\tnew\tinstructions\t%s\t%s\n' "$scene" "$preset" "$new_n" "$(load)" >>"$runs_log"
        ratio=$(awk -v a="$base_n" -v b="$new_n" 'BEGIN { printf "%.4f\n", b / a }')
        echo "   base $base_n, new $new_n, ratio $ratio" >&2
        if awk -v r="$ratio" -v lo="$low" -v hi="$high" 'BEGIN { exit !(r < lo || r > hi) }'; then
            failed=1
            ratio="$ratio (outside $low..$high)"
        fi
    fi
    base_s=() new_s=()
    for i in $(seq "$runs"); do
        for who in base new; do
            solver=$base_solver
            [ "$who" = new ] && solver=$new_solver
            s=$(wall "$solver" "$config" "$preset")
            l=$(load)
            printf '%s\t%s\t%s\twall_s\t%s\t%s\n' "$scene" "$preset" "$who" "$s" "$l" >>"$runs_log"
            echo "   $scene $preset $who wall run $i: $s s (load $l)" >&2
            if [ "$who" = base ]; then base_s+=("$s"); else new_s+=("$s"); fi
        done
    done
    rows+=("| $scene | $preset | $base_n | $new_n | $ratio | $(median "${base_s[@]}") | $(median "${new_s[@]}") | $load0 → $(load) |")
done

echo
echo "Base $(git rev-parse --short "$base_hash"), new $new_label; instructions: $count_label;" \
    "wall: median of $runs interleaved solves, every core ($(nproc) here)"
echo
echo "| scene | preset | base instructions | new instructions | ratio | base median wall s | new median wall s | load (1 min) start → end |"
echo "| --- | --- | ---: | ---: | ---: | ---: | ---: | --- |"
printf '%s\n' "${rows[@]}"
echo
echo "Every run: $runs_log"
if [ "$failed" = 1 ]; then
    echo "same-speed: an instruction ratio is outside $low..$high" >&2
    exit 1
fi
