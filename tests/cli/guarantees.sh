# meshcsg eval checks its result: when rounding to doubles broke a guarantee it snaps the
# rounded result to a coarser grid and evaluates it again by its winding number; if that
# does not keep them either, it
# warns, writes the first mesh all the same, and exits with status 3. Parts that touch in
# the exact result are allowed (status 0).
. "$(dirname "$0")/common.bash"
ROUNDING=${MCSG_TEST_DATA:?}/rounding

# Rounding makes parts touch along four edges: vertex copies moved apart by one unit in
# the last place, the result is clean (118 vertices once the 42 inside its flat regions
# and straight edges are removed; 160 with --keep-all-vertices).
for keep in "" --keep-all-vertices; do
    rm -f "$WORK/e18.off"
    run 0 eval "$ROUNDING/example018-moved.scad" -o "$WORK/e18.off" $keep
    lacks "warning"
    run 0 check "$WORK/e18.off"
    if [ -z "$keep" ]; then
        contains "ok: 118 vertices, 232 triangles, 1 component"
    else
        contains "ok: 160 vertices, 316 triangles, 1 component"
    fi
done
# With crossings checked too: the corners of triangles that rounding made cross are moved
# by one unit in the last place (two more than the four copies above; with every vertex
# kept, a sliver that rounding turned over is split away first); the volume stays that of
# the exact result.
for keep in "" --keep-all-vertices; do
    rm -f "$WORK/e18.off"
    run 0 eval "$ROUNDING/example018-moved.scad" -o "$WORK/e18.off" --check-crossings --stats \
        $keep
    lacks "warning"
    contains "touching or crossing made by rounding: 6 vertices moved"
    run 0 check --self-intersections "$WORK/e18.off"
    contains "1 component, volume 175969.18382"
    contains "ok: no self-intersections"
done

# Rounding makes three turned cubes cross (with every vertex kept): two corners moved by
# one unit in the last place, the result has no crossing triangles. Without its flat
# vertices, rounding makes none cross.
run 0 eval "$ROUNDING/crossing-after-rounding-3-cubes/tree.scad" -o "$WORK/c3.off"
lacks "warning"
run 0 eval "$ROUNDING/crossing-after-rounding-3-cubes/tree.scad" -o "$WORK/c3.off" \
    --check-crossings --stats --keep-all-vertices
lacks "warning"
contains "touching or crossing made by rounding: 2 vertices moved by one unit in the last place"
run 0 check --self-intersections "$WORK/c3.off"
contains "ok: no self-intersections"
run 0 eval "$ROUNDING/crossing-after-rounding-3-cubes/tree.scad" -o "$WORK/c3.off" \
    --check-crossings
lacks "warning"
run 0 check --self-intersections "$WORK/c3.off"
contains "ok: no self-intersections"

# Rounding makes parts of the five boxes touch: evaluated again, the result is closed and
# manifold once welded, and with crossings checked has none.
run 0 eval "$ROUNDING/nonmanifold-by-index-5-boxes/tree.scad" -o "$WORK/b5.off"
lacks "warning"
run 0 check "$WORK/b5.off"
run 0 eval "$ROUNDING/nonmanifold-by-index-5-boxes/tree.scad" -o "$WORK/b5.off" --check-crossings
lacks "warning"
run 0 check --self-intersections "$WORK/b5.off"
contains "ok: no self-intersections"

# Fuzz cases (grid family) where the rounds once ended with crossing triangles: a round
# whose evaluation made parts touch where the exact result does not (moved apart there),
# and a round whose evaluation is open (no start for the next round).
for case in touching-in-a-round-4-leaves round-after-open-candidate-8-leaves; do
    rm -f "$WORK/$case.off"
    run 0 eval "$ROUNDING/$case.scad" -o "$WORK/$case.off" --check-crossings
    lacks "warning"
    run 0 check --self-intersections "$WORK/$case.off"
    contains "ok: no self-intersections"
