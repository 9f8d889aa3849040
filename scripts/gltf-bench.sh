#!/usr/bin/env bash
# Loads a generated glTF of about 1,000,000 triangles and reports its load
# phases separately (issue 14): parse (Scene::load: the file read, accessors
# checked and read, node transforms, materials), world-space triangles, SAH
# BVH build, upload (device buffers), then the first `direct` frame at 256^2
# (its per-pass GPU times, and the whole command's wall clock, which adds
# device creation, pipeline compilation and the image readback), and the peak
# resident memory of the process.
#   scripts/gltf-bench.sh            release build (the figure the issue asks for)
#   PROFILE=debug scripts/gltf-bench.sh
#   GRID=N: an N x N grid of quads, 2 N^2 triangles (default 708: 1,002,528)
set -euo pipefail
cd "$(dirname "$0")/.."
profile=${PROFILE:-release}
if [ "$profile" = release ]; then cargo build --release --quiet; else cargo build --quiet; fi
bin=target/$profile/caustics
mkdir -p out/bench
glb=out/bench/grid_${GRID:-708}.glb
# The model: a rippled grid with normals and TEXCOORD_0 in one GLB, indexed
# (u32), one diffuse material. Written with the Python standard library.
python3 - "$glb" "${GRID:-708}" <<'PY'
import array, json, math, struct, sys
path, n = sys.argv[1], int(sys.argv[2])
pos, nor, uv = array.array('f'), array.array('f'), array.array('f')
for j in range(n + 1):
    v = j / n
    for i in range(n + 1):
        u = i / n
        y = 0.02 * math.sin(40.0 * u) * math.cos(40.0 * v)
        pos.extend((u - 0.5, y, v - 0.5))
        nor.extend((0.0, 1.0, 0.0))
        uv.extend((u, v))
idx = array.array('I')
for j in range(n):
    for i in range(n):
        a = j * (n + 1) + i
        idx.extend((a, a + n + 1, a + 1, a + 1, a + n + 1, a + n + 2))
chunks = [pos.tobytes(), nor.tobytes(), uv.tobytes(), idx.tobytes()]
views, off = [], 0
for c in chunks:
    views.append({"buffer": 0, "byteOffset": off, "byteLength": len(c)})
    off += len(c)
nv = (n + 1) ** 2
doc = {
    "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
    "nodes": [{"mesh": 0}],
    "materials": [{"name": "clay", "pbrMetallicRoughness": {"metallicFactor": 0.0}}],
    "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2},
                                "indices": 3, "material": 0}]}],
    "accessors": [
        {"bufferView": 0, "componentType": 5126, "count": nv, "type": "VEC3",
         "min": [-0.5, -0.02, -0.5], "max": [0.5, 0.02, 0.5]},
        {"bufferView": 1, "componentType": 5126, "count": nv, "type": "VEC3"},
        {"bufferView": 2, "componentType": 5126, "count": nv, "type": "VEC2"},
        {"bufferView": 3, "componentType": 5125, "count": len(idx), "type": "SCALAR"}],
    "bufferViews": views, "buffers": [{"byteLength": off}],
}
js = json.dumps(doc).encode()
js += b' ' * (-len(js) % 4)
total = 12 + 8 + len(js) + 8 + off
with open(path, 'wb') as f:
    f.write(struct.pack('<4sII', b'glTF', 2, total))
    f.write(struct.pack('<I4s', len(js), b'JSON') + js)
    f.write(struct.pack('<I4s', off, b'BIN\0'))
    for c in chunks:
        f.write(c)
print(f"{path}: {len(idx) // 3} triangles, {total / 2**20:.1f} MiB")
PY
$bin info | sed -n 1p
start=$(date +%s.%N)
RUST_LOG=caustics=info /usr/bin/time -f "peak resident memory: %M KiB; process CPU time %U s user + %S s system over %e s elapsed" \
  $bin render --scene "$glb" --technique direct --width 256 --height 256 --frames 1 \
  --out out/bench/gltf_first_frame.png 2>&1 | grep -E "^  |loaded in|on the device|direct at|geometry|peak|error"
end=$(date +%s.%N)
printf "whole command (process start to images written): %.0f ms\n" "$(echo "($end - $start) * 1000" | bc)"
