#!/usr/bin/env bash
# Extracts the real scanned meshes the tests and benchmarks use from Debian's libcgal-demo
# package (CGAL's demo data, data/meshes/*.off) into assets/scans/ (not committed). The package
# is downloaded, not installed. Idempotent: does nothing when the meshes are already there.
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
DEST=${STRATA_SCANS_DIR:-$ROOT/assets/scans}
MESHES=(camel man armadillo bear diplodocus refined_elephant)
missing=0
for m in "${MESHES[@]}"; do [ -s "$DEST/$m.off" ] || missing=1; done
[ "$missing" = 1 ] || exit 0
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
cd "$WORK"
if ! apt-get download libcgal-demo >/dev/null 2>&1; then
  SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  $SUDO apt-get update -qq
  apt-get download libcgal-demo >/dev/null
fi
dpkg -x libcgal-demo_*.deb pkg
mkdir -p "$DEST"
tar -xzf pkg/usr/share/doc/libcgal-dev/data.tar.gz -C "$WORK" $(printf 'data/meshes/%s.off ' "${MESHES[@]}")
for m in "${MESHES[@]}"; do mv "$WORK/data/meshes/$m.off" "$DEST/$m.off.tmp" && mv "$DEST/$m.off.tmp" "$DEST/$m.off"; done
echo "fetch_scans: ${MESHES[*]} in $DEST (CGAL demo data, libcgal-demo)"