done
# A vertex rounded onto a face: moved off it before any round. (The cone's edge lies in
# the box's face in the exact result: that edge of four triangles is allowed.)
rm -f "$WORK/corner.off"
run 0 eval "$ROUNDING/crossing-corner-moved-2-leaves.scad" -o "$WORK/corner.off" --check-crossings --stats
lacks "warning"
contains "touching or crossing made by rounding: 1 vertices moved"
run 1 check --self-intersections "$WORK/corner.off"
contains "ok: no self-intersections"
contains "error: 1 non-manifold edges"

# The level-3 Menger sponge as exported: its turned group is evaluated in its own frame,
# where the faces meant to be coplanar are; the result is clean.
rm -f "$WORK/m3.off"
run 0 eval "$ROUNDING/menger-3-6digits.scad" -o "$WORK/m3.off" --stats
lacks "warning"
contains "frames"
run 0 check "$WORK/m3.off"
contains "ok: 5327 vertices, 13566 triangles, 1 component"

# The same sponge with every cube turned on its own (the matrices composed into each
# leaf): rounding leaves edges of four triangles once welded, and a round's mesh, snapped
# to a grid, keeps the guarantees checked by default (closed, manifold once welded): it
# is written, status 0. Its triangles still cross, which only --check-crossings counts
# (with it, no round keeps every guarantee and the status is 3; not run here: 14 s).
rm -f "$WORK/m3.off"
run 0 eval "$ROUNDING/menger-3-6digits-leaf-matrices.scad" -o "$WORK/m3.off"
lacks "warning"
run 0 check "$WORK/m3.off"
contains "ok: "
run 1 check --self-intersections "$WORK/m3.off"
contains "pairs of triangles intersect each other"

# A turned group whose result (with every vertex), once turned, has triangles that cross:
# corners moved by a unit in the last place mend them, and the result is clean. Without
# its flat vertices, the group's result has no such triangles.
rm -f "$WORK/f5.off"
run 0 eval "$ROUNDING/frame-turn-makes-crossings-5-leaves.scad" -o "$WORK/f5.off" -v \
    --keep-all-vertices
lacks "warning"
contains "turning a group's result made"
contains "corners moved by a unit in the last place mend them"
run 0 check --self-intersections "$WORK/f5.off"
contains "ok: no self-intersections"
rm -f "$WORK/f5.off"
run 0 eval "$ROUNDING/frame-turn-makes-crossings-5-leaves.scad" -o "$WORK/f5.off"
lacks "warning"
run 0 check --self-intersections "$WORK/f5.off"
contains "ok: 22 vertices, 40 triangles"
contains "ok: no self-intersections"

# A turned group whose turned result folds slivers onto each other: evaluated as a leaf
# by its winding number, it has a region smaller than a unit in the last place of its
# coordinates (the search for a point inside it once gave up, and the tree was evaluated
# with each leaf turned on its own); the result is clean (a fuzz tree of 70 leaves,
# shrunk).
# (With every vertex kept, as the case was found; without its flat vertices the group's
# result folds nothing.)
rm -f "$WORK/fb.off"
run 0 eval "$ROUNDING/frame-fails-flattened-3-leaves.scad" -o "$WORK/fb.off" -v --stats \
    --keep-all-vertices
lacks "warning"
contains "it is evaluated as a mesh that crosses itself"
lacks "failed"
run 0 check --self-intersections "$WORK/fb.off"
contains "ok: 51 vertices, 98 triangles, 1 component, volume 92942.9425918635"
contains "ok: no self-intersections"
rm -f "$WORK/fb.off"
run 0 eval "$ROUNDING/frame-fails-flattened-3-leaves.scad" -o "$WORK/fb.off"
lacks "warning"
run 0 check --self-intersections "$WORK/fb.off"
contains "ok: 30 vertices, 56 triangles, 1 component, volume 92942.94259186"
contains "ok: no self-intersections"

printf 'union() { cube(1); translate([1, 1, 0]) cube(1); }\n' > "$WORK/touching.scad"
run 0 eval "$WORK/touching.scad" -o "$WORK/touching.off" --check-crossings
lacks "warning"
finish
