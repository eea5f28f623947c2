#!/usr/bin/env bash
# Run every libFuzzer target in BUILD_DIR for SECONDS each, starting from the committed
# corpus (copied, so new inputs stay in the build tree). Crashes are written under
# BUILD_DIR/fuzz-findings/TARGET/; copy the ones worth keeping into fuzz/corpus/TARGET/
# as regression inputs once the bug is fixed.
set -euo pipefail
build=${1:?usage: fuzz/run.sh BUILD_DIR SECONDS}
seconds=${2:-60}
src=$(cd "$(dirname "$0")" && pwd)
status=0
for bin in "$build"/fuzz/fuzz_*; do
  [ -x "$bin" ] || continue
  target=$(basename "$bin"); target=${target#fuzz_}
  work="$build/fuzz-corpus/$target"; findings="$build/fuzz-findings/$target"
  mkdir -p "$work" "$findings"
  cp -n "$src/corpus/$target"/* "$work"/ 2>/dev/null || true
  echo "== fuzzing $target for ${seconds}s"
  if ! "$bin" "$work" -max_total_time="$seconds" -max_len=65536 -timeout=10 \
       -rss_limit_mb=2048 -artifact_prefix="$findings/" -print_final_stats=1 2>"$findings/log"; then
    echo "!! $target: a finding; see $findings/ and the end of $findings/log"
    tail -n 30 "$findings/log"
    status=1
  else
    grep -E 'stat::number_of_executed_units|cov:' "$findings/log" | tail -n 2
  fi
done
exit $status
