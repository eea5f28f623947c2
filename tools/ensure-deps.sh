#!/usr/bin/env bash
# Make sure the build dependencies are present; install them with apt-get when running
# as root on Debian, otherwise say exactly what is missing.
#   tools/ensure-deps.sh          gcc, make, cmake, GMP headers, python3 (for the tests)
#   tools/ensure-deps.sh clang    also clang (compile check; libFuzzer runtime for make fuzz)
set -euo pipefail

missing=()
have() { command -v "$1" >/dev/null 2>&1; }
have gcc   || missing+=(gcc)
have make  || missing+=(make)
have cmake || missing+=(cmake)
have python3 || missing+=(python3) # the tests generate ../shared/scenes with it
if ! have gcc || ! echo '#include <gmp.h>' | gcc -E -x c - >/dev/null 2>&1; then
  missing+=(libgmp-dev)
fi
if [ "${1:-}" = clang ]; then
  have clang || missing+=(clang)
  # libFuzzer and the sanitizer runtimes of clang.
  if have clang && ! echo 'int LLVMFuzzerTestOneInput(const char*d,unsigned long n){(void)d;(void)n;return 0;}' |
       clang -fsanitize=fuzzer -x c - -o /dev/null >/dev/null 2>&1; then
    missing+=(libclang-rt-dev)
  fi
fi

[ ${#missing[@]} -eq 0 ] && exit 0

if [ "$(id -u)" = 0 ] && have apt-get; then
  echo "installing: ${missing[*]}"
  apt-get update -qq
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${missing[@]}" >/dev/null
  exit 0
fi
echo "missing build dependencies: ${missing[*]}" >&2
echo "install them with: sudo apt-get install ${missing[*]}" >&2
exit 1
