# Bad input to `meshcsg eval`: each case gives one clear line naming the file (and where),
# exit status 1, and no output file.
. "$(dirname "$0")/common.bash"

# eval_fails SCAD_TEXT EXPECTED... : writes $WORK/case.scad, evaluates it, checks the
# message pieces and that no output was written.
eval_fails() {
  local text=$1; shift
  printf '%s\n' "$text" > "$WORK/case.scad"
  rm -f "$WORK/out.off"
  run 1 eval "$WORK/case.scad" -o "$WORK/out.off" || return
  for piece in "$@"; do contains "$piece"; done
  if [ -e "$WORK/out.off" ]; then echo "FAIL: an output file was written"; failed=$((failed + 1)); fi
  [ "$(printf '%s\n' "$OUT" | wc -l)" -eq 1 ] || { echo "FAIL: more than one line: $OUT"; failed=$((failed + 1)); }
}

cube_off 1 > "$WORK/open.off"
eval_fails 'union() { cube(2); import("open.off"); }' \
  'leaf 1, import("open.off") at ' 'case.scad:1:20: the surface is open: 3 boundary edges, e.g. from ('

{ cube_off; echo "3 0 2 1"; } | sed 's/^8 12 0$/8 13 0/' > "$WORK/nonmanifold.off"
eval_fails 'difference() { cube(2); import("nonmanifold.off"); }' \
  'import("nonmanifold.off")' 'the surface does not close up: 3 edges of more than two triangles are used more often one way than the other, e.g. from ('

{ cube_off 1; echo "3 3 7 4"; } | sed "s/^8 11 0$/8 12 0/" > "$WORK/oneflip.off"
eval_fails 'union() { import("oneflip.off"); sphere(1); }' \
  'import("oneflip.off")' 'not consistently oriented: 3 edges'

# Inside out is not bad input: the leaf's winding number is -1 inside, its solid empty.
cube_off 0 1 > "$WORK/inverted.off"
printf 'union() { import("inverted.off"); }\n' > "$WORK/case.scad"
run 0 eval "$WORK/case.scad" -o "$WORK/out.off" && contains '0 vertices, 0 triangles'

# Nor is a shell folded flat (volume 0): its winding number is 0 everywhere, its solid
# empty.
printf 'OFF\n4 4 0\n0 0 0\n4 0 0\n0 4 0\n1 1 0\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n' > "$WORK/flat.off"
printf 'intersection() { cube(3); import("flat.off"); }\n' > "$WORK/case.scad"
run 0 eval "$WORK/case.scad" -o "$WORK/out.off" && contains '0 vertices, 0 triangles'

printf 'OFF\n3 1 0\n0 0 0\nnan 0 0\n0 1 0\n3 0 1 2\n' > "$WORK/nan.off"
eval_fails 'union() { cube(1); import("nan.off"); }' 'case.scad:1:20: import("nan.off"): vertex 1 is not finite'
eval_fails 'union() { cube(1); scale(1e300) scale(1e300) cube(1); }' \
  'case.scad:1:46: cube(size=[1, 1, 1], center=false): vertex' 'is not finite after the transforms'
eval_fails 'union() { cube(1); translate([0/0, 0, 0]) cube(1); }' 'case.scad:1:30: translate(): `v` must be finite'

: > "$WORK/zero.off"
eval_fails 'union() { cube(1); import("zero.off"); }' 'import("zero.off"): ' 'zero.off:1: empty file'
printf 'OFF\n8 12 0\n0 0 0\n1 0 0\n' > "$WORK/truncated.off"
eval_fails 'union() { cube(1); import("truncated.off"); }' 'truncated.off:4: unexpected end of file'
eval_fails 'union() { cube(1); import("missing.stl"); }' 'import("missing.stl")' 'missing.stl: cannot open'
printf 'solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0\n' > "$WORK/broken.stl"
eval_fails 'union() { cube(1); import("broken.stl"); }' 'broken.stl:5:'

eval_fails 'union() { cube(1); roof() square(1); }' \
  'case.scad:1:20: `roof` is not supported by meshcsg'
eval_fails 'union() { cube(1) }' 'case.scad:1:19: expected a statement'

# An empty mesh is the empty set (a warning, not an error).
printf 'OFF\n0 0 0\n' > "$WORK/empty.off"
printf 'union() { cube(1); import("empty.off"); }\n' > "$WORK/case.scad"
run 0 eval "$WORK/case.scad" -o "$WORK/out.off"
contains 'warning: '
contains 'import() is empty'
contains '8 vertices, 12 triangles'

# A leaf crossing itself (the corner (1, 1, 1) pushed through the bottom face): with
# --check-inputs its shells are tested first (exact), and one that crosses itself is
# evaluated by winding number, its faces intersected with each other: 10/27 of the cube
# (a generalized-winding-number estimate agrees to 4 digits).
printf 'OFF\n8 12 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0 0 1\n1 0 1\n0.5 0.5 -0.2\n0 1 1\n' > "$WORK/pushed.off"
cube_off | tail -n 12 >> "$WORK/pushed.off"
printf 'union() { translate([5, 0, 0]) cube(1); import("pushed.off"); }\n' > "$WORK/case.scad"
run 0 eval "$WORK/case.scad" --check-inputs -o "$WORK/out.off"
run 0 check --self-intersections "$WORK/out.off" && contains 'ok: no self-intersections'
run 0 check "$WORK/out.off" && contains '2 components, volume 1.37037037037037'
run 1 check --self-intersections "$WORK/pushed.off"
contains 'pairs of triangles intersect each other'
run 0 check --self-intersections "$MODELS/spot.obj"
contains 'spot.obj: ok: no self-intersections'

# Named relative to the working folder, the model has no folder to resolve imports
# against: they are opened from the working folder (a missing one named as given).
cube_off > "$WORK/closed.off"
printf 'union() { import("closed.off"); import("missing.off"); }\n' > "$WORK/relative.scad"
cli=$(cd "$(dirname "$CLI")" && pwd)/$(basename "$CLI")
OUT=$(cd "$WORK" && "$cli" eval relative.scad -o out.off 2>&1); code=$?
if [ "$code" -eq 1 ]; then passed=$((passed + 1)); else echo "FAIL: exit $code: $OUT"; failed=$((failed + 1)); fi
contains 'missing.off'
finish
