#!/usr/bin/env bash
# Run every benchmark binary of a Release build. Each prints its own medians.
set -euo pipefail
build=${1:?usage: bench/run.sh BUILD_DIR}
export MCSG_SHARED_DIR=${MCSG_SHARED_DIR:-$(cd "$(dirname "$0")/../.." && pwd)/shared}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
for bin in "$build"/bench/bench_*; do
  [ -x "$bin" ] || continue
  echo "== $(basename "$bin")"
  "$bin" "$tmp"
done
