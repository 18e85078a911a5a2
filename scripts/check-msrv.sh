#!/usr/bin/env bash
# Fails if any package in the lock graph declares a `rust-version` above the
# workspace's (`[workspace.package] rust-version` in the root Cargo.toml), so that
# the declared MSRV stays true when a dependency is updated. Clippy's
# `incompatible_msrv` lint covers the other half: std APIs newer than the MSRV in
# our own code.
set -euo pipefail
cd "$(dirname "$0")/.."

metadata=$(cargo metadata --format-version 1 --locked)
ours=$(jq -r '.packages[] | select(.name == "walkthrough") | .rust_version' <<<"$metadata")
if [ -z "$ours" ] || [ "$ours" = "null" ]; then
  echo "check-msrv: the root package declares no rust-version" >&2
  exit 1
fi

# "1.88" and "1.88.0" are the same version.
normalize() { local v=$1; while [ "$(tr -cd . <<<"$v" | wc -c)" -lt 2 ]; do v="$v.0"; done; echo "$v"; }
ours=$(normalize "$ours")

# Every package the lock resolves (for all targets), with its declared MSRV.
too_new=()
while read -r name version rust_version; do
  [ "$rust_version" = "null" ] && continue
  rust_version=$(normalize "$rust_version")
  highest=$(printf '%s\n%s\n' "$ours" "$rust_version" | sort -V | tail -n1)
  if [ "$highest" != "$ours" ]; then
    too_new+=("$name $version needs Rust $rust_version")
  fi
done < <(jq -r '.packages[] | "\(.name) \(.version) \(.rust_version)"' <<<"$metadata")

if [ ${#too_new[@]} -gt 0 ]; then
  echo "check-msrv: dependencies declare a rust-version above the workspace's $ours:" >&2
  printf '  %s\n' "${too_new[@]}" >&2
  echo "raise [workspace.package] rust-version or pin older versions" >&2
  exit 1
fi
echo "check-msrv: $(jq '.packages | length' <<<"$metadata") packages, none needs more than Rust $ours"
