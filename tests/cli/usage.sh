# The option parser: `meshcsg --help` and `meshcsg CMD --help` list every command and
# option (with defaults); unknown options, missing or malformed values and numbers out of
# range are usage errors (exit 2, one line naming the option, nothing else done).
. "$(dirname "$0")/common.bash"

run 0 --help
for cmd in check tree convert intersect eval picture demo; do contains "  $cmd "; done
contains "--version"
run 0 --version
contains "meshcsg "
run 2
contains "usage: meshcsg COMMAND"
run 2 nosuchcommand
contains "unknown command 'nosuchcommand'"

# help CMD OPTION... : CMD --help (and -h) exits 0 and lists every OPTION.
help() {
  local cmd=$1 opt; shift
  run 0 "$cmd" -h
  run 0 "$cmd" --help || return
  contains "usage: meshcsg $cmd [OPTIONS]"
  for opt in "$@" --help; do contains "$opt"; done
}
help check --self-intersections "-o, --output FILE"
help tree
help convert "-f, --format F" "ply-binary-be" "default: from OUT's"
help intersect "-o, --output FILE"
help eval "-o, --output FILE" --stats "-t, --threads N" --check-inputs "default: one per" \
    --keep-all-vertices "-q, --quiet"
help repair "-o, --output FILE" --keep-all-vertices "-q, --quiet"
help picture "--view V" "--size WxH" --edges "default: 800x600"
help demo "-n, --spheres N" "default: 200" "-o, --output FILE" "-t, --threads N"
# --help wins over operands and other options: nothing is read.
run 0 tree "$WORK/missing.scad" --help
lacks "cannot open"

# usage_error MESSAGE ARGS... : exit 2 and exactly one line containing MESSAGE.
usage_error() {
  local message=$1; shift
  run 2 "$@" || return
  contains "$message"
  [ "$(printf '%s\n' "$OUT" | wc -l)" -eq 1 ] && passed=$((passed + 1)) ||
    { echo "FAIL: more than one line: $OUT"; failed=$((failed + 1)); }
}
printf 'cube(1);\n' > "$WORK/c.scad"
usage_error "unknown option: --bogus" check --bogus "$WORK/c.scad"
usage_error "unknown option: -x" eval -x "$WORK/c.scad"
usage_error "--threads takes a whole number from 1 to 1024: abc" eval "$WORK/c.scad" --threads abc
usage_error "--threads takes a whole number from 1 to 1024: 0" eval "$WORK/c.scad" --threads 0
usage_error "--threads takes a whole number from 1 to 1024: 2x" eval "$WORK/c.scad" --threads=2x
usage_error "-t takes a whole number from 1 to 1024: 99999999999999999999" eval "$WORK/c.scad" -t 99999999999999999999
usage_error "--threads needs a value" eval "$WORK/c.scad" --threads
usage_error "-n takes a whole number from 1 to 10000: -3" demo -n -3
usage_error "--stats takes no value" eval "$WORK/c.scad" --stats=1
usage_error "missing operand" eval
usage_error "too many operands" eval "$WORK/c.scad" "$WORK/c.scad"
usage_error "too many operands" tree a b
usage_error "missing operand" convert "$WORK/c.scad"
usage_error "unknown format 'nope'" convert "$MODELS/cube.obj" "$WORK/x.off" --format nope
usage_error "-o writes one fixed mesh" check -o "$WORK/x.off" "$MODELS/cube.obj" "$MODELS/cube.obj"

# The accepted spellings: --name=value, -xVALUE, and -- before an operand that starts
# with '-'.
run 0 eval "$WORK/c.scad" --threads=2 -o"$WORK/c1.off"
contains "8 vertices, 12 triangles"
[ -s "$WORK/c1.off" ] && passed=$((passed + 1)) || { echo "FAIL: -oFILE wrote nothing"; failed=$((failed + 1)); }
cp "$WORK/c.scad" "$WORK/-dash.scad"
(cd "$WORK" && "$CLI" eval -t 1 -- -dash.scad >/dev/null 2>&1) && passed=$((passed + 1)) ||
  { echo "FAIL: -- did not end the options"; failed=$((failed + 1)); }

