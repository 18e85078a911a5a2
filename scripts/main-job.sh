#!/usr/bin/env bash
# The main job (README, "Two commands"): install the missing system packages, build
# in release, solve the bundled Cornell box with the medium preset, then show it —
# in the desktop stereo mirror window when there is a display and the runtime has
# one, else as an offscreen stereo screenshot pair whose paths are printed.
#
# It fails, with a message saying which step, whenever a step cannot be done; it
# never reports success for something it did not show.
set -euo pipefail
cd "$(dirname "$0")/.."

bash scripts/install-deps.sh run

echo "main-job: building the solver (release)"
cargo build --release --locked -p solver --bin solver

scene=config/cornell_box.toml
sol=out/cornell_box.sol
mkdir -p out
# Medium with 512 rays per grouped shot (the preset's 64 suit 100k-box scenes):
# 1.68% / 1.64% MARE against the path-traced truth, two seeds' images 0.47%
# apart (no visible noise), 4.4 s on two cores (docs/lab/grouped-shooters.md, "Grouped
# shooters by default").
solve_args=(solve "$scene" -o "$sol" --preset medium --group-samples 512)
if [ -e "$sol.checkpoint" ]; then
  # An earlier main job was interrupted: continue it instead of starting over.
  echo "main-job: found $sol.checkpoint from an interrupted solve; resuming it"
  solve_args+=(--resume)
fi
echo "main-job: solving $scene (preset medium, 512 group rays)"
./target/release/solver "${solve_args[@]}"
echo "main-job: solution written to $sol"

echo "main-job: building the runtime (release)"
if ! cargo build --release --locked -p runtime --bin runtime; then
  echo "main-job: cannot show $sol: the runtime does not build (see the errors above)" >&2
  exit 1
fi
runtime=./target/release/runtime
if ! help=$("$runtime" --help 2>&1); then
  echo "main-job: cannot show $sol: \`runtime --help\` failed, the runtime is not ready:" >&2
  echo "$help" >&2
  exit 1
fi
has_command() { grep -qE "^[[:space:]]+$1([[:space:]]|$)" <<<"$help"; }

if [ -n "${DISPLAY:-}${WAYLAND_DISPLAY:-}" ] && has_command mirror; then
  echo "main-job: showing $sol in the stereo mirror window (F1 lists the keys; close it to finish)"
  status=0
  "$runtime" mirror "$sol" || status=$?
  # Exit status 3 means the display could not be used: fall back to screenshots.
  if [ "$status" -ne 3 ]; then
    exit "$status"
  fi
  echo "main-job: the display ${DISPLAY:-$WAYLAND_DISPLAY} cannot be used; falling back to a screenshot"
fi

if ! has_command screenshot; then
  echo "main-job: cannot show $sol: the runtime has neither a usable \`mirror\` (display:" \
       "${DISPLAY:-none}) nor a \`screenshot\` command" >&2
  exit 1
fi
echo "main-job: no display (or no mirror command): writing an offscreen stereo screenshot"
"$runtime" screenshot "$sol" --out out/cornell_box
status=0
for eye in left right; do
  png="out/cornell_box-$eye.png"
  if [ -s "$png" ]; then
    echo "main-job: $eye eye: $png"
  else
    echo "main-job: the runtime did not write $png" >&2
    status=1
  fi
done
exit "$status"
