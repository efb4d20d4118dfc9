#!/bin/sh
# Extracts meshes from Debian's libcgal-demo package into a folder.
#
#   fetch_cgal_meshes.sh DEST_DIR MESH...
#
# The meshes live in data.tar.gz (folder data/meshes/) of libcgal-demo. The package
# is downloaded with `apt-get download` and unpacked with `dpkg-deb -x`, so nothing is
# installed and nothing depends on dpkg keeping /usr/share/doc. An installed copy of
# the archive is used when present; the downloaded package is cached in DEST_DIR.
set -eu
dest=$1
shift
mkdir -p "$dest"

missing=""
for mesh in "$@"; do
  [ -s "$dest/$mesh" ] || missing="$missing $mesh"
done
[ -n "$missing" ] || exit 0

archive=/usr/share/doc/libcgal-dev/data.tar.gz
if [ ! -s "$archive" ]; then
  cache="$dest/.libcgal-demo"
  archive="$cache/usr/share/doc/libcgal-dev/data.tar.gz"
  if [ ! -s "$archive" ]; then
    mkdir -p "$cache"
    deb=$(ls "$cache"/libcgal-demo_*.deb 2>/dev/null | head -n 1 || true)
    if [ -z "$deb" ]; then
      (cd "$cache" && apt-get download libcgal-demo >/dev/null 2>apt-get.log) || {
        cat "$cache/apt-get.log" >&2
        echo "fetch_cgal_meshes: 'apt-get download libcgal-demo' failed; run 'apt-get update' first" >&2
        exit 1
      }
      deb=$(ls "$cache"/libcgal-demo_*.deb | head -n 1)
    fi
    dpkg-deb -x "$deb" "$cache"
  fi
fi

for mesh in $missing; do
  tar -xzf "$archive" -O "data/meshes/$mesh" > "$dest/$mesh.part" || {
    rm -f "$dest/$mesh.part"
    echo "fetch_cgal_meshes: data/meshes/$mesh is not in $archive" >&2
    exit 1
  }
  mv "$dest/$mesh.part" "$dest/$mesh"
done
