# Whole scenes through meshcsg eval, each result checked by meshcsg check (closed,
# oriented, edge-manifold) and against a volume known without meshcsg:
#  - a plate minus an 8 x 8 grid of square holes, plus 8 bars on top (coplanar contacts
#    everywhere): exactly 56;
#  - a plate drilled by an 8 x 8 grid of 24-sided holes: the plate minus the polygons;
#  - a cylinder minus 28 tilted cylinders, and Spot minus a moved and turned copy of
#    itself: |A - B| + |A n B| = |A| to 1e-10 relative;
#  - the built-in ring with 400 spheres against its exact reference volume (not under the
#    sanitizers: MCSG_FULL_SCENES).
. "$(dirname "$0")/common.bash"

# volume_of FILE : sets VOLUME and SHELLS from meshcsg check, or fails the script's check.
volume_of() {
  run 0 check "$1" || return 1
  VOLUME=$(printf '%s' "$OUT" | sed -n 's/.* volume \(.*\)$/\1/p')
  SHELLS=$(printf '%s' "$OUT" | sed -n 's/.* \([0-9]*\) components\{0,1\}, volume .*/\1/p')
}

# expect_volume NAME GOT EXPECTED SHELLS EXPECTED_SHELLS
expect_volume() {
  if awk -v a="$2" -v b="$3" 'BEGIN { d = a - b; if (d < 0) d = -d; exit !(d <= 1e-10 * b) }' &&
     [ "$4" = "$5" ]; then
    passed=$((passed + 1)); echo "ok   $1: volume $2, $4 shells"
  else
    echo "FAIL: $1: volume $2 with $4 shells, expected $3 and $5"; failed=$((failed + 1))
  fi
}

# eval_volume NAME : evaluates $WORK/NAME.scad into NAME.off and measures it.
eval_volume() {
  run 0 eval "$WORK/$1.scad" -o "$WORK/$1.off" && volume_of "$WORK/$1.off"
}

write_box_grid "$WORK/box_grid.scad"
eval_volume box_grid && expect_volume box_grid "$VOLUME" 56 "$SHELLS" 1

write_drill_plate "$WORK/drill_plate.scad"
hole=$(awk 'BEGIN { printf "%.17g", 0.5 * 24 * 0.09 * sin(3.141592653589793 / 12) }')
eval_volume drill_plate &&
  expect_volume drill_plate "$VOLUME" "$(awk -v h="$hole" 'BEGIN { printf "%.17g", 64 * (1 - h) }')" "$SHELLS" 1

# identity NAME A_TEXT B_TEXT : |A - B| + |A n B| = |A|.
identity() {
  local a b d i
  printf '%s\n' "$2" > "$WORK/$1_a.scad"
  printf 'difference() {\n%s\n%s\n}\n' "$2" "$3" > "$WORK/$1_d.scad"
  printf 'intersection() {\n%s\n%s\n}\n' "$2" "$3" > "$WORK/$1_i.scad"
  eval_volume "$1_a" || return; a=$VOLUME
  eval_volume "$1_d" || return; d=$VOLUME
  eval_volume "$1_i" || return; i=$VOLUME
  expect_volume "$1 (difference + intersection)" \
    "$(awk -v d="$d" -v i="$i" 'BEGIN { printf "%.17g", d + i }')" "$a" 1 1
}

identity cylinder_holes 'cylinder(h = 20, r = 10, center = true, $fn = 200);' "$(cylinder_holes_union)"

cp "$MODELS/spot.obj" "$WORK/spot.obj"
identity spot_minus_moved 'import("spot.obj");' \
  'translate([0.07, 0.04, 0.03]) rotate([0, 0, 3]) import("spot.obj");'

if [ "${MCSG_FULL_SCENES:-0}" = 1 ]; then
  run 0 demo -n 400 -o "$WORK/ring.off"
  contains "3 shells"
  contains "matches"
fi
finish
