#!/usr/bin/env bash
# meshcsg against OpenSCAD 2021.01 on OpenSCAD's own test files (Debian
# openscad-testing-data, /usr/share/openscad/testdata/scad): every file whose STL render
# succeeds is a 3D case; its .csg export is evaluated by meshcsg and the volumes compared
# (relative difference at most 1e-4 counts as a match). Needs openscad and
# openscad-testing-data; renders one file at a time (about 8 minutes for all of them).
# Works on a copy of the test data's folder (WORK/testdata), where each export is written
# next to its source, so that the files it imports resolve as they do for OpenSCAD.
# Writes WORK/results.tsv (name, status, OpenSCAD seconds, meshcsg seconds, OpenSCAD
# volume, meshcsg volume, message) and prints the counts per status.
# usage: bench/openscad_testdata.sh MESHCSG WORK   (OPENSCAD_TESTDATA: another folder)
set -uo pipefail
meshcsg=$(realpath "${1:?usage: openscad_testdata.sh MESHCSG WORK}")
work=$(mkdir -p "${2:?usage: openscad_testdata.sh MESHCSG WORK}" && realpath "$2")
src=${OPENSCAD_TESTDATA:-/usr/share/openscad/testdata/scad}
results=$work/results.tsv
printf 'name\tstatus\topenscad_s\tmeshcsg_s\topenscad_volume\tmeshcsg_volume\tmessage\n' > "$results"
volume_of() { "$meshcsg" check "$1" 2>/dev/null | sed -n 's/.*: ok: .* volume \(.*\)$/\1/p'; }
now() { date +%s.%N; }
[ -d "$src" ] || { echo "no $src: apt-get install openscad-testing-data" >&2; exit 1; }
rm -rf "$work/testdata"
cp -r "$(dirname "$(realpath "$src")")" "$work/testdata"
cd "$work/testdata/$(basename "$src")" || exit 1
find . -name '*.scad' | sort | while read -r rel; do
  name=${rel#./}
  dir=$(dirname "$rel")
  out=$work/$(echo "${name%.scad}" | tr '/' '_')
  start=$(now)
  (cd "$dir" && timeout 300 openscad -o "$out.stl" "$(basename "$rel")" >/dev/null 2>&1) || continue
  oseconds=$(echo "$(now) - $start" | bc)
  ovolume=$(volume_of "$out.stl")
  [ -n "$ovolume" ] || continue # empty or not a closed mesh: not a 3D case
  csg=$(basename "${rel%.scad}").export.csg
  (cd "$dir" && timeout 300 openscad -o "$csg" "$(basename "$rel")" >/dev/null 2>&1)
  start=$(now)
  message=$(cd "$dir" && timeout 300 "$meshcsg" eval -q "$csg" -o "$out.off" 2>&1 | head -1)
  mseconds=$(echo "$(now) - $start" | bc)
  mvolume=$(volume_of "$out.off")
  status=$(python3 -c "import sys; a, b = sys.argv[1], sys.argv[2]
print('error' if not b else 'match' if abs(float(a) - float(b)) <= 1e-4 * abs(float(a)) else 'volume')" \
    "$ovolume" "$mvolume")
  printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$name" "$status" "$oseconds" "$mseconds" "$ovolume" \
    "$mvolume" "${message:0:200}" >> "$results"
done
tail -n +2 "$results" | cut -f2 | sort | uniq -c
