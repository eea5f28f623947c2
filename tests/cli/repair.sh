# `meshcsg repair`: one mesh's solid by winding number. Two overlapping cubes in one file
# become one shell of the union's volume; a cube with an inward cube inside keeps it as a
# cavity; an inside-out cube alone is empty; a shell crossing itself is named.
. "$(dirname "$0")/common.bash"

# box LO HI [in]: the faces of the cube LO..HI on every axis, outward (or inward), as
# OFF vertex and face lines for vertices numbered from $BASE.
box() {
  local lo=$1 hi=$2 inward=${3:-}
  for x in $lo $hi; do for y in $lo $hi; do for z in $lo $hi; do echo "$x $y $z"; done; done; done
  for q in "0 1 3 2" "4 6 7 5" "0 4 5 1" "2 3 7 6" "0 2 6 4" "1 5 7 3"; do
    set -- $q
    if [ -n "$inward" ]; then set -- $4 $3 $2 $1; fi
    echo "F 3 $((BASE + $1)) $((BASE + $2)) $((BASE + $3))"
    echo "F 3 $((BASE + $1)) $((BASE + $3)) $((BASE + $4))"
  done
}

# shells FILE SPEC...: an OFF file of boxes "lo:hi" or "lo:hi:in".
shells() {
  local file=$1; shift
  local body="" n=0
  BASE=0
  for spec in "$@"; do
    IFS=: read -r lo hi inward <<< "$spec"
    body+=$(box "$lo" "$hi" "$inward")$'\n'
    BASE=$((BASE + 8)); n=$((n + 1))
  done
  { echo OFF; echo "$((8 * n)) $((12 * n)) 0"
    printf '%s' "$body" | grep -v '^F '; printf '%s' "$body" | grep '^F ' | cut -c3-; } > "$file"
}

shells "$WORK/overlap.off" 0:10 5:15
run 0 repair "$WORK/overlap.off" -o "$WORK/union.off" &&
  contains '2 shells in, 6 pairs of triangles meeting (shells crossing); 1 shells out (0 cavities)'
run 0 check "$WORK/union.off" && contains 'volume 1875'

shells "$WORK/cavity.off" 0:10 2:8:in
run 0 repair "$WORK/cavity.off" -o "$WORK/hollow.off" && contains '2 shells out (1 cavities)'
run 0 check "$WORK/hollow.off" && contains 'volume 784'

shells "$WORK/inverted.off" 0:10:in
run 0 repair "$WORK/inverted.off" && contains '0 shells out (0 cavities), 0 vertices, 0 triangles'

# A cube whose corner vertex is pushed through the opposite face crosses itself: its
# faces are intersected with each other, and the result is where its winding number is
# positive (a generalized-winding-number estimate gives 301.1 and 1301.5).
shells "$WORK/folded.off" 0:10
sed -i 's/^10 10 10$/5 5 -2/' "$WORK/folded.off"
run 0 repair "$WORK/folded.off" -o "$WORK/unfolded.off" && contains '1 shells out (0 cavities)'
run 0 check --self-intersections "$WORK/unfolded.off" && contains 'ok: no self-intersections'
run 0 check "$WORK/unfolded.off" && contains '1 component, volume 300.925925925925'
# The same fold in the second of two shells.
shells "$WORK/folded2.off" 0:10 20:30
sed -i 's/^30 30 30$/25 25 18/' "$WORK/folded2.off"
run 0 repair "$WORK/folded2.off" -o "$WORK/unfolded.off" && contains '2 shells out (0 cavities)'
run 0 check "$WORK/unfolded.off" && contains '2 components, volume 1300.925925925925'

finish
