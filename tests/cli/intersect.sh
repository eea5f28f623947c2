# meshcsg intersect: counts, closed curves, OBJ output with shared vertices.
. "$(dirname "$0")/common.bash"

cat > "$WORK/boxes.scad" <<'SCAD'
difference() {
  cube(1);
  translate([0.5, 0.5, 0.5]) cube(1);
}
SCAD
run 0 intersect "$WORK/boxes.scad" -o "$WORK/curves.obj"
contains "faces 24"
contains "points of odd degree 0"
contains "time: octree"
if grep -q '^v ' "$WORK/curves.obj" && grep -q '^l ' "$WORK/curves.obj"; then passed=$((passed + 1))
else echo "FAIL: curves.obj lacks v/l records"; failed=$((failed + 1)); fi

# Coplanar contacts everywhere: a bar on a plate, sharing a side plane with a hole.
cat > "$WORK/coplanar.scad" <<'SCAD'
union() {
  difference() { cube([2, 2, 1]); translate([0.25, 0.25, -1]) cube([0.5, 0.5, 3]); }
  translate([0, 0, 1]) cube([0.25, 2, 0.5]);
}
SCAD
run 0 intersect "$WORK/coplanar.scad"
contains "points of odd degree 0"
lacks "coplanar overlapping pairs 0"

cp "$MODELS/spot.obj" "$WORK/cow.obj"
printf 'union() { import("cow.obj"); translate([0.05, 0.03, 0.02]) rotate([0, 0, 3]) import("cow.obj"); }\n' > "$WORK/cows.scad"
run 0 intersect "$WORK/cows.scad"
contains "points of odd degree 0"
run 2 intersect
run 1 intersect "$WORK/missing.scad"
finish
