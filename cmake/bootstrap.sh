#!/bin/sh
# One-step set-up for a fresh Debian 12 machine (run as root, or as a user with sudo).
#
#   cmake/bootstrap.sh demo   install missing packages, build (Release), run the main job
#   cmake/bootstrap.sh test   install missing packages, build (Release), run the test suite
#
# Only packages that are missing are installed. With CI set in the environment, compiler
# warnings are errors.
set -eu
mode=${1:-demo}
case "$mode" in demo|test) ;; *) echo "usage: $0 demo|test" >&2; exit 2 ;; esac
cd "$(dirname "$0")/.."

packages="build-essential cmake ninja-build ccache pkg-config
  libcgal-dev libtet1.5-dev libopenmesh-dev libembree-dev libeigen3-dev libtbb-dev
  nlohmann-json3-dev libcli11-dev libgtest-dev libgmock-dev libbenchmark-dev
  libmeshoptimizer-dev libpng-dev libopenexr-dev
  python3-dev pybind11-dev python3-numpy libassimp-dev"
# The test suite opens the HTML report in headless Chromium and runs the Python tests;
# pip, venv and setuptools: the test that pip installs the module into a virtual environment;
# blender: the test of the Blender add-on (apps/blender), headless.
if [ "$mode" = test ]; then
  packages="$packages chromium python3-pil python3-pytest parallel python3-distributed python3-pip python3-venv python3-setuptools python3-wheel blender"
fi

missing=""
for package in $packages; do
  dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed" || missing="$missing $package"
done

as_root() {
  if [ "$(id -u)" -eq 0 ]; then "$@"; else sudo "$@"; fi
}

# The meshes come from the libcgal-demo and assimp-testmodels packages (downloaded, not
# installed): apt needs package lists for that even when nothing is missing.
if [ -n "$missing" ] || ! apt-cache show libcgal-demo assimp-testmodels >/dev/null 2>&1; then
  as_root apt-get update
fi
if [ -n "$missing" ]; then
  echo "visproxy: installing$missing"
  as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends $missing
fi

# The test suite checks exported glTF files with the Khronos glTF validator, an npm package:
# Node.js and npm from Debian when the machine has none, the validator (pinned) into the build tree.
if [ "$mode" = test ]; then
  if ! command -v node >/dev/null 2>&1 || ! command -v npm >/dev/null 2>&1; then
    as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends nodejs npm
  fi
  if [ ! -f build/release/node/node_modules/gltf-validator/package.json ]; then
    npm install --prefix build/release/node --no-audit --no-fund --no-save gltf-validator@2.0.0-dev.3.10 ||
      echo "visproxy: warning: npm could not install gltf-validator; the test suite will report the glTF validation as skipped" >&2
  fi
fi

werror=OFF
[ -n "${CI:-}" ] && werror=ON
cmake --preset release -DVISPROXY_WARNINGS_AS_ERRORS=$werror
cmake --build --preset release

if [ "$mode" = demo ]; then
  ./build/release/apps/visproxy info build/release/meshes/bunny00.off
  mesh=build/release/meshes/bunny00.off
  out=build/release/demo/bunny00
  ./build/release/apps/visproxy build "$mesh" -o "$out"
  ./build/release/apps/visproxy verify "$mesh" "$out"
  ./build/release/apps/visproxy measure "$mesh" "$out"
  ./build/release/apps/visproxy report "$out"
  echo "visproxy: report of the bunny's proxies: $out/report.html (and report.md, recommendation.json, f_miss.svg, efficiency.svg, pictures/)"
else
  ctest --preset release
fi
