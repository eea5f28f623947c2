#!/usr/bin/env bash
# Make sure the build dependencies are present; install them with apt-get when running
# as root on Debian, otherwise say exactly what is missing.
#   tools/ensure-deps.sh          gcc, make, cmake, GMP, libpng, libzip and expat headers,
#                                 FreeType, HarfBuzz and fontconfig (text()) with the
#                                 Liberation fonts (OpenSCAD's default font), python3
#                                 (benchmark scenes), pkg-config (the build and the
#                                 install test), python3-numpy and
#                                 python3-pytest (the Python interface's tests),
#                                 and the de_DE.UTF-8 locale (test_numparse_locale checks
#                                 that numbers ignore a decimal comma)
#   tools/ensure-deps.sh clang    also clang (compile check; libFuzzer runtime for make fuzz)
set -euo pipefail

missing=()
have() { command -v "$1" >/dev/null 2>&1; }
have gcc   || missing+=(gcc)
have make  || missing+=(make)
have cmake || missing+=(cmake)
have python3 || missing+=(python3) # make bench and the optional shared-scene test
have pkg-config || missing+=(pkg-config) # the font libraries; the install test builds as a user would
# The Python interface's tests, on Debian's interpreter (the one apt's packages serve).
python=/usr/bin/python3; [ -x "$python" ] || python=python3
"$python" -c 'import numpy' >/dev/null 2>&1 || missing+=(python3-numpy)
"$python" -c 'import pytest' >/dev/null 2>&1 || missing+=(python3-pytest)
has_german_locale() { locale -a 2>/dev/null | grep -qix 'de_DE.utf-\{0,1\}8'; }
# Optional (installed when root, otherwise the test that needs it is skipped):
optional=()
[ -e /usr/share/i18n/locales/de_DE ] || optional+=(locales)
if ! have gcc || ! echo '#include <gmp.h>' | gcc -E -x c - >/dev/null 2>&1; then
  missing+=(libgmp-dev)
fi
if ! have gcc || ! echo '#include <png.h>' | gcc -E -x c - >/dev/null 2>&1; then
  missing+=(libpng-dev) # the tool's pictures
fi
if ! have gcc || ! echo '#include <zip.h>' | gcc -E -x c - >/dev/null 2>&1; then
  missing+=(libzip-dev) # 3MF's container
fi
if ! have gcc || ! echo '#include <expat.h>' | gcc -E -x c - >/dev/null 2>&1; then
  missing+=(libexpat1-dev) # 3MF's XML
fi
# text(): found through pkg-config; the Liberation fonts are OpenSCAD's default, and
# test_text compares their outlines with OpenSCAD's.
has_pc() { have pkg-config && pkg-config --exists "$1"; }
has_pc freetype2 || missing+=(libfreetype-dev)
has_pc harfbuzz || missing+=(libharfbuzz-dev)
has_pc fontconfig || missing+=(libfontconfig-dev)
if have fc-list; then
  [ -n "$(fc-list 'Liberation Sans' file)" ] || missing+=(fonts-liberation2)
else
  [ -e /usr/share/fonts/truetype/liberation2/LiberationSans-Regular.ttf ] || missing+=(fonts-liberation2)
fi
if [ "${1:-}" = clang ]; then
  have clang || missing+=(clang)
  # libFuzzer and the sanitizer runtimes of clang.
  if have clang && ! echo 'int LLVMFuzzerTestOneInput(const char*d,unsigned long n){(void)d;(void)n;return 0;}' |
       clang -fsanitize=fuzzer -x c - -o /dev/null >/dev/null 2>&1; then
    missing+=(libclang-rt-dev)
  fi
fi

# The locale is generated from the `locales` package's sources (localedef, in libc-bin).
make_german_locale() {
  has_german_locale && return 0
  if [ "$(id -u)" = 0 ]; then
    echo "generating the de_DE.UTF-8 locale (for test_numparse_locale)"
    localedef -i de_DE -f UTF-8 de_DE.UTF-8 || echo "warning: localedef failed: test_numparse_locale will be skipped" >&2
  else
    echo "note: the de_DE.UTF-8 locale is missing: test_numparse_locale will be skipped" >&2
    echo "      (generate it with: sudo localedef -i de_DE -f UTF-8 de_DE.UTF-8)" >&2
  fi
}

if [ "$(id -u)" = 0 ] && have apt-get && [ ${#missing[@]} -gt 0 -o ${#optional[@]} -gt 0 ]; then
  echo "installing: ${missing[*]} ${optional[*]}"
  apt-get update -qq
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${missing[@]}" "${optional[@]}" >/dev/null
  missing=()
fi
if [ ${#missing[@]} -eq 0 ]; then
  make_german_locale
  exit 0
fi
echo "missing build dependencies: ${missing[*]}" >&2
echo "install them with: sudo apt-get install ${missing[*]}" >&2
exit 1
