# Shared helpers for the CLI tests (tests/cli/*.sh source this; the CLI path is $1).
set -u
CLI=${1:?usage: test.sh PATH_TO_MESHCSG}
WORK=${MCSG_TMP:-$(mktemp -d)}
rm -rf "$WORK"; mkdir -p "$WORK"
MODELS=${MCSG_SHARED_DIR:?MCSG_SHARED_DIR not set}/models
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

finish() {
  echo "$passed passed, $failed failed"
  [ "$failed" -eq 0 ] && [ "$passed" -gt 0 ]
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
