# Sourced by scripts/same-results.sh and scripts/same-speed.sh: builds the
# solver of a base commit beside this tree's, to compare the two.

# build_base_solver BASE WORK TARGET: extracts commit BASE into WORK/base-src,
# builds its solver in the release profile in the target folder TARGET, and
# copies the binary to WORK/base-solver (TARGET may be this tree's: both
# solvers are named solver, and this tree's build would replace it there).
# Fails with a message when BASE is not in this clone.
build_base_solver() {
    local base=$1 work=$2 target=$3
    local src="$work/base-src" commit
    if ! commit=$(git rev-parse --verify --quiet "$base^{commit}"); then
        echo "$(basename "$0"): commit $base is not in this clone (a shallow clone?); fetch the history first" >&2
        return 1
    fi
    # git archive stamps every file with the commit's time, older than any
    # build: when the base changes its files are touched, or cargo would take
    # the last base's artifacts in a kept target folder as fresh.
    if [ "$(cat "$work/base-commit" 2>/dev/null)" != "$commit" ]; then
        rm -rf "$src"
        mkdir -p "$src"
        git archive "$commit" | tar -x -C "$src"
        find "$src" -type f -exec touch {} +
        echo "$commit" >"$work/base-commit"
    fi
    echo "== $(basename "$0" .sh): building the base solver ($base), release"
    # Both trees' workspace crates hash to the same artifacts in one target
    # folder, and cargo finds them fresh when the sources their fingerprints
    # name (the other tree's) have not changed: it would hand this tree's
    # solver over as the base's, and the base's back as this tree's. So the
    # workspace crates' artifacts are forgotten before and after the base's
    # build (the third-party crates stay shared).
    (cd "$src" && CARGO_TARGET_DIR="$target" cargo clean --release -p solver -p solution)
    (cd "$src" && CARGO_TARGET_DIR="$target" cargo build --release --locked -p solver)
    cp "$target/release/solver" "$work/base-solver"
    (cd "$src" && CARGO_TARGET_DIR="$target" cargo clean --release -p solver -p solution)
}
