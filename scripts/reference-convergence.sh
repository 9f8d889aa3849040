#!/usr/bin/env bash
# Convergence of the ground truth: runs `caustics reference` for SECONDS on
# each scene at SIZE² and prints, per scene, the remaining noise (the RMS
# standard error of the pixels' mean over passes, relative to the mean
# pixel) after 10, 30 and SECONDS seconds, and when it first fell below
# NOISE percent. Usage: scripts/reference-convergence.sh [SECONDS] [SIZE] [NOISE]
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-60}
size=${2:-128}
noise=${3:-50}
cargo build --release --quiet
out=out/convergence
mkdir -p "$out"
printf '| scene | passes | photons/s | noise at 10 s | at 30 s | at %s s | first below %s%% |\n| --- | ---: | ---: | ---: | ---: | ---: | ---: |\n' "$seconds" "$noise"
for scene in ball_lens ball_lens_top water_pool volume_cone; do
  log="$out/$scene.log"
  target/release/caustics reference --scene "assets/scenes/$scene.toml" --width "$size" --height "$size" \
    --seconds "$seconds" --out "$out/$scene.png" >"$log.out" 2>"$log"
  # Lines: "<photons> photons, pass <n> at <t> s, r <r> m, noise <x>%".
  awk -v lim="$noise" -v s="$seconds" -v name="$scene" -v rate="$(grep -o '[0-9.]* M photons/s' "$log.out")" '
    / pass / { t = $6 + 0; n = $NF; sub("%", "", n); p = $4 + 0
               if (t <= 10) a = n; if (t <= 30) b = n; c = n
               if (first == "" && n != "-" && n + 0 <= lim) first = t " s" }
    END { printf "| `%s` | %d | %s | %s%% | %s%% | %s%% | %s |\n", name, p, rate, a, b, c, (first == "" ? "not reached" : first) }' "$log"
done
