#!/usr/bin/env bash
# Checks the dependency invariants that ARCHITECTURE.md states, on the real
# dependency graph (normal and build dependencies; dev-dependencies do not ship).
set -euo pipefail
cd "$(dirname "$0")/.."

fail=0
# deps_of PACKAGE: the names of every crate PACKAGE links, one per line.
deps_of() {
  cargo tree --locked -p "$1" -e normal,build --prefix none --format '{p}' |
    awk '{print $1}' | sort -u
}
# refuse PACKAGE FORBIDDEN...: fails when PACKAGE's graph contains one of them.
refuse() {
  local package=$1; shift
  local graph; graph=$(deps_of "$package")
  for forbidden in "$@"; do
    if grep -qx "$forbidden" <<<"$graph"; then
      echo "check-architecture: FAILED: $package depends on $forbidden" >&2
      cargo tree --locked -p "$package" -e normal,build -i "$forbidden" >&2 || true
      fail=1
    fi
  done
}

refuse runtime solver
refuse solution solver runtime clap ash openxr winit
refuse solver runtime ash openxr winit

# "Every file is written atomically", "the solver core is pure" and "no function
# over 150 lines" are checked by `cargo clippy` (scripts/test.sh): clippy.toml and
# solver/clippy.toml list the calls and the threshold, and every library and program
# turns the three lints on at its root (Cargo.toml's
# [workspace.lints] leaves them off for tests). A root that forgot would go unchecked.
opt_in='#![cfg_attr(not(test), warn(clippy::disallowed_methods, clippy::disallowed_macros))]'
length_in='#![cfg_attr(not(test), warn(clippy::too_many_lines))]'
roots=$(cargo metadata --locked --no-deps --format-version 1 |
  jq -r '.packages[].targets[] | select(any(.kind[]; . == "lib" or . == "bin")) | .src_path')
while read -r root; do
  for line in "$opt_in" "$length_in"; do
    if ! grep -qxF "$line" "$root"; then
      echo "check-architecture: FAILED: ${root#"$PWD"/} lacks the line $line" >&2
      fail=1
    fi
  done
done <<<"$roots"
# Clippy reads only the nearest clippy.toml, so the solver's repeats the workspace's.
missing=$(grep -vE '^[[:space:]]*(#|$)' clippy.toml | grep -vxF -f solver/clippy.toml || true)
if [ -n "$missing" ]; then
  echo "check-architecture: FAILED: solver/clippy.toml lacks these lines of clippy.toml:" >&2
  echo "$missing" >&2
  fail=1
fi
# Clap stays out of the solver core: Clippy cannot scope a disallowed derive, so grep.
core=(mesh solve geometry brdf texture reference export view light)
if grep -rnw clap "${core[@]/#/solver/src/}" >&2; then
  echo "check-architecture: FAILED: clap in the solver core (above)" >&2
  fail=1
fi
# No source file over 1,000 code lines (ARCHITECTURE.md; functions are clippy's
# too_many_lines): the lines of non-test files under a crate's src/ that are neither
# blank nor comments, #[cfg(test)] items left out.
big=$(find . \( -name target -o -name .git \) -prune -o -path '*/src/*.rs' ! -name '*test*' -print |
  sort | xargs awk '
    function report() { if (file != "" && n > 1000) printf "%s: %d code lines\n", file, n }
    FNR == 1 { report(); file = FILENAME; n = 0; skip = 0 }
    skip {
      line = $0; o = gsub(/[{]/, "", line); c = gsub(/[}]/, "", line)
      depth += o - c; if (o) opened = 1
      if ((opened && depth <= 0) || (!opened && $0 ~ /;[[:space:]]*$/)) skip = 0
      next
    }
    /^[[:space:]]*#\[cfg\(test\)\]/ { skip = 1; depth = 0; opened = 0; next }
    /^[[:space:]]*$/ || /^[[:space:]]*\/\// { next }
    { n++ }
    END { report() }')
if [ -n "$big" ]; then
  echo "check-architecture: FAILED: files over 1,000 code lines (split them by job):" >&2
  echo "$big" >&2
  fail=1
fi
[ "$fail" -eq 0 ] || exit 1
echo "check-architecture: runtime links no solver; solution links no solver, runtime, clap, ash, openxr, winit; solver links no ash, openxr, winit; no clap in the solver core; every library and program has Clippy's purity, atomic-write and function-length lints on (cargo clippy checks them); no source file over 1,000 code lines"

# The runtime must build on its own: in a workspace build Cargo unifies features
# and dependencies across members, which could hide a missing one.
echo "== cargo build -p runtime (alone)"
cargo build --locked -p runtime
