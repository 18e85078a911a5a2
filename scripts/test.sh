#!/usr/bin/env bash
# The whole test suite, as CI runs it: install what is missing, then format
# check, clippy with warnings as errors, and every test of the workspace.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh test

# A clean build of every test target needs about 3 GB of disk (measured with
# CARGO_INCREMENTAL=0, which a one-shot CI build gains nothing from). Say so
# plainly rather than fail midway with "No space left on device" from rustc.
export CARGO_INCREMENTAL="${CARGO_INCREMENTAL:-0}"
need_gb=5
target_dir="${CARGO_TARGET_DIR:-target}"
mkdir -p "$target_dir"
free_gb=$(df -Pk "$target_dir" | awk 'NR == 2 { print int($4 / 1048576) }')
if [ "$free_gb" -lt "$need_gb" ]; then
    echo "test.sh: only ${free_gb} GB free under $target_dir; a clean build needs about ${need_gb} GB" >&2
    exit 1
fi

# lavapipe is the Vulkan device of the GPU tests unless the caller picks another.
export VK_ICD_FILENAMES="${VK_ICD_FILENAMES:-$(ls /usr/share/vulkan/icd.d/lvp_icd*.json 2>/dev/null | head -n1)}"

echo "== cargo fmt --check"
cargo fmt --all -- --check
echo "== architecture invariants"
bash scripts/check-architecture.sh
echo "== minimum supported Rust version of the dependencies"
bash scripts/check-msrv.sh
echo "== cargo clippy"
cargo clippy --workspace --all-targets --locked -- -D warnings
echo "== cargo test"
cargo test --workspace --locked
echo "== same results as before issue 40's refactor"
bash scripts/same-results.sh
