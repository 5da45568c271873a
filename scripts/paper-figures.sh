#!/usr/bin/env bash
# Renders the paper's four test scenes (scenes/paper/) at 1 sample per pixel with the CMAM off
# (point sampling) and on (MIP, SAT, EWA), plus a 256-spp point-sampled reference of each, and
# writes the images and a table of their error against the reference.
#   usage: scripts/paper-figures.sh [CMAM_BINARY] [OUT_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
CMAM=${1:-build/release/app/cmam}
OUT=${2:-out/paper-figures}
REF_SPP=${REF_SPP:-256}
mkdir -p "$OUT"
table="$OUT/results.md"
{
  echo "# CMAM on and off: the paper's test scenes"
  echo
  echo "1 sample per pixel, scanline tags; error against a ${REF_SPP}-spp point-sampled render of the same scene"
  echo "(linear RGB). Produced by \`make paper-figures\` (scripts/paper-figures.sh)."
  echo
  echo "| scene | method | RMSE | RMSE / mean | PSNR (dB) | render (s) |"
  echo "|---|---|---|---|---|---|"
} > "$table.tmp"
for scene in scenes/paper/scene*.pbrt; do
  name=$(basename "$scene" .pbrt)
  echo "== $name" >&2
  "$CMAM" render "$scene" --spp "$REF_SPP" --lod none -o "$OUT/$name-reference.exr" --quiet
  "$CMAM" render "$scene" --spp "$REF_SPP" --lod none -o "$OUT/$name-reference.png" --quiet
  for method in off trilinear sat ewa; do
    if [[ $method == off ]]; then args=(--lod none); else args=(--lod cmam --filter "$method"); fi
    start=$(date +%s.%N)
    "$CMAM" render "$scene" --spp 1 "${args[@]}" -o "$OUT/$name-$method.exr" --quiet
    end=$(date +%s.%N)
    "$CMAM" render "$scene" --spp 1 "${args[@]}" -o "$OUT/$name-$method.png" --quiet
    read -r rmse rel psnr < <("$CMAM" compare "$OUT/$name-reference.exr" "$OUT/$name-$method.exr" --json |
      sed -E 's/.*"rmse": ([^,]*), "relative_rmse": ([^,]*), "psnr": ([^,]*),.*/\1 \2 \3/')
    label=$([[ $method == off ]] && echo "CMAM off (point sampling)" || echo "CMAM on, $method")
    printf '| %s | %s | %.5f | %.2f%% | %.2f | %.2f |\n' "$name" "$label" "$rmse" \
      "$(echo "$rel * 100" | bc -l)" "$psnr" "$(echo "$end - $start" | bc -l)" >> "$table.tmp"
  done
done
mv "$table.tmp" "$table"
echo "paper figures: $(cd "$OUT" && pwd) (table: $table)"
