#!/usr/bin/env bash
# Every test under AddressSanitizer and UndefinedBehaviorSanitizer: set up, build everything
# (library, CLI, tests, benchmarks) in build-san/ with -DHYBRIDTREE_SANITIZE=ON, run the suites.
# Every test runs at its full size; ctest gives them UndefinedBehaviorSanitizer's options and the
# third-party suppressions of tests/sanitizers/ (tests/CMakeLists.txt).
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/setup.sh
cmake -S . -B build-san -DCMAKE_BUILD_TYPE=RelWithDebInfo -DHYBRIDTREE_SANITIZE=ON
cmake --build build-san -j"$(nproc)"
ctest --test-dir build-san -j"$(nproc)" --output-on-failure --timeout 1800
