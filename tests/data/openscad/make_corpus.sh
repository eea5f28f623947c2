#!/usr/bin/env bash
# Regenerates this folder from OpenSCAD 2021.01's examples (Debian: apt-get install
# openscad; /usr/share/openscad/examples, dedicated to the public domain under CC0): every
# 3D example whose .csg export uses only what meshcsg reads, exported with
# `openscad -o NAME.csg` (six significant digits), the files they import or read as
# surfaces (STL, DXF, .dat, PNG), and
# volumes.tsv: the volume of OpenSCAD's own render (`openscad -o NAME.stl`, float
# coordinates) and the seconds it took, as measured by `meshcsg check` on that STL.
# usage: make_corpus.sh MESHCSG   (run in this folder)
set -euo pipefail
meshcsg=${1:?usage: make_corpus.sh MESHCSG}
examples=/usr/share/openscad/examples
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
printf 'example\topenscad_volume\topenscad_seconds\n' > volumes.tsv
for scad in $(find "$examples" -name '*.scad' | sort); do
  name=$(basename "$(dirname "$scad")")_$(basename "$scad" .scad)
  (cd "$(dirname "$scad")" && openscad -o "$tmp/$name.csg" "$scad" >/dev/null 2>&1) || continue
  stls=$(grep -oE '(import|surface)\(file = "[^"]*"' "$tmp/$name.csg" | sed 's/.*"\(.*\)"/\1/' | sort -u || true)
  for stl in $stls; do cp "$(dirname "$scad")/$stl" "$tmp/$stl"; done
  # only what meshcsg reads, and only examples with a solid result
  (cd "$tmp" && "$meshcsg" tree "$name.csg" >/dev/null 2>&1) || continue
  start=$(date +%s.%N)
  (cd "$(dirname "$scad")" && openscad -o "$tmp/$name.stl" "$scad" >/dev/null 2>&1) || continue
  seconds=$(echo "$(date +%s.%N) - $start" | bc)
  volume=$("$meshcsg" check "$tmp/$name.stl" | sed -n 's/.* volume \(.*\)$/\1/p' || true)
  [ -n "$volume" ] || continue
  cp "$tmp/$name.csg" .
  for stl in $stls; do cp "$tmp/$stl" .; done
  printf '%s\t%s\t%.2f\n' "$name" "$volume" "$seconds" >> volumes.tsv
done
