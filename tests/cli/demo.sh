# meshcsg demo: builds the ring scene, validates every leaf, runs the intersection stage,
# says what is not built yet.
. "$(dirname "$0")/common.bash"
run 0 demo -n 20
contains "21 leaves, 5200 triangles"
contains "every leaf closed, oriented, manifold"
contains "arrange faces"
contains "classification is not built yet"
run 2 demo -n
finish
