#!/usr/bin/env bash
# Renders a small evaluation (one scene failing, which the report lists), opens its index.html in
# headless Chromium at 1280 px, and checks that every image loaded, that no two boxes of the
# page (captions, images, plot labels, tables) overlap, that the page is no wider than the
# window, and that a screenshot of the page is not blank.
#   usage: report_test.sh CMAM IMAGE_STATS SCENES_DIR WORK_DIR
set -euo pipefail
cmam=$1 stats=$2 scenes=$3 work=$4
browser=$(command -v chromium || command -v chromium-browser || true)
if [[ -z $browser ]]; then
  echo "report test: Chromium is not installed (make test installs Debian's chromium package)" >&2
  exit 1
fi
rm -rf "$work"
mkdir -p "$work"
printf 'Camera "perspective"\nWorldBegin\nShape "nope"\nWorldEnd\n' >"$work/broken.pbrt"
methods=none,differentials+trilinear,differentials+ewa,differentials+area,cones+trilinear,cones-aniso+ewa,cmam+trilinear,cmam+sat,cmam-pixel-hull+trilinear
rc=0
"$cmam" eval "$scenes/paper/scene1.pbrt" "$work/broken.pbrt" --methods $methods --spp 1 \
  --reference-spp 4 -o "$work/report" --quiet 2>"$work/eval.err" || rc=$?
[[ $rc != 0 ]] || { echo "report test: eval must exit non-zero when a scene fails" >&2; exit 1; }
grep -q 'broken.pbrt is skipped' "$work/eval.err" || { echo "report test: no message for the failed scene" >&2; exit 1; }
grep -q 'broken.pbrt' "$work/report/index.html" || { echo "report test: the failed scene is not listed" >&2; exit 1; }
flags=(--headless --no-sandbox --disable-gpu --disable-quic --no-first-run --disable-background-networking
       --disable-component-update --disable-sync --user-data-dir="$work/profile" --virtual-time-budget=5000)
dom=$("$browser" "${flags[@]}" --window-size=1280,1000 --dump-dom "file://$work/report/index.html" 2>/dev/null)
ok=$(grep -o 'data-images-ok="[0-9]*"' <<<"$dom" | grep -o '[0-9]*' || true)
broken=$(grep -o 'data-images-broken="[0-9]*"' <<<"$dom" | grep -o '[0-9]*' || true)
echo "images loaded: ${ok:-?}, broken: ${broken:-?}"
# The ground truth and its texture AOV, then per method the image and two heat maps.
[[ -n $ok && $ok -ge 29 && $broken == 0 ]] || { echo "report test: images did not all load" >&2; exit 1; }
grep -q '<svg class="plot"' <<<"$dom" || { echo "report test: no error/time plot" >&2; exit 1; }
overlaps=$(grep -o 'data-overlaps="[0-9]*"' <<<"$dom" | grep -o '[0-9]*' || true)
overflow=$(grep -o 'data-overflow-x="[0-9]*"' <<<"$dom" | grep -o '[0-9]*' || true)
echo "overlapping boxes: ${overlaps:-?}, page wider than the window by: ${overflow:-?} px"
if [[ $overlaps != 0 || $overflow != 0 ]]; then
  grep -o 'data-first-overlap="[^"]*"' <<<"$dom" >&2 || true
  echo "report test: the layout overlaps or overflows at 1280 px" >&2
  exit 1
fi
"$browser" "${flags[@]}" --window-size=1280,1000 --screenshot="$work/shot.png" "file://$work/report/index.html" \
  >/dev/null 2>&1
read -r w h mean sd < <("$stats" "$work/shot.png")
echo "screenshot ${w}x${h}, luminance mean $mean, stddev $sd"
awk -v sd="$sd" 'BEGIN { exit !(sd > 0.02) }' || { echo "report test: the screenshot is blank" >&2; exit 1; }
rm -rf "$work"
