#!/usr/bin/env bash
# make bench: the end-to-end scene benchmark (bench/eval_bench.py, which rewrites the
# generated table in docs/benchmarks.md), then every micro-benchmark binary of the build
# (each prints its own medians). BENCH_RUNS=N changes the number of runs per scene
# (default 5), BENCH_ONLY=a,b limits the scenes, BENCH_MICRO=0 skips the micro-benchmarks.
# When CGAL is installed the peer comparison runs too (bench/cgal_bench.py; BENCH_CGAL=0
# skips it, BENCH_CGAL_RUNS=N sets its runs, default 3).
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
# The peer comparison (optional): built by make bench when CGAL is installed.
if [ "${BENCH_CGAL:-1}" = 0 ]; then
  :
elif [ -x "$build/cgal_csg" ]; then
  python3 "$root/bench/cgal_bench.py" "$build/meshcsg" "$build/cgal_csg" "$MCSG_SHARED_DIR" \
    "$build/bench-scenes" "$root/docs/benchmarks.md" --runs "${BENCH_CGAL_RUNS:-3}" "${only[@]}"
  echo "docs/benchmarks.md: CGAL comparison updated"
else
  echo "no CGAL comparison: install libcgal-dev (apt-get install libcgal-dev) and rerun make bench"
fi
[ "${BENCH_MICRO:-1}" = 0 ] && exit 0
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
for bin in "$build"/bench/bench_*; do
  [ -x "$bin" ] || continue
  echo "== $(basename "$bin")"
  "$bin" "$tmp"
done
