#!/usr/bin/env bash
# The README's gallery: `caustics compare` on the showcase scenes, every
# technique that applies beside the ground truth with its FLIP error map,
# FLIP, relative energy and milliseconds under each (compare's contact
# sheet). Writes the sheets to docs/images/gallery_<scene>.png and the
# whole comparisons (EXRs, PNGs, report.md, report.json) to out/gallery/.
# Usage: scripts/gallery.sh [SIZE] [PHOTONS]
#   SIZE     image side in pixels (default 128: the PNGs stay small)
#   PHOTONS  reference photons (default 8388608)
# CAUSTICS=path/to/caustics uses that binary instead of building the
# release one. References are cached (compare's cache), so a rerun after a
# change to a technique traces nothing.
set -euo pipefail
cd "$(dirname "$0")/.."
size=${1:-128}
photons=${2:-8388608}
if [ -z "${CAUSTICS:-}" ]; then
  cargo build --release --quiet
  CAUSTICS=target/release/caustics
fi
# scene and the techniques shown (all: every technique that applies).
for entry in "still_life all" "light_shaft direct,volume_lines,beams" "pool_shafts water_photons"; do
  set -- $entry
  scene=$1 techniques=$2
  out=out/gallery/$scene
  "$CAUSTICS" compare --scene "assets/scenes/$scene.toml" --techniques "$techniques" \
    --width "$size" --height "$size" --photons "$photons" --frames 3 --out "$out"
  cp "$out/contact_sheet.png" "docs/images/gallery_$scene.png"
  echo "docs/images/gallery_$scene.png <- $out/contact_sheet.png"
done
