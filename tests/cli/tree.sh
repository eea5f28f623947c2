# meshcsg tree: prints operations and leaves; deep files work; errors give line:col.
. "$(dirname "$0")/common.bash"

cp "$MODELS/cube.obj" "$WORK/part.obj"
cat > "$WORK/model.scad" <<'SCAD'
// a plate with a hole and an imported part
difference() {
  cube([10, 10, 2]);
  translate([5, 5, -1]) cylinder(h = 4, r = 2, $fn = 16);
  import("part.obj");
}
SCAD
run 0 tree "$WORK/model.scad"
contains "difference (3 children)"
contains "12 triangles"
contains "60 triangles"
contains "3 leaves"

# 10,000 nested unions.
{ yes 'union() {' | head -n 10000; echo 'cube(1);'; yes '}' | head -n 10000; } > "$WORK/deep.scad"
run 0 tree "$WORK/deep.scad"
contains "depth 10000"

printf 'union() {\n  cube(1);\n  for (i = [0:3]) cube(i);\n}\n' > "$WORK/bad.scad"
run 1 tree "$WORK/bad.scad"
contains "bad.scad:3:3"

run 0 check "$WORK/model.scad"
finish
