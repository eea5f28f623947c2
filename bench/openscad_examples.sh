#!/usr/bin/env bash
# meshcsg against OpenSCAD 2021.01 on OpenSCAD's 42 3D examples (tests/data/openscad):
# each .csg export evaluated by `meshcsg eval` (wall seconds, the median of RUNS runs),
# its volume against OpenSCAD's render, and OpenSCAD's own render time as volumes.tsv
# records it (`openscad -o NAME.stl NAME.scad`, measured by make_corpus.sh). Prints a
# Markdown table.
# usage: bench/openscad_examples.sh MESHCSG [RUNS]
set -euo pipefail
meshcsg=$(realpath "${1:?usage: openscad_examples.sh MESHCSG [RUNS]}")
runs=${2:-3}
dir=$(cd "$(dirname "$0")/../tests/data/openscad" && pwd)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
echo "| example | OpenSCAD s | meshcsg s | ratio | volume rel. diff | triangles |"
echo "|---|---|---|---|---|---|"
tail -n +2 "$dir/volumes.tsv" | while IFS=$'\t' read -r name volume oseconds; do
  times=()
  for ((r = 0; r < runs; r++)); do
    start=$(date +%s.%N)
    (cd "$dir" && "$meshcsg" eval -q "$name.csg" -o "$tmp/out.off")
    times+=("$(echo "$(date +%s.%N) - $start" | bc)")
  done
  median=$(printf '%s\n' "${times[@]}" | sort -g | sed -n "$(((runs + 1) / 2))p")
  report=$("$meshcsg" check "$tmp/out.off")
  got=$(sed -n 's/.* volume \(.*\)$/\1/p' <<<"$report")
  tris=$(sed -n 's/.* \([0-9]*\) triangles.*/\1/p' <<<"$report")
  python3 - "$name" "$oseconds" "$median" "$volume" "$got" "$tris" <<'PY'
import sys
name, os_s, mc_s, ref, got, tris = sys.argv[1:]
os_s, mc_s, ref, got = float(os_s), float(mc_s), float(ref), float(got)
print(f"| {name} | {os_s:.2f} | {mc_s:.3f} | {os_s / mc_s:.1f}x | {abs(got - ref) / abs(ref):.1e} | {tris} |")
PY
done
