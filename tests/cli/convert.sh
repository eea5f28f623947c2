# meshcsg convert: every format round-trips Spot (tests/data/models/spot.obj) with its counts and stays valid.
. "$(dirname "$0")/common.bash"

for fmt in off obj stl-ascii stl-binary ply-ascii ply-binary ply-binary-be 3mf; do
  ext=${fmt%%-*}
  run 0 convert "$MODELS/spot.obj" "$WORK/spot-$fmt.$ext" --format "$fmt"
  contains "2930 vertices, 5856 triangles"
  run 0 check "$WORK/spot-$fmt.$ext"
  contains "ok: 2930 vertices, 5856 triangles, 1 component"
  run 0 convert "$WORK/spot-$fmt.$ext" "$WORK/back-$fmt.off"
done
# OFF, OBJ, PLY and 3MF keep doubles exactly: converting back gives the same OFF text.
run 0 convert "$MODELS/spot.obj" "$WORK/ref.off"
for fmt in obj ply-ascii ply-binary ply-binary-be 3mf; do
  if cmp -s "$WORK/ref.off" "$WORK/back-$fmt.off"; then passed=$((passed + 1))
  else echo "FAIL: $fmt round trip changed the mesh"; failed=$((failed + 1)); fi
done

run 2 convert "$MODELS/cube.obj" "$WORK/out.xyz"
contains "cannot tell the output format"
run 2 convert "$MODELS/cube.obj" "$WORK/out.off" --format nope
run 1 convert "$WORK/none.obj" "$WORK/out.off"
contains "none.obj"
[ ! -e "$WORK/out.off" ] && passed=$((passed + 1)) || { echo "FAIL: partial output left"; failed=$((failed + 1)); }
finish
