# meshcsg eval checks its result: when rounding to doubles broke a guarantee it evaluates
# the rounded result again by its winding number; if that does not keep them either, it
# warns, writes the first mesh all the same, and exits with status 3. Parts that touch in
# the exact result are allowed (status 0).
. "$(dirname "$0")/common.bash"
ROUNDING=${MCSG_TEST_DATA:?}/rounding

# A sliver folded flat by rounding: evaluated again, the result is clean.
run 0 eval "$ROUNDING/example018-moved.scad" -o "$WORK/e18.off"
lacks "warning"
run 0 check "$WORK/e18.off"
contains "ok: 162 vertices, 320 triangles, 1 component"
# With crossings checked, rounding makes new ones in every round: the first result stays.
rm -f "$WORK/e18.off"
run 3 eval "$ROUNDING/example018-moved.scad" -o "$WORK/e18.off" --check-crossings
contains "warning: the result breaks its guarantees after rounding to doubles: 4 edges of more than two triangles once vertices are welded by coordinates"
[ -s "$WORK/e18.off" ] && passed=$((passed + 1)) || { echo "FAIL: no output written"; failed=$((failed + 1)); }
run 1 check "$WORK/e18.off"
contains "4 non-manifold edges"

run 0 eval "$ROUNDING/crossing-after-rounding-3-cubes/tree.scad" -o "$WORK/c3.off"
lacks "warning"
run 3 eval "$ROUNDING/crossing-after-rounding-3-cubes/tree.scad" -o "$WORK/c3.off" --check-crossings
contains "20 pairs of crossing triangles"
run 1 check --self-intersections "$WORK/c3.off"
contains "20 pairs of triangles intersect each other"

run 3 eval "$ROUNDING/nonmanifold-by-index-5-boxes/tree.scad" -o "$WORK/b5.off"
contains "1 edge not manifold by vertex index"

printf 'union() { cube(1); translate([1, 1, 0]) cube(1); }\n' > "$WORK/touching.scad"
run 0 eval "$WORK/touching.scad" -o "$WORK/touching.off" --check-crossings
lacks "warning"
finish