# Flat vertices: two cubes side by side are one box of 8 corners, or with every vertex
# of the exact result 12 (the shared face's corners), for eval and repair alike.
printf 'union() { cube(1); translate([1, 0, 0]) cube(1); }\n' > "$WORK/two.scad"
run 0 eval "$WORK/two.scad" -o "$WORK/two.off" --stats
contains "8 vertices, 12 triangles"
contains "4 flat vertices removed"
contains "output triangles 12, smallest angle"
run 0 eval "$WORK/two.scad" --keep-all-vertices
contains "12 vertices, 20 triangles"
run 0 repair "$WORK/two.off" --keep-all-vertices
contains "8 vertices, 12 triangles"

# Pictures: PNG files (their pixels are test_picture's); bad views and sizes are usage
# errors named as such.
run 0 picture "$MODELS/cube.obj" "$WORK/cube.png" --view top --size 64x32 --edges
[ "$(head -c 8 "$WORK/cube.png" | od -An -tx1 | tr -d ' ')" = 89504e470d0a1a0a ] &&
  passed=$((passed + 1)) || { echo "FAIL: picture wrote no PNG"; failed=$((failed + 1)); }
run 0 eval "$WORK/two.scad" --picture "$WORK/two.png" -q
[ -s "$WORK/two.png" ] && [ -z "$OUT" ] && passed=$((passed + 1)) ||
  { echo "FAIL: eval --picture"; failed=$((failed + 1)); }
usage_error "--view takes iso, top, front or side: below" picture "$MODELS/cube.obj" "$WORK/x.png" --view below
usage_error "--size takes WxH, each from 16 to 8192: 8x8" eval "$WORK/c.scad" --picture "$WORK/x.png" --size 8x8
usage_error "--view, --size and --edges go with --picture" eval "$WORK/c.scad" --edges
run 1 picture "$MODELS/cube.obj" "$WORK/no/such/dir.png"
contains "cannot create"

# --quiet: nothing but errors. The leaf's zero-area pair gives a warning without it.
usage_error "--quiet and --verbose contradict each other" eval "$WORK/c.scad" -q -v
printf 'cube(1); polyhedron(points = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0.5, 0, 0]],
  faces = [[0, 1, 2], [0, 2, 1], [0, 3, 1], [0, 1, 3]]);\n' > "$WORK/warn.scad"
run 0 eval "$WORK/warn.scad"
contains "warning: leaf 1"
run 0 eval "$WORK/warn.scad" --quiet -o "$WORK/warn.off"
[ -z "$OUT" ] && [ -s "$WORK/warn.off" ] && passed=$((passed + 1)) ||
  { echo "FAIL: eval --quiet printed '$OUT' or wrote nothing"; failed=$((failed + 1)); }
run 0 repair "$WORK/two.off" -q
[ -z "$OUT" ] && passed=$((passed + 1)) || { echo "FAIL: repair -q printed '$OUT'"; failed=$((failed + 1)); }
run 1 eval "$WORK/missing.scad" -q
contains "missing.scad"

# The progress line: on a terminal only (script(1) gives the program one), once the
# work has run for a second; never with --quiet or into a pipe or file.
if [ "${MCSG_FULL_SCENES:-1}" = 1 ] && command -v script >/dev/null; then
  OUT=$(script -qec "'$CLI' demo -n 1500 -t 1" /dev/null 2>&1)
  contains "meshcsg: step "
  contains " of 5 ("
  run 0 demo -n 1500 -t 1
  lacks "meshcsg: step "
  { echo 'union() {'
    for i in $(seq 0 799); do echo "translate([$i * 1.5, 0, 0]) sphere(1, \$fn = 24);"; done
    echo '}'; } > "$WORK/slow.scad"
  OUT=$(script -qec "'$CLI' eval '$WORK/slow.scad' -t 1 --quiet; echo exit \$?" /dev/null 2>&1)
  lacks "meshcsg: step "
  contains "exit 0"
  OUT=$(script -qec "'$CLI' eval '$WORK/slow.scad' -t 1" /dev/null 2>&1)
  contains "meshcsg: step "
fi

# The README shows `meshcsg --help` verbatim: it must not drift from the tables.
readme=${MCSG_TEST_DATA:?}/../../README.md
if [ -f "$readme" ]; then
  shown=$(awk '/^## Command line/ { section = 1 } section && /^```$/ { if (inside) exit; inside = 1; next }
               inside { print }' "$readme")
  if [ "$shown" = "$("$CLI" --help)" ]; then passed=$((passed + 1))
  else echo "FAIL: README.md's command-line block differs from meshcsg --help:"
    diff <(printf '%s\n' "$shown") <("$CLI" --help) | head -20; failed=$((failed + 1)); fi
fi
finish
