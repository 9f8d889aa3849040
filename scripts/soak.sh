#!/usr/bin/env bash
# Soak test (issue 18; not part of the suite): DIRECT_FRAMES (10,000) frames
# of `direct` and CAUSTICS_FRAMES (500) of each caustics technique at SIZE²
# (32), time advancing 1/60 s a frame (animated scenes move), two frames in
# flight, with validation and synchronization validation on (any error
# fails the run). `caustics bench --memory-samples SAMPLES` (30) samples,
# evenly over the timed frames (after WARMUP, 10, untimed) and with no frame
# in flight:
# - what the renderer owns, counted where it is allocated (vk/host_memory.rs):
#   the Rust heap in use, the host memory of its Vulkan objects (allocation
#   callbacks) and gpu-allocator's live device memory. Each must stay flat:
#   max over min of the samples at most 1 + TOL (0.01).
# - the host's RSS after glibc's malloc_trim returned the arenas' free
#   pages, which also holds what the driver and the validation layer keep for
#   themselves (a leak the renderer's use causes inside the driver shows only
#   here). Its floor must stay flat: the least sample of the last third at
#   most 1 + TOL times the least of the first third. Not max/min: lavapipe
#   keeps a finished scene's rasteriser bins until it reuses the scene (4.5
#   MiB on water_pool's 18,770 triangles), so single samples rise and fall by MiBs
#   while the memory in use does not grow (BENCHMARKS.md "Soak").
# Without CountingAllocator (a library build) the Rust heap is "not counted"
# and left out of the verdict.
# Prints a table (BENCHMARKS.md, "Soak") with the RSS's max/min, floor rise
# and least-squares slope, and the untrimmed RSS's max/min for comparison;
# JSON in out/soak/.
#   scripts/soak.sh                    everything at the default counts
#   DIRECT_FRAMES=2000 CAUSTICS_FRAMES=50 scripts/soak.sh direct image_space
# BIN picks the binary (default target/release/caustics, built if missing).
set -euo pipefail
cd "$(dirname "$0")/.."
DIRECT_FRAMES=${DIRECT_FRAMES:-10000}
CAUSTICS_FRAMES=${CAUSTICS_FRAMES:-500}
SIZE=${SIZE:-32}
SAMPLES=${SAMPLES:-30}
TOL=${TOL:-0.01}
BIN=${BIN:-target/release/caustics}
[ "$SAMPLES" -ge 3 ] || { echo "soak.sh: SAMPLES=$SAMPLES: the floor compares thirds, so at least 3" >&2; exit 2; }
[ -x "$BIN" ] || cargo build --release --quiet
out=out/soak
mkdir -p "$out"
techniques=("$@")
[ ${#techniques[@]} -eq 0 ] && techniques=(direct image_space volume_lines water_photons beams pinhole)

# The scene each technique soaks on (animated where the technique allows)
# and small maps and buffers: a leak check, not a benchmark (at their
# defaults the caustics techniques take 0.4-5 s a frame on lavapipe).
scene_of() {
    case "$1" in
        direct | image_space | beams) echo assets/scenes/gemstone.toml ;;
        volume_lines) echo assets/scenes/volume_cone.toml ;;
        water_photons) echo assets/scenes/water_pool.toml ;;
        pinhole) echo assets/scenes/ring.toml ;;
        *) echo "soak.sh: unknown technique $1" >&2; exit 2 ;;
    esac
}
params_of() {
    local p="shadow_map_size=256"
    case "$1" in
        image_space) p="$p photon_buffer_size=64 caustic_map_size=64" ;;
        volume_lines) p="$p photon_buffer_size=64 caustic_map_size=64 volume_buffer_size=64 airlight_steps=16" ;;
        water_photons) p="$p ccm_size=64" ;;
        beams) p="$p light_view_size=64 grid_size=4" ;;
        pinhole) p="$p samples=60 cube_size=16" ;;
    esac
    for x in $p; do printf -- '--param %s ' "$x"; done
}

echo "| technique | scene | frames | frame ms | Rust heap (max/min) | Vulkan host memory (max/min) | device memory (max/min) | host RSS first → last (max/min) | RSS floor rise | RSS trend | untrimmed RSS (max/min) | flat |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|"
failed=0
for t in "${techniques[@]}"; do
    frames=$CAUSTICS_FRAMES
    [ "$t" = direct ] && frames=$DIRECT_FRAMES
    scene=$(scene_of "$t")
    json="$out/$t.json"
    log="$out/$t.log"
    # shellcheck disable=SC2046
    if ! "$BIN" bench --technique "$t" --scene "$scene" --width "$SIZE" --height "$SIZE" \
        $(params_of "$t") --frames "$frames" --warmup "${WARMUP:-10}" --memory-samples "$SAMPLES" --validate-sync \
        --json "$json" >"$log" 2>&1; then
        echo "| $t | $scene | $frames | failed: $(tail -n 1 "$log") | | | | | | | | no |"
        failed=1
        continue
    fi
    python3 - "$json" "$t" "$scene" "$TOL" <<'EOF' || failed=1
import json, sys
path, technique, scene, tol = sys.argv[1], sys.argv[2], sys.argv[3], float(sys.argv[4])
r = json.load(open(path))
m = r["memory"]
mib = lambda b: f"{b / 2**20:.2f} MiB"
def spread(key):
    v = [s[key] for s in m]
    return v[0], v[-1], max(v) / max(min(v), 1)
heap = spread("rust_heap") if m[0]["rust_heap"] is not None else None
vkhost = spread("vulkan_host")
dev = spread("device_allocated")
rss = spread("host_rss")
raw = spread("host_rss_untrimmed")
# The RSS's floor: least sample of the last third over least of the first.
v = [s["host_rss"] for s in m]
third = max(len(v) // 3, 1)
floor_rise = min(v[-third:]) / min(v[:third])
owned = [x for x in (heap, vkhost, dev) if x is not None]
flat = all(x[2] <= 1 + tol for x in owned) and floor_rise <= 1 + tol
# Least-squares slope of the RSS samples over their frames: a leak is a
# trend, the allocator's and the driver's churn a scatter.
f = [s["frame"] for s in m]
fm, vm = sum(f) / len(f), sum(v) / len(v)
den = sum((x - fm) ** 2 for x in f)
slope = sum((x - fm) * (y - vm) for x, y in zip(f, v)) / den if den else 0.0
span = lambda x: f"{mib(x[0])} → {mib(x[1])} ({x[2]:.4f})"
print(f"| {technique} | {scene.split('/')[-1]} | {r['frames']} | {r['frame_ms']:.2f} | "
      f"{span(heap) if heap else 'not counted'} | {span(vkhost)} | {span(dev)} | {span(rss)} | "
      f"{floor_rise:.4f} | {slope / 1024:+.2f} KiB/frame | {raw[2]:.4f} | {'yes' if flat else 'NO'} |")
sys.exit(0 if flat else 1)
EOF
done
exit $failed
