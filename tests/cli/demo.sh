# meshcsg demo: builds the ring scene, validates every leaf, evaluates it, prints the
# step timings, checks the result against the reference volume and writes it.
. "$(dirname "$0")/common.bash"
run 0 demo -n 100 -o "$WORK/demo.off"
contains "101 leaves, 19600 triangles"
contains "every leaf closed, oriented, manifold"
contains "arrange faces"
contains "classify"
contains "closed, oriented, manifold"
contains "1 shells"
contains "reference volume 1218.25668328392"
contains "matches"
contains "wrote $WORK/demo.off"
run 0 check "$WORK/demo.off"
contains "ok:"
run 2 demo -n
run 2 demo --bogus
finish
