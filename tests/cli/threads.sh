# Output bytes must not depend on the thread count: shared scenes big enough that every
# parallel step splits its work (pair tests run in chunks of 4096 pairs; faces, their
# arrangements and the primitives are spread over the threads) are evaluated with 1, 2,
# 3 and 5 threads and the OFF files compared byte for byte.
. "$(dirname "$0")/common.bash"
SCENES_DIR=${MCSG_SHARED_DIR}/scenes
command -v python3 >/dev/null || { echo "FAIL: python3 is needed to generate the scenes"; exit 1; }
list="ring_spheres_100,box_grid_8,cylinder_28_holes"
python3 "$SCENES_DIR/make_scenes.py" "$WORK/scenes" --models "$MCSG_SHARED_DIR/models" \
  --only "$list" >/dev/null || { echo "FAIL: make_scenes.py"; exit 1; }

IFS=, read -ra names <<< "$list"
for name in "${names[@]}"; do
  run 0 eval "$WORK/scenes/$name/tree.scad" -o "$WORK/$name-1.off" --threads 1 || continue
  contains "triangles"
  for t in 2 3 5; do
    run 0 eval "$WORK/scenes/$name/tree.scad" -o "$WORK/$name-$t.off" --threads "$t" || continue
    if cmp -s "$WORK/$name-1.off" "$WORK/$name-$t.off"; then
      passed=$((passed + 1))
    else
      echo "FAIL: $name: output with $t threads differs from 1 thread"; failed=$((failed + 1))
    fi
  done
  echo "ok   $name: identical with 1, 2, 3 and 5 threads"
done
finish
