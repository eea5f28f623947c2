#!/usr/bin/env bash
# Installs the build in $1 (cmake --install, as `make install` does) into a scratch
# prefix and checks what a user gets: the files of docs/architecture.md's list, the
# shared library's soname and exported symbols, a C program built with pkg-config, a
# CMake project with find_package(meshcsg), the README's Python example, the manual page
# against the tool's help, DESTDIR, and an uninstall that leaves nothing behind.
#   run.sh BUILD_DIR SOURCE_DIR SCRATCH_DIR
set -euo pipefail
build=$1 source=$2 scratch=$3
fail() { echo "FAIL: $*" >&2; exit 1; }
rm -rf "$scratch" && mkdir -p "$scratch"
prefix=$scratch/prefix
cmake --install "$build" --prefix "$prefix" >/dev/null

version=$(sed -n 's/^#define MCSG_VERSION_\(MAJOR\|MINOR\|PATCH\) \+\([0-9]\+\)$/\2/p' \
          "$source/include/meshcsg.h" | paste -sd.)
major=${version%%.*}
for f in bin/meshcsg include/meshcsg.h lib/libmeshcsg.a lib/libmeshcsg.so \
         lib/libmeshcsg.so.$major lib/libmeshcsg.so.$version lib/pkgconfig/meshcsg.pc \
         lib/cmake/meshcsg/meshcsgConfig.cmake lib/cmake/meshcsg/meshcsgConfigVersion.cmake \
         lib/cmake/meshcsg/meshcsgTargets.cmake share/man/man1/meshcsg.1 \
         lib/python3/dist-packages/meshcsg/__init__.py \
         share/meshcsg/installed-files; do
  [ -e "$prefix/$f" ] || fail "$f not installed"
done
echo "ok   installed files (version $version)"

# The soname names the major version; only the header's mcsg_* functions are exported,
# and every one of them is.
soname=$(readelf -d "$prefix/lib/libmeshcsg.so.$version" | sed -n 's/.*Library soname: \[\(.*\)\]/\1/p')
[ "$soname" = "libmeshcsg.so.$major" ] || fail "soname '$soname', expected libmeshcsg.so.$major"
nm -D --defined-only "$prefix/lib/libmeshcsg.so" | awk '{print $3}' | sort -u > "$scratch/exported"
grep -v '^mcsg_' "$scratch/exported" > "$scratch/foreign" && fail "exported beyond mcsg_*: $(head -5 "$scratch/foreign" | paste -sd' ')"
grep -o '\bmcsg_[a-z0-9_]*(' "$source/include/meshcsg.h" | tr -d '(' | sort -u > "$scratch/declared"
missing=$(comm -23 "$scratch/declared" "$scratch/exported" | paste -sd' ')
[ -z "$missing" ] || fail "declared in meshcsg.h but not exported: $missing"
echo "ok   soname $soname, $(wc -l < "$scratch/exported") symbols exported, all mcsg_*"

# A C program built with pkg-config, run against the installed shared library.
export PKG_CONFIG_PATH=$prefix/lib/pkgconfig
[ "$(pkg-config --modversion meshcsg)" = "$version" ] || fail "pkg-config --modversion"
cc -std=c11 -Wall -Werror "$source/tests/install/use.c" $(pkg-config --cflags --libs meshcsg) \
   -o "$scratch/use_pkgconfig"
# (outputs captured before grep -q: under pipefail its early exit would fail the writer)
loaded=$(LD_LIBRARY_PATH=$prefix/lib ldd "$scratch/use_pkgconfig")
grep -q "libmeshcsg.so.$major => $prefix/lib/" <<< "$loaded" ||
  fail "use_pkgconfig does not load libmeshcsg.so.$major"
LD_LIBRARY_PATH=$prefix/lib "$scratch/use_pkgconfig" || fail "use_pkgconfig"
echo "ok   pkg-config build"

# A CMake project: the shared target and the static one.
cmake -S "$source/tests/install/cmake" -B "$scratch/cmake" -DCMAKE_PREFIX_PATH="$prefix" \
      -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$scratch/cmake" >/dev/null
LD_LIBRARY_PATH=$prefix/lib "$scratch/cmake/use_shared" || fail "use_shared (CMake)"
"$scratch/cmake/use_static" || fail "use_static (CMake)"
dynamic=$(readelf -d "$scratch/cmake/use_static")
grep -q libmeshcsg <<< "$dynamic" && fail "use_static links the shared library"
echo "ok   CMake find_package build (meshcsg::meshcsg, meshcsg::meshcsg_static)"

# The manual page names every command and every long option of the installed tool.
page=$(sed 's/\\//g' "$prefix/share/man/man1/meshcsg.1")
for cmd in $("$prefix/bin/meshcsg" --help | sed -n 's/^  \([a-z]\+\) .*/\1/p'); do
  grep -q "$cmd" <<< "$page" || fail "meshcsg.1 lacks the command $cmd"
  for opt in $("$prefix/bin/meshcsg" "$cmd" --help | grep -o -- '--[a-z-]\+' | sort -u); do
    grep -q -- "$opt" <<< "$page" || fail "meshcsg.1 lacks $cmd's option $opt"
  done
done
echo "ok   manual page covers every command and option"

# The README's Python example, on the installed package and library alone.
python=${MCSG_PYTHON:-python3}
sed -n '/^## Python/,/^## /p' "$source/README.md" | sed -n '/^```python/,/^```/p' | sed '1d;$d' \
  > "$scratch/example.py"
[ -s "$scratch/example.py" ] || fail "no Python example in README.md"
(cd "$scratch" && env -u MESHCSG_LIBRARY PYTHONPATH="$prefix/lib/python3/dist-packages" \
   "$python" example.py) || fail "the README's Python example"
[ -s "$scratch/part.stl" ] || fail "the Python example wrote no part.stl"
echo "ok   Python example from the README"

# DESTDIR: everything under it, and the relocatable pkg-config file still works there.
DESTDIR=$scratch/stage cmake --install "$build" --prefix /opt/meshcsg >/dev/null
[ -e "$scratch/stage/opt/meshcsg/lib/libmeshcsg.so" ] || fail "DESTDIR not honoured"
PKG_CONFIG_PATH=$scratch/stage/opt/meshcsg/lib/pkgconfig cc -std=c11 "$source/tests/install/use.c" \
  $(PKG_CONFIG_PATH=$scratch/stage/opt/meshcsg/lib/pkgconfig pkg-config --cflags --libs meshcsg) \
  -o "$scratch/use_stage"
LD_LIBRARY_PATH=$scratch/stage/opt/meshcsg/lib "$scratch/use_stage" >/dev/null || fail "use_stage"
echo "ok   DESTDIR"

# Uninstall removes every installed file, and meshcsg's own folders.
bash "$source/tools/uninstall.sh" "$prefix" >/dev/null
left=$(find "$prefix" ! -type d -o -name meshcsg | head -5 | paste -sd' ')
[ -z "$left" ] || fail "left after uninstall: $left"
bash "$source/tools/uninstall.sh" "$scratch/stage/opt/meshcsg" >/dev/null
[ -z "$(find "$scratch/stage" ! -type d | head -1)" ] || fail "DESTDIR uninstall"
echo "ok   uninstall"
rm -rf "$scratch"
