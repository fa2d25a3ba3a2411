#!/usr/bin/env bash
# Installs the build into a temporary prefix and runs the installed programs from another
# directory: `lcmloc-fusion --help` names the installed default config, and an installed
# lcmloc-replay of a shipped log gives the bytes the build tree's replay gives.
# Usage: check_install.sh BUILD_DIR SOURCE_DIR
set -euo pipefail
build=$1 src=$2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
prefix=$tmp/prefix
cmake --install "$build" --prefix "$prefix" > "$tmp/install.log"

fail() { echo "FAIL: $*" >&2; exit 1; }
for f in bin/lcmloc-fusion bin/lcmloc-replay bin/lcmloc-logger share/lcmloc/config/paper.yaml \
         share/java/lcmloc_types.jar share/java/lcmloc_spy.jar share/doc/lcmloc/README.md; do
  [[ -e $prefix/$f ]] || fail "$f not installed"
done
for f in "$prefix"/bin/*; do
  case $(basename "$f") in test_* | bench_* | lcmloc-burst) fail "test or benchmark program installed: $f" ;; esac
done

mkdir "$tmp/elsewhere" && cd "$tmp/elsewhere"
# No source path compiled in: the installed program's default config is under its prefix.
env -u LCMLOC_CONFIG_DIR "$prefix/bin/lcmloc-fusion" --help > help.txt || fail "lcmloc-fusion --help exited $?"
grep -q -- "$prefix/share/lcmloc/config/paper.yaml" help.txt || fail "--help does not name the installed config: $(grep -- --config help.txt)"
grep -q -- "$src/config" help.txt && fail "--help names the source tree's config"

# A shipped log replayed by the installed program, with a relative path, from here.
cp "$src/tests/data/golden/vp.lcmlog" "$src/tests/data/golden/vp.yaml" .
env -u LCMLOC_CONFIG_DIR "$prefix/bin/lcmloc-replay" vp.lcmlog --config vp.yaml -o installed.lcmlog \
  > replay.txt 2>&1 || fail "installed lcmloc-replay exited $?: $(cat replay.txt)"
"$build/bin/lcmloc-replay" vp.lcmlog --config vp.yaml -o built.lcmlog > /dev/null 2>&1 || fail "build-tree lcmloc-replay failed"
[[ -s installed.lcmlog ]] || fail "the installed replay wrote nothing"
cmp installed.lcmlog built.lcmlog || fail "the installed replay differs from the build tree's"
echo "installed into $prefix: $(ls "$prefix/bin" | wc -l) programs; replay of vp.lcmlog identical ($(stat -c %s installed.lcmlog) bytes)"
