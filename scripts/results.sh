#!/usr/bin/env bash
# Regenerates docs/results.md: `cmam eval` over the paper's scenes and the other bundled scenes
# with every method, plus the machine it ran on. The full report lands in out/results/.
#   usage: scripts/results.sh [CMAM_BINARY]
set -euo pipefail
cd "$(dirname "$0")/.."
CMAM=${1:-build/release/app/cmam}
OUT=out/results
REF=${REFERENCE_SPP:-1024}
scenes=(scenes/paper/scene1.pbrt scenes/paper/scene2.pbrt scenes/paper/scene3.pbrt scenes/paper/scene4.pbrt
        scenes/demo.pbrt scenes/spheres.pbrt scenes/mesh.pbrt)
cmd="$CMAM eval ${scenes[*]} --spp 1,4,16 --reference-spp $REF -o $OUT"
start=$(date -u +%Y-%m-%dT%H:%MZ)
$cmd
cpu=$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ *//')
{
  echo "# Results"
  echo
  echo "Every footprint method against the ground truth, on the paper's four test scenes and the other"
  echo "bundled scenes. Produced by \`make results\` (scripts/results.sh), i.e."
  echo
  echo '```'
  echo "$cmd"
  echo '```'
  echo
  echo "Machine: $(nproc) cores ($cpu), $(free -g | awk '/Mem:/ {print $2}') GB, $(. /etc/os-release && echo "$PRETTY_NAME");"
  echo "run started $start. Render times are wall-clock seconds on all cores; they vary by about ±20% between runs here."
  echo
  echo "* RMSE, PSNR and SSIM compare the rendered image with the ground truth ($REF stratified jittered"
  echo "  samples per pixel, point-sampled textures) in linear RGB."
  echo "* *off edges* keeps the pixels where an untextured render at the same spp agrees with the untextured ground truth."
  echo "* *texture* compares the unlit texture AOV of the first non-specular hit."
  echo "* Methods: \`none\` point-samples; \`differentials\` / \`cones\` / \`cones-aniso\` are ray differentials and ray cones;"
  echo "  \`cmam\` is the paper's module (scanline tags, average on a miss, conjugate ellipse, adjacency check);"
  echo "  \`cmam-literal\` drops the adjacency check (the paper's literal matching); \`cmam-point\` point-samples on"
  echo "  a miss; \`cmam-pixel-hull\` uses pixel tags with the paper's Section 4 convex hull weighting;"
  echo "  \`cmam2d\` is the 2-D CMAM (the left neighbour and the sample above, beyond the paper)."
  echo "* Filters: \`trilinear\` (MIP), \`sat\` (summed-area table of the footprint's bounding box), \`ewa\`"
  echo "  (elliptical Gaussian), and \`area\`, the exact mean over each sample's own parallelogram"
  echo "  (docs/algorithms.md §5.2): the box-filtered pixel that the ground truth converges to."
  echo
  sed -n '/^| scene |/,$p' "$OUT/results.md"
} > docs/results.md.tmp
mv docs/results.md.tmp docs/results.md
echo "docs/results.md written; report: $OUT/index.html"
