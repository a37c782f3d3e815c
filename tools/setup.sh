#!/usr/bin/env bash
# Installs HybridTree's build dependencies from Debian's packages and extracts the real test
# meshes shipped by libcgal-demo into data/meshes/ (git-ignored). Idempotent: packages already
# present are not reinstalled and meshes already extracted are kept.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)

# libopenvdb-dev (10.0.1; it pulls in libopenvdb10.0, libblosc-dev, libimath-dev, liblog4cplus) is
# for the OpenVDB peer benchmark only (bench/vdb_peer_bench.cpp); its headers also include Boost's,
# which libcgal-demo already brings through libcgal-dev.
packages=(cmake g++ make libtbb-dev libembree-dev libglm-dev libopenmesh-dev nlohmann-json3-dev
          libcli11-dev libgtest-dev libgmock-dev libbenchmark-dev libhwy-dev libstb-dev libcgal-demo
          pybind11-dev python3-dev python3-numpy python3-pytest libopenvdb-dev)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "setup: installing ${missing[*]}"
  sudo=""; [ "$(id -u)" -ne 0 ] && sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

# The meshes the examples, tests and benchmarks use (all closed).
meshes=(bunny00.off armadillo.off refined_elephant.off eight.off knot2.off sphere.off)
dest="$here/data/meshes"
mkdir -p "$dest"
need=()
for m in "${meshes[@]}"; do [ -s "$dest/$m" ] || need+=("data/meshes/$m"); done
if ((${#need[@]})); then
  archive=/usr/share/doc/libcgal-dev/data.tar.gz
  [ -f "$archive" ] || { echo "setup: $archive not found (is libcgal-demo installed?)" >&2; exit 1; }
  tmp=$(mktemp -d)
  trap 'rm -rf "$tmp"' EXIT
  tar -xzf "$archive" -C "$tmp" "${need[@]}"
  for m in "${need[@]}"; do mv "$tmp/$m" "$dest/"; done
  echo "setup: extracted ${#need[@]} meshes into data/meshes/"
fi

# Igea at the paper's 67,170 triangles, from the meshes shared beside the checkout (../shared,
# their sources in its SOURCES.md): examples/bowl.json and examples/restoration.json name it.
shared="$here/../shared/data/meshes"
for m in igea-67k.ply; do
  if [ ! -s "$dest/$m" ] && [ -s "$shared/$m" ]; then cp "$shared/$m" "$dest/$m"; echo "setup: copied $m into data/meshes/"; fi
done
