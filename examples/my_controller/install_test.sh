#!/usr/bin/env bash
# CTest `install.example_plugin` (release builds): the proof that the installed package and the
# plugins work from a user's own project. Installs the build tree into a temporary prefix, then
# configures and builds this example against that prefix (not the build tree), and runs its
# scenario with the installed `symb --plugin`; the robot must have driven.
#
#   install_test.sh BUILD_DIR
set -euo pipefail
build=$1
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
tmp=$(mktemp -d "${TMPDIR:-/tmp}/symb-install.XXXXXX")
trap 'rm -rf "$tmp"' EXIT

cmake --install "$build" --prefix "$tmp/prefix" >/dev/null
# Only public headers are installed: never the command's own (apps) nor yaml-cpp's scaffold.
if [[ -e "$tmp/prefix/include/symb/apps" || -e "$tmp/prefix/include/symb/sim/yaml_document.hpp" ]]; then
  echo "install_test: a private header was installed" >&2
  exit 1
fi
# The example finds the package by its prefix alone; the build tree is not on any path.
cmake -S "$here" -B "$tmp/build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH="$tmp/prefix" >/dev/null
cmake --build "$tmp/build"
"$tmp/prefix/bin/symb" --version
"$tmp/prefix/bin/symb" run "$here/my_controller.yaml" --plugin "$tmp/build/libmy_controller.so" \
  --out "$tmp/out" --quiet --print-hash
# summary.txt: robot,distance_m,...: the plugin's controller drove the robot (more than 50 cm in 20 s).
distance=$(awk -F, '$1 == "thymio" { print $2 }' "$tmp/out/summary.txt")
echo "distance: $distance m"
awk -v d="$distance" 'BEGIN { exit !(d > 0.5) }'
# The installed Python module imports from the prefix (its RPATH finds the libraries there).
if [[ -d "$tmp/prefix/lib/python3/dist-packages" ]]; then
  PYTHONPATH="$tmp/prefix/lib/python3/dist-packages" /usr/bin/python3 -c \
    'import symbricator, sys; sys.exit(0 if symbricator.__file__.startswith(sys.argv[1]) else 1)' "$tmp/prefix"
fi
# pkg-config gives the same libraries.
PKG_CONFIG_PATH="$tmp/prefix/lib/pkgconfig" pkg-config --exists symbricator
