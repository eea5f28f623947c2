# Optional: the benchmark scenes of ../shared/scenes (next to a checkout; not part of the
# project) evaluated by meshcsg eval: every result must be valid (closed, oriented,
# edge-manifold) and match reference.tsv's exact volume (to 1e-10 relative: only the
# final rounding differs) and shell count. Skipped (exit 77) without the shared folder or
# python3. Sanitizer builds run the lighter scenes only (MCSG_FULL_SCENES is set for the
# others). The suite's own scenes are in scenes.sh.
. "$(dirname "$0")/common.bash"
SCENES_DIR=${MCSG_SHARED_DIR:-}/scenes
[ -n "${MCSG_SHARED_DIR:-}" ] && [ -f "$SCENES_DIR/make_scenes.py" ] && [ -d "$MCSG_SHARED_DIR/models" ] ||
  skip "no shared scenes folder (MCSG_SHARED_DIR=${MCSG_SHARED_DIR:-unset})"
command -v python3 >/dev/null || skip "python3 is needed to generate the shared scenes"

light="ring_spheres_100,box_grid_8,cylinder_28_holes,armadillo_minus_bunny,cow100K_minus_shifted,bunny_and_bunny_same"
all="$light,ring_spheres_200,ring_spheres_400,ring_spheres_800,armadillo_union_6bunnies,bunny100k_minus_shifted"
list=$light
[ "${MCSG_FULL_SCENES:-0}" = 1 ] && list=$all

python3 "$SCENES_DIR/make_scenes.py" "$WORK/scenes" --models "$MCSG_SHARED_DIR/models" \
  --only "$list" >/dev/null || { echo "FAIL: make_scenes.py"; exit 1; }

IFS=, read -ra names <<< "$list"
for name in "${names[@]}"; do
  ref=$(awk -v n="$name" '$1 == n { print $3, $4 }' "$SCENES_DIR/reference.tsv")
  [ -n "$ref" ] || { echo "FAIL: $name missing from reference.tsv"; failed=$((failed + 1)); continue; }
  read -r volume shells <<< "$ref"
  run 0 eval "$WORK/scenes/$name/tree.scad" -o "$WORK/$name.off" || continue
  run 0 check "$WORK/$name.off" || continue
  got=$(printf '%s' "$OUT" | sed -n 's/.* \([0-9]*\) components\{0,1\}, volume \(.*\)$/\1 \2/p')
  read -r got_shells got_volume <<< "$got"
  if awk -v a="$got_volume" -v b="$volume" 'BEGIN { d = a - b; if (d < 0) d = -d; exit !(d <= 1e-10 * b) }' &&
     [ "$got_shells" = "$shells" ]; then
    passed=$((passed + 1)); echo "ok   $name: volume $got_volume, $got_shells shells"
  else
    echo "FAIL: $name: volume $got_volume shells $got_shells, expected $volume and $shells"
    failed=$((failed + 1))
  fi
  rm -f "$WORK/$name.off"
done
finish
