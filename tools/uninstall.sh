#!/usr/bin/env bash
# `make uninstall`: removes what `make install` put under ROOT ($(DESTDIR)$(PREFIX)), the
# files listed in ROOT/share/meshcsg/installed-files, then meshcsg's own folders. Shared
# folders (bin, lib, ...) stay, even when empty.
#   tools/uninstall.sh ROOT
set -euo pipefail
root=${1:?usage: tools/uninstall.sh ROOT}
list=$root/share/meshcsg/installed-files
if [ ! -f "$list" ]; then
  echo "uninstall: no $list: meshcsg is not installed under $root" >&2
  exit 1
fi
mapfile -t files < "$list"
for f in "${files[@]}"; do
  case $f in
    '' | /* | *..*) echo "uninstall: skipped '$f' (not a path inside $root)" >&2; continue ;;
  esac
  if [ -e "$root/$f" ] || [ -L "$root/$f" ]; then
    rm -f "$root/$f"
    echo "removed $root/$f"
  fi
done
# Python writes its byte code next to the package on import: gone with it.
rm -rf "$root/lib/python3/dist-packages/meshcsg/__pycache__"
for d in lib/cmake/meshcsg share/meshcsg lib/python3/dist-packages/meshcsg; do
  rmdir "$root/$d" 2>/dev/null || true
done
