#!/usr/bin/env bash
# Reproduces the tables of BENCHMARKS.md on this machine's default Vulkan
# device (set VK_DRIVER_FILES to pick lavapipe): the `direct` base frame per
# pass at 512^2 and 1024^2, reference photons per second, BVH build time and
# size per canonical scene. JSON goes to out/bench/.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --quiet
bin=target/release/caustics
mkdir -p out/bench
$bin info | head -1

for size in 512 1024; do
  $bin bench --scene assets/scenes/ball_lens.toml --technique direct --width $size --height $size \
    --frames ${FRAMES:-10} --warmup 2 --json out/bench/direct_ball_lens_$size.json
done

for scene in ball_lens ring volume_cone; do
  $bin reference --scene assets/scenes/$scene.toml --width 256 --height 256 --photons ${PHOTONS:-20000000} \
    --out out/bench/reference_$scene.png | grep photons
done

for scene in assets/scenes/*.toml; do
  $bin bench --scene "$scene" --technique direct --width 64 --height 64 --frames 1 --warmup 0 \
    --json out/bench/geometry_$(basename "$scene" .toml).json > /dev/null
  python3 - "$scene" out/bench/geometry_$(basename "$scene" .toml).json <<'PY'
import json, sys
g = json.load(open(sys.argv[2]))["geometry"]
print(f"{sys.argv[1]}: {g['triangles']} triangles, {g['bvh_nodes']} nodes, {g['bvh_leaves']} leaves, depth {g['bvh_depth']}, {g['bvh_build_ms']:.2f} ms")
PY
done
