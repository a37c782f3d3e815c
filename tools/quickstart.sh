#!/usr/bin/env bash
# The main job on the bundled example, the paper's winged bunny (Figure 7): set up, build
# (Release), describe the scene, evaluate its field at the example points, mesh it into
# build/winged_bunny.ply with its statistics and draw it into build/winged_bunny.png.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/setup.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
cmake --build build -j"$(nproc)"
scene=${1:-examples/winged_bunny.json}
echo "== hybridtree info $scene"
build/bin/hybridtree info "$scene"
echo "== hybridtree eval $scene --points examples/points.txt --gradient"
build/bin/hybridtree eval "$scene" --points examples/points.txt --gradient
out=build/$(basename "${scene%.json}")
echo "== hybridtree mesh $scene -o $out.ply --stats-json $out.stats.json"
build/bin/hybridtree mesh "$scene" -o "$out.ply" --stats-json "$out.stats.json"
echo "== hybridtree render $scene -o $out.png"
build/bin/hybridtree render "$scene" -o "$out.png"
