#!/usr/bin/env bash
# make bench: the end-to-end scene benchmark (bench/eval_bench.py, which rewrites the
# generated table in docs/benchmarks.md), then every micro-benchmark binary of the build
# (each prints its own medians). BENCH_RUNS=N changes the number of runs per scene
# (default 5), BENCH_ONLY=a,b limits the scenes, BENCH_MICRO=0 skips the micro-benchmarks.
set -euo pipefail
build=${1:?usage: bench/run.sh BUILD_DIR}
root=$(cd "$(dirname "$0")/.." && pwd)
export MCSG_SHARED_DIR=${MCSG_SHARED_DIR:-$(cd "$root/.." && pwd)/shared}
command -v python3 >/dev/null || { echo "make bench needs python3 (apt-get install python3)"; exit 1; }
only=()
[ -n "${BENCH_ONLY:-}" ] && only=(--only "$BENCH_ONLY")
python3 "$root/bench/eval_bench.py" "$build/meshcsg" "$MCSG_SHARED_DIR" "$build/bench-scenes" \
  "$root/docs/benchmarks.md" --runs "${BENCH_RUNS:-5}" "${only[@]}"
echo "docs/benchmarks.md updated"
[ "${BENCH_MICRO:-1}" = 0 ] && exit 0
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
for bin in "$build"/bench/bench_*; do
  [ -x "$bin" ] || continue
  echo "== $(basename "$bin")"
  "$bin" "$tmp"
done
