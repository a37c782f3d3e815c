#!/usr/bin/env bash
# Builds the libFuzzer targets in build-fuzz/ (clang, -DHYBRIDTREE_FUZZ=ON: AddressSanitizer,
# UndefinedBehaviorSanitizer, coverage) and runs each for SECONDS (default 60), one after the
# other, on one core, starting from its committed corpus in fuzz/corpus/<name>/.
#   bash tools/fuzz.sh [SECONDS] [NAME...]       NAME: scene mesh_off mesh_obj mesh_ply mesh_stl cache_entry cache_part
# New inputs go to build-fuzz/corpus/<name>/ (not committed); a finding stops its target and
# leaves crash-*, leak-*, timeout-* or oom-* in build-fuzz/findings/. To keep a finding as a
# regression input, minimize it (build-fuzz/bin/fuzz_<name> -minimize_crash=1 -runs=10000 FILE)
# and copy it into fuzz/corpus/<name>/; the normal suite replays that folder (fuzz_replay.*).
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-60}
shift || true
names=("$@")
[ ${#names[@]} -gt 0 ] || names=(scene mesh_off mesh_obj mesh_ply mesh_stl cache_entry cache_part)

CC=clang CXX=clang++ cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=RelWithDebInfo -DHYBRIDTREE_FUZZ=ON \
  -DHYBRIDTREE_TESTS=OFF -DHYBRIDTREE_BENCH=OFF
nice -n 10 cmake --build build-fuzz -j2 --target hybridtree_fuzz_all

mkdir -p build-fuzz/findings
status=0
for name in "${names[@]}"; do
  mkdir -p "build-fuzz/corpus/$name"
  echo "== fuzz_$name for ${seconds}s"
  # -timeout: one input must finish in well under a second; 10 s marks a hang. -rss_limit_mb: a
  # small file must not make the reader allocate gigabytes. -max_len: the inputs worth finding
  # fit in a few kilobytes (fuzz/fuzz_support.hpp kMaxInputBytes caps what a target reads).
  nice -n 10 "build-fuzz/bin/fuzz_$name" "build-fuzz/corpus/$name" "fuzz/corpus/$name" \
    -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -max_len=8192 \
    -artifact_prefix="build-fuzz/findings/$name-" -print_final_stats=1 || status=1
done
exit $status
