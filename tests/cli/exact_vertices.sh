# Output vertices that are input vertices keep their exact value, the sign of a zero
# included. Regression: a unit cube with its corner written as -0 -0 -0, united with a
# tetrahedron whose edge passes exactly through that corner (so the corner also arrives
# as an edge/plane intersection point); a merge shortcut once kept the implicit copy and
# wrote the corner as "-0 0 0".
. "$(dirname "$0")/common.bash"

cat > "$WORK/cube.obj" <<'OBJ'
v -0 -0 -0
v 1 0 0
v 0 1 0
v 1 1 0
v 0 0 1
v 1 0 1
v 0 1 1
v 1 1 1
f 1 3 2
f 2 3 4
f 5 6 8
f 5 8 7
f 1 2 6
f 1 6 5
f 3 7 8
f 3 8 4
f 1 5 7
f 1 7 3
f 2 4 8
f 2 8 6
OBJ
cat > "$WORK/tetra.obj" <<'OBJ'
v -0.5 -0.5 0
v 0.5 0.5 0
v 0.5 -0.5 0
v 0 0 -1
f 1 3 2
f 1 2 4
f 2 3 4
f 3 1 4
OBJ
# Both orders: the corner is then first met in the tetrahedron's faces, as an implicit
# point (the output once rounded that copy and wrote "-0 0 0").
for order in 'import("cube.obj"); import("tetra.obj");' 'import("tetra.obj"); import("cube.obj");'; do
    printf 'union() { %s }\n' "$order" > "$WORK/zero.scad"
    run 0 eval "$WORK/zero.scad" -o "$WORK/zero.obj"
    if grep -qx 'v -0 -0 -0' "$WORK/zero.obj"; then passed=$((passed + 1))
    else echo "FAIL ($order): the corner -0 -0 -0 lost a sign:"; grep '^v ' "$WORK/zero.obj" | head -3
        failed=$((failed + 1)); fi
    run 0 check "$WORK/zero.obj"
done
finish
