#!/usr/bin/env bash
# The training renders of profile-guided optimisation (`make`; CMAM_PGO in CMakeLists.txt): the
# instrumented cmam renders the bundled scenes small with their own settings, the demo with each
# footprint method and filter, and the scenes of scripts/pgo/: the common materials and lights
# (path traced, and as bdpt), an environment map (directlighting) and participating media
# (volpath), so that the profile records what renders spend their time on. About 20 s on 2 cores
# (37 s of CPU time). The profile of an earlier training is removed first.
#   usage: scripts/pgo-train.sh CMAM PROFILE_DIR
set -euo pipefail
CMAM=${1:?usage: pgo-train.sh CMAM PROFILE_DIR}
PROFILE=${2:?usage: pgo-train.sh CMAM PROFILE_DIR}
ROOT=$(cd "$(dirname "$0")/.." && pwd)
work=$(mktemp -d)
# Variants written beside the originals (their texture paths are relative).
bdpt="$ROOT/scripts/pgo/.bdpt-$$.pbrt" exr="$ROOT/scripts/pgo/.exr-$$.pbrt"
trap 'rm -rf "$work" "$bdpt" "$exr"' EXIT

mkdir -p "$PROFILE"
find "$PROFILE" -name '*.gcda' -delete
render() { "$CMAM" render "$@" --quiet -o "$work/out.exr" >/dev/null; }

for scene in "$ROOT"/scenes/*.pbrt "$ROOT"/scenes/paper/*.pbrt; do
  render "$scene" --resolution 200 --spp 16
done
for method in "--filter area" "--filter trilinear" "--filter sat" "--lod cones-aniso" \
  "--lod cmam" "--lod cmam --cmam-2d --filter area"; do
  # shellcheck disable=SC2086  # the method is two or four words
  render "$ROOT/scenes/demo.pbrt" --resolution 200 --spp 4 $method
done
for scene in materials envmap media; do
  render "$ROOT/scripts/pgo/$scene.pbrt" --resolution 200 --spp 16
done
# Code a training does not run is optimised for size, so the usual inputs must all be read: the
# environment map again from an RGB EXR (the format of most real maps), made here, and the
# noisy photograph as a float texture (bump and roughness) too.
"$CMAM" render "$ROOT/scripts/pgo/materials.pbrt" --resolution 128 --spp 1 --quiet \
  -o "$work/sky.exr" >/dev/null
sed -e "s#\"../../scenes/textures/gravel.png\"#\"$work/sky.exr\"#" \
  "$ROOT/scripts/pgo/envmap.pbrt" >"$exr"
render "$exr" --resolution 200 --spp 16
sed 's/"path"/"bdpt"/' "$ROOT/scripts/pgo/materials.pbrt" >"$bdpt"
# (bdpt's warning kept out of the build's output, but shown with any error)
render "$bdpt" --resolution 200 --spp 16 2>"$work/bdpt.err" || { cat "$work/bdpt.err" >&2; exit 1; }
