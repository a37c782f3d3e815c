#!/usr/bin/env bash
# The main job on the bundled example: set up, build (Release), describe the scene, evaluate its
# field at the example points, and mesh it into build/bunny_garden.ply with its statistics.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/setup.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
cmake --build build -j"$(nproc)"
scene=${1:-examples/bunny_garden.json}
echo "== hybridtree info $scene"
build/bin/hybridtree info "$scene"
echo "== hybridtree eval $scene --points examples/points.txt --gradient"
build/bin/hybridtree eval "$scene" --points examples/points.txt --gradient
out=build/$(basename "${scene%.json}")
echo "== hybridtree mesh $scene -o $out.ply --stats-json $out.stats.json"
build/bin/hybridtree mesh "$scene" -o "$out.ply" --stats-json "$out.stats.json"
