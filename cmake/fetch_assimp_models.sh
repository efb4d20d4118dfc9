#!/bin/sh
# Unpacks Debian's assimp-testmodels package (Assimp's own test models: glTF 2.0, FBX,
# Collada, 3DS, ..., and an `invalid/` folder of broken files) into a folder.
#
#   fetch_assimp_models.sh DEST_DIR
#
# The package is downloaded with `apt-get download` and unpacked with `dpkg-deb -x`, never
# installed; the models end up in DEST_DIR/models. DEST_DIR/.unpacked marks a finished run.
set -eu
dest=$1
[ -e "$dest/.unpacked" ] && exit 0
mkdir -p "$dest"
deb=$(ls "$dest"/assimp-testmodels_*.deb 2>/dev/null | head -n 1 || true)
if [ -z "$deb" ]; then
  (cd "$dest" && apt-get download assimp-testmodels >/dev/null 2>apt-get.log) || {
    cat "$dest/apt-get.log" >&2
    echo "fetch_assimp_models: 'apt-get download assimp-testmodels' failed; run 'apt-get update' first" >&2
    exit 1
  }
  deb=$(ls "$dest"/assimp-testmodels_*.deb | head -n 1)
fi
rm -rf "$dest/unpacked" "$dest/models"
dpkg-deb -x "$deb" "$dest/unpacked"
mv "$dest/unpacked/usr/share/assimp/models" "$dest/models"
rm -rf "$dest/unpacked"
touch "$dest/.unpacked"
