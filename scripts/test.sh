#!/usr/bin/env bash
# The whole test suite, as CI runs it: install what is missing, then format
# check, clippy with warnings as errors, and every test of the workspace.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh test

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
