#!/usr/bin/env bash
# Every technique on every canonical scene at one size, `caustics bench --json`
# each, everything written under $OUT. Made for the lent GPU machine (see
# ../.library/device/README.md), where nothing is installed and nothing can
# be fetched: the release binary is built here and carried, and the Vulkan
# loader comes from the packages carried in .gl/ (unpacked first when present).
#
#   scripts/gpu-bench.sh                      1920x1080, 20 frames, 2 warm-up
#   WIDTH=64 HEIGHT=64 FRAMES=1 WARMUP=0 scripts/gpu-bench.sh   (lavapipe smoke run)
#
# BIN (target/release/caustics), OUT (out/gpu-bench), WIDTH, HEIGHT, FRAMES,
# WARMUP and LIMIT (seconds per run, 60) set the effort; the defaults fit in
# 8 minutes on a GPU. A technique that does not apply to a scene (water_photons
# needs water and a directional light) is reported and skipped; the script
# fails only if no run succeeded. $OUT gets three files (the device machine
# sends back only a few): info.txt (`caustics info`), summary.txt (one line
# per run: frame ms, or why it failed) and runs.tar.gz (every run's JSON and
# failure log).
set -uo pipefail
cd "$(dirname "$0")/.."

BIN=${BIN:-target/release/caustics}
OUT=${OUT:-out/gpu-bench}
WIDTH=${WIDTH:-1920}
HEIGHT=${HEIGHT:-1080}
FRAMES=${FRAMES:-20}
WARMUP=${WARMUP:-2}
LIMIT=${LIMIT:-60}

if [ -d .gl ] && ls .gl/*.deb > /dev/null 2>&1; then
  for f in .gl/*.deb; do dpkg -x "$f" /; done
  ldconfig
fi
if ! ldconfig -p 2>/dev/null | grep -q libvulkan.so.1; then
  echo "no Vulkan loader (libvulkan.so.1): carry .gl/ with libvulkan1 (../.library/device/README.md)" >&2
  exit 1
fi
nvidia_icd=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
if [ -z "${VK_DRIVER_FILES:-}" ] && [ -f "$nvidia_icd" ]; then
  export VK_DRIVER_FILES=$nvidia_icd
fi
if [ ! -x "$BIN" ]; then
  echo "$BIN not found: cargo build --release here, and carry target/release/caustics" >&2
  exit 1
fi

mkdir -p "$OUT"
runs=$(mktemp -d)
trap 'rm -rf "$runs"' EXIT
"$BIN" info > "$OUT/info.txt" 2>&1
cat "$OUT/info.txt"
techniques=$("$BIN" render --technique list | awk '/^  [a-z_]+ / && $1 != "reference" { print $1 }')
summary="$OUT/summary.txt"
: > "$summary"
ok=0
for scene in assets/scenes/*.toml; do
  name=$(basename "$scene" .toml)
  for technique in $techniques; do
    json="$runs/${technique}_${name}.json"
    log="$runs/${technique}_${name}.log"
    timeout "$LIMIT" "$BIN" bench --scene "$scene" --technique "$technique" \
      --width "$WIDTH" --height "$HEIGHT" --frames "$FRAMES" --warmup "$WARMUP" \
      --json "$json" > "$log" 2>&1
    rc=$?
    if [ $rc -eq 124 ]; then
      echo "$technique $name timed out after $LIMIT s" | tee -a "$summary"
    elif [ $rc -eq 0 ]; then
      ok=$((ok + 1))
      frame=$(sed -n 's/^ *"frame_ms": *\([0-9.e+-]*\).*/\1/p' "$json")
      echo "$technique $name ok frame_ms=${frame:-?}" | tee -a "$summary"
      rm -f "$log"
    else
      echo "$technique $name failed: $(tail -n 1 "$log")" | tee -a "$summary"
    fi
  done
done
tar -C "$runs" -czf "$OUT/runs.tar.gz" .
echo "$ok runs succeeded; results in $OUT"
[ "$ok" -gt 0 ]
