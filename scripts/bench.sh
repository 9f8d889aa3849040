#!/usr/bin/env bash
# Reproduces the tables of BENCHMARKS.md on this machine's default Vulkan
# device (set VK_DRIVER_FILES to pick lavapipe). JSON goes to out/bench/.
#   scripts/bench.sh               every section below
#   scripts/bench.sh SECTION...    only those: direct, reference, geometry,
#                                  image_space, volume_lines, water_photons,
#                                  pinhole
# direct: the base frame per pass at 512^2 and 1024^2; reference: photons per
# second; geometry: BVH build time and size per canonical scene; image_space:
# caustic-map passes over photon buffers 64^2/256^2/1024^2, caustic maps
# 128^2/512^2 and screens 512^2/1024^2 on ball_lens (Wyman's Figs. 6.3.7-8
# sweep); volume_lines: stage B (Hu 2010's volume caustic passes) over
# volume caustic buffers 256^2/512^2/1024^2 x screens 256^2/512^2/1024^2 on
# volume_cone (Hu's Table 2 sweep), then the line and covered-pixel counts
# (tests/suite/volume_lines.rs, ignored test `coverage_statistics`);
# water_photons: the per-pass split of Kougianos & Moustakas' Fig. 14 on
# water_pool over ccm_0 and cascade counts; loading: Scene::load per MB of
# TOML (64,000 materials and 16,000 boxes) and for a 2,000,000-triangle OBJ
# (examples/load_scene.rs). FRAMES (10) and PHOTONS (2e7) set the effort.
# pinhole: Wand & Strasser's Fig. 4 (time against sample count, filtering
# on and off) and the cost of the visibility rays on ring; SIZE (128) the
# screen; then the accuracy table (Fig. 5's strategies, the cluster count)
# from tests/suite/pinhole.rs.
set -euo pipefail
cd "$(dirname "$0")/.."
sections=("$@")
[ ${#sections[@]} -eq 0 ] && sections=(direct reference geometry image_space volume_lines water_photons pinhole loading)
wants() { [[ " ${sections[*]} " == *" $1 "* ]]; }
cargo build --release --quiet
bin=target/release/caustics
mkdir -p out/bench
$bin info | sed -n 1p  # sed reads everything: no broken pipe under pipefail

if wants direct; then
  for size in 512 1024; do
    $bin bench --pass-timing --scene assets/scenes/ball_lens.toml --technique direct --width $size --height $size \
      --frames ${FRAMES:-10} --warmup 2 --json out/bench/direct_ball_lens_$size.json
  done
fi

if wants reference; then
  for scene in ball_lens ring volume_cone; do
    $bin reference --scene assets/scenes/$scene.toml --width 256 --height 256 --photons ${PHOTONS:-20000000} \
      --out out/bench/reference_$scene.png | grep photons
  done
fi

if wants geometry; then
  for scene in assets/scenes/*.toml; do
    $bin bench --pass-timing --scene "$scene" --technique direct --width 64 --height 64 --frames 1 --warmup 0 \
      --json out/bench/geometry_$(basename "$scene" .toml).json > /dev/null
    python3 - "$scene" out/bench/geometry_$(basename "$scene" .toml).json <<'PY'
import json, sys
g = json.load(open(sys.argv[2]))["geometry"]
print(f"{sys.argv[1]}: {g['triangles']} triangles, {g['bvh_nodes']} nodes, {g['bvh_leaves']} leaves, depth {g['bvh_depth']}, {g['bvh_build_ms']:.2f} ms")
PY
  done
fi

if wants image_space; then
  # caustics_on_change stays 0 (its default): every frame recomputes the map.
  echo "| screen | photons | caustic map | caustic photons | caustic splat | caustic apply | caustic total | refractor gbuffer + refraction | frame |"
  echo "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"
  for size in 512 1024; do
    for photons in 64 256 1024; do
      for map in 128 512; do
        json=out/bench/image_space_ball_lens_${size}_p${photons}_m${map}.json
        $bin bench --pass-timing --scene assets/scenes/ball_lens.toml --technique image_space \
          --param photon_buffer_size=$photons --param caustic_map_size=$map \
          --width $size --height $size --frames ${FRAMES:-10} --warmup 2 --json $json \
          > /dev/null 2> ${json%.json}.log || { cat ${json%.json}.log; exit 1; }
    python3 - $json <<'PY'
import json, sys
b = json.load(open(sys.argv[1]))
ms = {p["name"]: p["ms"] for p in b["passes_ms"]}
caustic = ["caustic map clear", "caustic photons", "caustic splat", "caustic apply"]
p, m = int(b["params"]["photon_buffer_size"]), int(b["params"]["caustic_map_size"])
cells = [f"{ms[n]:.1f}" for n in caustic[1:]]
print(f"| {b['width']}x{b['height']} | {p}² | {m}² | " + " | ".join(cells)
    + f" | {sum(ms[n] for n in caustic):.1f}"
    + f" | {ms['refractor gbuffer'] + ms['refraction']:.1f} | {b['frame_ms']:.1f} |")
PY
      done
    done
  done
fi

if wants volume_lines; then
  # C (image_space) runs with its smallest photon buffer and caustic map:
  # only stage B's passes are tabulated.
  echo "| volume caustic buffer | screen | visibility | light view | segments | lines | composite | stage B total | frame |"
  echo "| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"
  for buffer in 256 512 1024; do
    for size in 256 512 1024; do
      json=out/bench/volume_lines_volume_cone_b${buffer}_s${size}.json
      $bin bench --pass-timing --scene assets/scenes/volume_cone.toml --technique volume_lines \
        --param volume_buffer_size=$buffer --param photon_buffer_size=64 --param caustic_map_size=64 \
        --width $size --height $size --frames ${FRAMES:-10} --warmup 2 --json $json \
        > /dev/null 2> ${json%.json}.log || { cat ${json%.json}.log; exit 1; }
      python3 - $json <<'PY'
import json, sys
b = json.load(open(sys.argv[1]))
ms = {p["name"]: p["ms"] for p in b["passes_ms"]}
stage_b = ["volume visibility", "volume clear", "volume light view", "volume segments", "volume lines", "volume composite"]
n = int(b["params"]["volume_buffer_size"])
cells = [f"{ms[k]:.1f}" for k in ["volume visibility", "volume light view", "volume segments", "volume lines", "volume composite"]]
print(f"| {n}² | {b['width']}x{b['height']} | " + " | ".join(cells)
      + f" | {sum(ms[k] for k in stage_b):.1f} | {b['frame_ms']:.1f} |")
PY
    done
  done
  cargo test --release --quiet --test suite volume_lines::coverage_statistics -- --ignored --nocapture | grep '^|'
  # Hu's Table 1: the whole frame's stage split (A airlight, C surface
  # radiance = image_space, B volume caustics, composition) at 256^2.
  echo "| scene | A airlight | C surface (image_space) | B volume caustics | composition | frame |"
  echo "| --- | ---: | ---: | ---: | ---: | ---: |"
  for scene in volume_cone smoke; do
    json=out/bench/volume_lines_stages_$scene.json
    $bin bench --pass-timing --scene assets/scenes/$scene.toml --technique volume_lines \
      --width 256 --height 256 --frames ${FRAMES:-10} --warmup 1 --json $json \
      > /dev/null 2> ${json%.json}.log || { cat ${json%.json}.log; exit 1; }
    python3 - $json $scene <<'PY'
import json, sys
b = json.load(open(sys.argv[1]))
ms = {p["name"]: p["ms"] for p in b["passes_ms"]}
a = ms["airlight"]
bb = sum(v for k, v in ms.items() if k in ("volume visibility", "volume clear", "volume light view", "volume segments", "volume lines"))
comp = ms["volume composite"] + ms["tonemap"]
c = sum(ms.values()) - a - bb - comp
print(f"| {sys.argv[2]} | {a:.1f} | {c:.1f} | {bb:.1f} | {comp:.1f} | {b['frame_ms']:.1f} |")
PY
  done
fi

if wants water_photons; then
  # Fig. 14's split: CCM raster (with the GPU water surface), tracing,
  # splat, denoise, composite, and the rest of the frame (direct passes,
  # camera refraction, tonemap). Runs: ccm_0, N, splat mode, denoiser
  # (0 none, 1 adaptive, 2 fixed), denoise passes.
  # One row: scene, then ccm_0, N, splat mode, denoiser, denoise passes.
  wp_row() {
    local scene=$1
    shift
    json=out/bench/water_photons_${scene}_c$1_n$2_s$3_d$4x$5.json
    $bin bench --pass-timing --scene assets/scenes/$scene.toml --technique water_photons \
      --param ccm_size=$1 --param cascades=$2 --param splat_mode=$3 \
      --param denoise=$4 --param denoise_passes=$5 \
      --width 256 --height 256 --frames ${FRAMES:-10} --warmup 2 --json $json \
      > ${json%.json}.log 2>&1 || { cat ${json%.json}.log; exit 1; }
    python3 - $json <<'PY'
import json, sys
b = json.load(open(sys.argv[1]))
ms = {p["name"]: p["ms"] for p in b["passes_ms"]}
p = b["params"]
own = ["water surface", "ccm raster", "photon trace", "photon splat", "caustic composite"]
denoise = sum(v for k, v in ms.items() if k.startswith("denoise "))
rest = sum(v for k, v in ms.items() if k not in own and not k.startswith("denoise "))
splat = ["differential", "paper", "fixed"][int(p["splat_mode"])]
kind = ["none", "adaptive", "fixed"][int(p["denoise"])]
if kind != "none":
    kind += f" x{int(p['denoise_passes'])}"
layout = int(p["ccm_size"]), int(p["cascades"])
threads = layout[0] ** 2 * (1 + 0.75 * (layout[1] - 1))
print(f"| {b['width']}x{b['height']} | {layout[0]}² | {layout[1]} | {splat} | {kind} | {int(threads)}"
      + f" | {ms['water surface'] + ms['ccm raster']:.1f} | {ms['photon trace']:.1f} | {ms['photon splat']:.1f}"
      + f" | {denoise:.1f} | {ms['caustic composite']:.1f} | {rest:.1f} | {b['frame_ms']:.1f} |")
PY
  }
  echo "| screen | ccm_0 | N | splat | denoise | trace threads | water surface + ccm raster | photon trace | photon splat | denoise | caustic composite | rest | frame |"
  echo "| --- | ---: | ---: | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"
  for run in "256 1 0 1 1" "512 1 0 1 1" "512 2 0 1 1" "512 4 0 1 1" "1024 1 0 1 1" "1024 4 0 1 1" \
             "512 1 2 1 1" "512 1 0 0 1" "512 1 0 2 10"; do
    wp_row water_pool $run
  done
  # ocean_large (400 m basin): the defaults (N = 2) at ccm_0 512.
  echo
  echo "ocean_large:"
  wp_row ocean_large 512 2 0 1 1
fi

if wants loading; then
  # Generated inputs, each in its own folder (load_scene counts the folder's
  # bytes as the input size).
  mkdir -p out/bench/loading/toml out/bench/loading/obj
  python3 - out/bench/loading <<'PY'
import sys
root = sys.argv[1]
head = ('[camera]\neye = [0.0, 2.0, 5.0]\ntarget = [0.0, 0.0, 0.0]\n\n'
        '[[light]]\nkind = "point"\nposition = [0.0, 5.0, 0.0]\nintensity = 10.0\n\n')
kinds = ['kind = "diffuse"\nalbedo = [0.5, 0.4, 0.3]', 'kind = "mirror"\nreflectance = 0.9',
         'kind = "dielectric"\nior = 1.5\nabsorption = [0.1, 0.2, 0.3]']
with open(f"{root}/toml/scene.toml", "w") as f:
    f.write(head)
    for i in range(64000):
        f.write(f'[[material]]\nname = "m{i}"\n{kinds[i % 3]}\n')
    for i in range(0, 64000, 4):
        f.write(f'[[object]]\nshape = "box"\nmin = [{i}.0, 0.0, 0.0]\nmax = [{i}.5, 1.0, 1.0]\n'
                f'material = "m{i}"\nrotate = [0.0, 30.0, 0.0]\n')
n = 1000  # n x n quads: 2,000,000 triangles
with open(f"{root}/obj/grid.obj", "w") as f:
    f.write("".join(f"v {i / n:.6f} 0 {j / n:.6f}\n" for j in range(n + 1) for i in range(n + 1)))
    for j in range(n):
        f.write("".join(f"f {j * (n + 1) + i + 1} {(j + 1) * (n + 1) + i + 1} {(j + 1) * (n + 1) + i + 2} {j * (n + 1) + i + 2}\n"
                        for i in range(n)))
with open(f"{root}/obj/scene.toml", "w") as f:
    f.write(head + '[[material]]\nname = "white"\nkind = "diffuse"\n\n'
            '[[object]]\nshape = "mesh"\npath = "grid.obj"\nmaterial = "white"\n')
PY
  cargo build --release --quiet --example load_scene
  target/release/examples/load_scene --repeat 3 out/bench/loading/toml/scene.toml out/bench/loading/obj/scene.toml
fi

if wants pinhole; then
  size=${SIZE:-128}
  for n in 100 1000 10000; do
    for filter in 1 0; do
      echo "samples=$n filter=$filter:"
      $bin bench --pass-timing --scene assets/scenes/ring.toml --technique pinhole --param samples=$n \
        --param filter=$filter --width $size --height $size --frames ${FRAMES:-10} --warmup 1 \
        --json out/bench/pinhole_ring_${n}_filter$filter.json | grep -E "pinhole receivers|frame interval"
    done
  done
  echo "samples=1000 visibility=0:"
  $bin bench --pass-timing --scene assets/scenes/ring.toml --technique pinhole --param samples=1000 \
    --param visibility=0 --width $size --height $size --frames ${FRAMES:-10} --warmup 1 \
    --json out/bench/pinhole_ring_1000_vis0.json | grep -E "pinhole receivers|frame interval"
  cargo test --release --test suite pinhole::ring_accuracy_table -- --ignored --nocapture | grep "^|"
fi
