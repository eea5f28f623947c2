# Output bytes must not depend on the thread count: scenes big enough that every parallel
# step splits its work (pair tests run in chunks of 4096 pairs; faces, their arrangements
# and the primitives are spread over the threads) are evaluated with 1, 2, 3 and 5
# threads and the OFF files compared byte for byte.
. "$(dirname "$0")/common.bash"

write_box_grid "$WORK/box_grid.scad"
printf 'difference() {\ncylinder(h = 20, r = 10, center = true, $fn = 200);\n%s\n}\n' \
  "$(cylinder_holes_union)" > "$WORK/cylinder_holes.scad"

# same_for_all_threads NAME ARGS... : runs the CLI with ARGS plus "-o FILE --threads T".
same_for_all_threads() {
  local name=$1 t; shift
  run 0 "$@" -o "$WORK/$name-1.off" --threads 1 || return
  for t in 2 3 5; do
    run 0 "$@" -o "$WORK/$name-$t.off" --threads "$t" || continue
    if cmp -s "$WORK/$name-1.off" "$WORK/$name-$t.off"; then
      passed=$((passed + 1))
    else
      echo "FAIL: $name: output with $t threads differs from 1 thread"; failed=$((failed + 1))
    fi
  done
  echo "ok   $name: identical with 1, 2, 3 and 5 threads"
}

same_for_all_threads ring_100 demo -n 100
same_for_all_threads box_grid eval "$WORK/box_grid.scad"
same_for_all_threads cylinder_holes eval "$WORK/cylinder_holes.scad"
finish
