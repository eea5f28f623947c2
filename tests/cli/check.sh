# meshcsg check: valid models pass, each problem class is named, exit codes are right.
. "$(dirname "$0")/common.bash"

run 0 check "$MODELS/cube.obj" "$MODELS/spot.obj" "$MODELS/sphere.obj"
contains "cube.obj: ok: 8 vertices, 12 triangles, 1 component, volume 1"
contains "spot.obj: ok: 2930 vertices, 5856 triangles, 1 component, volume"
contains "sphere.obj: ok: 1442 vertices, 2880 triangles, 1 component, volume"

cube_off 1 > "$WORK/open.off"
run 1 check "$WORK/open.off"
contains "open.off: error: 3 boundary edges (the surface is open), e.g. between vertex"

cube_off 0 1 > "$WORK/inverted.off"
run 0 check -o "$WORK/fixed.off" "$WORK/inverted.off"
contains "inverted.off: warning: the mesh is inside out (volume -1): every triangle faces inward; flipped"
run 0 check "$WORK/fixed.off"
contains "fixed.off: ok: 8 vertices, 12 triangles, 1 component, volume 1"
lacks "inside out"

# One flipped triangle in an otherwise valid cube.
{ cube_off 1; echo "3 3 7 4"; } | sed "s/^8 11 0$/8 12 0/" > "$WORK/oneflip.off"
run 1 check "$WORK/oneflip.off"
contains "oneflip.off: error: 3 inconsistently oriented edges"

# Duplicate and degenerate triangles, non-manifold edges.
{ cube_off; echo "3 0 2 1"; } | sed 's/^8 12 0$/8 13 0/' > "$WORK/dup.off"
run 1 check "$WORK/dup.off"
contains "1 duplicate triangles"
contains "3 non-manifold edges"

run 1 check "$WORK/missing.off"
contains "missing.off"

run 1 check "$MODELS/cube.obj" "$WORK/open.off"
contains "cube.obj: ok"
run 2 check
run 2 nosuchcommand
finish
