# Shared helpers for the CLI tests (tests/cli/*.sh source this; the CLI path is $1).
set -u
CLI=${1:?usage: test.sh PATH_TO_MESHCSG}
WORK=${MCSG_TMP:-$(mktemp -d)}
rm -rf "$WORK"; mkdir -p "$WORK"
MODELS=${MCSG_TEST_DATA:?MCSG_TEST_DATA not set (run under ctest)}/models
passed=0; failed=0

# run EXPECTED_EXIT CMD... : runs the CLI, keeps stdout+stderr in $OUT.
run() {
  local expected=$1; shift
  OUT=$("$CLI" "$@" 2>&1); local code=$?
  if [ "$code" -ne "$expected" ]; then
    echo "FAIL: meshcsg $* exited $code, expected $expected"; echo "$OUT" | head -20
    failed=$((failed + 1)); return 1
  fi
  passed=$((passed + 1))
}

# contains TEXT : the last run's output contains TEXT.
contains() {
  if printf '%s' "$OUT" | grep -qF -- "$1"; then passed=$((passed + 1))
  else echo "FAIL: expected '$1' in output:"; echo "$OUT" | head -20; failed=$((failed + 1)); fi
}

lacks() {
  if printf '%s' "$OUT" | grep -qF -- "$1"; then
    echo "FAIL: did not expect '$1' in output:"; echo "$OUT" | head -20; failed=$((failed + 1))
  else passed=$((passed + 1)); fi
}

# skip REASON : the script's checks cannot run here (optional data missing). CTest
# reports exit status 77 as skipped, never as passed.
skip() {
  echo "skipped: $1"
  exit 77
}

finish() {
  echo "$passed passed, $failed failed"
  [ "$failed" -eq 0 ] && [ "$passed" -gt 0 ]
}

# Scenes for scenes.sh and threads.sh, written as CSG files of primitives.
# write_box_grid FILE: a plate minus an 8 x 8 grid of square holes, plus 8 bars on top.
write_box_grid() {
  {
    echo 'union() {'
    echo '  difference() {'
    echo '    cube([8, 8, 1]);'
    for i in 0 1 2 3 4 5 6 7; do for j in 0 1 2 3 4 5 6 7; do
      echo "    translate([$i.25, $j.25, -1]) cube([0.5, 0.5, 3]);"
    done; done
    echo '  }'
    for i in 0 1 2 3 4 5 6 7; do echo "  translate([$i, 0, 1]) cube([0.25, 8, 0.5]);"; done
    echo '}'
  } > "$1"
}

# write_drill_plate FILE: a plate drilled by an 8 x 8 grid of 24-sided holes.
write_drill_plate() {
  {
    echo 'difference() {'
    echo '  cube([8, 8, 1]);'
    for i in 0 1 2 3 4 5 6 7; do for j in 0 1 2 3 4 5 6 7; do
      echo "  translate([$i.5, $j.5, -0.5]) cylinder(h = 2, r = 0.3, \$fn = 24);"
    done; done
    echo '}'
  } > "$1"
}

# cylinder_holes_union: prints a union of 28 tilted cylinders crossing a cylinder of
# radius 10 and height 20 centred at the origin (about 27,000 crossing triangle pairs).
cylinder_holes_union() {
  awk 'BEGIN {
    print "union() {"
    for (k = 0; k < 28; k++) {
      a = 360 * k / 28; t = 20 + (k * 37) % 50; z = -8 + (k * 13) % 16
      printf "  rotate([0, 0, %g]) translate([0, 0, %g]) rotate([%g, 90, 0]) ", a, z, t
      printf "cylinder(h = 30, r = %g, center = true, $fn = 48);\n", 1 + (k % 3) * 0.4
    }
    print "}" }'
}

cube_off() { # cube_off [drop-last-n] [flip]
  local drop=${1:-0} flip=${2:-0}
  local faces=("0 2 1" "0 3 2" "4 5 6" "4 6 7" "0 1 5" "0 5 4" "1 2 6" "1 6 5" "2 3 7" "2 7 6" "3 0 4" "3 4 7")
  local n=$((12 - drop))
  printf 'OFF\n8 %d 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0 0 1\n1 0 1\n1 1 1\n0 1 1\n' "$n"
  for ((i = 0; i < n; i++)); do
    set -- ${faces[$i]}
    if [ "$flip" = 1 ]; then echo "3 $1 $3 $2"; else echo "3 $1 $2 $3"; fi
  done
}
