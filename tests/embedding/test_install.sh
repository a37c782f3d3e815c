#!/usr/bin/env bash
# The README's "Embedding" consumer against an installed HybridTree, as a new user would run it:
#   cmake --install BUILD --prefix TMP/prefix
#   the README's CMakeLists.txt and main.cpp, configured with CMAKE_PREFIX_PATH=TMP/prefix,
#   built and run (in a folder holding examples/ and data/, as the README's paths expect);
# then the README's "Python" block with PYTHONPATH set to the prefix's site-packages, when the
# module is built. Usage: test_install.sh SOURCE_DIR BUILD_DIR [PYTHON PYTHON_SITE]
set -euo pipefail
src=$1 build=$2 python=${3:-} site=${4:-}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
blocks="$src/tests/embedding/readme_blocks.py"
interp=${python:-python3}

cmake --install "$build" --prefix "$tmp/prefix" > "$tmp/install.log"
for f in include/hybridtree/api.hpp lib/cmake/HybridTree/HybridTreeConfig.cmake bin/hybridtree; do
  [ -e "$tmp/prefix/$f" ] || { echo "not installed: $f" >&2; exit 1; }
done

mkdir -p "$tmp/consumer" "$tmp/run"
"$interp" "$blocks" "$src/README.md" Embedding cmake > "$tmp/consumer/CMakeLists.txt"
"$interp" "$blocks" "$src/README.md" Embedding cpp > "$tmp/consumer/main.cpp"
cmake -S "$tmp/consumer" -B "$tmp/consumer/build" -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_PREFIX_PATH="$tmp/prefix" > "$tmp/configure.log" || { cat "$tmp/configure.log"; exit 1; }
cmake --build "$tmp/consumer/build" > "$tmp/build.log" 2>&1 || { cat "$tmp/build.log"; exit 1; }
exe=$(find "$tmp/consumer/build" -maxdepth 1 -type f -executable | head -n 1)
[ -n "$exe" ] || { echo "the consumer built no executable" >&2; exit 1; }
ln -s "$src/examples" "$tmp/run/examples"
ln -s "$src/data" "$tmp/run/data"
(cd "$tmp/run" && "$exe")
[ -s "$tmp/run/garden.ply" ] || { echo "the consumer wrote no garden.ply" >&2; exit 1; }
echo "consumer: built against $tmp/prefix and ran"

if [ -n "$site" ]; then
  rm -f "$tmp/run/garden.ply"
  "$interp" "$blocks" "$src/README.md" Python python > "$tmp/readme.py"
  (cd "$tmp/run" && PYTHONPATH="$tmp/prefix/$site" "$interp" "$tmp/readme.py")
  [ -s "$tmp/run/garden.ply" ] || { echo "the Python block wrote no garden.ply" >&2; exit 1; }
  echo "python: the README block ran against $tmp/prefix/$site"
fi
