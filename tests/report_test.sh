#!/usr/bin/env bash
# Renders a small evaluation, opens its index.html in headless Chromium, and checks that every
# image loaded and that a screenshot of the page is not blank.
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
"$cmam" eval "$scenes/paper/scene1.pbrt" --methods none,differentials+ewa,cmam+trilinear --spp 1 \
  --reference-spp 4 -o "$work/report" --quiet
flags=(--headless --no-sandbox --disable-gpu --disable-quic --no-first-run --disable-background-networking
       --disable-component-update --disable-sync --user-data-dir="$work/profile" --virtual-time-budget=5000)
dom=$("$browser" "${flags[@]}" --dump-dom "file://$work/report/index.html" 2>/dev/null)
ok=$(grep -o 'data-images-ok="[0-9]*"' <<<"$dom" | grep -o '[0-9]*' || true)
broken=$(grep -o 'data-images-broken="[0-9]*"' <<<"$dom" | grep -o '[0-9]*' || true)
echo "images loaded: ${ok:-?}, broken: ${broken:-?}"
[[ -n $ok && $ok -ge 7 && $broken == 0 ]] || { echo "report test: images did not all load" >&2; exit 1; }
grep -q '<svg class="plot"' <<<"$dom" || { echo "report test: no error/time plot" >&2; exit 1; }
"$browser" "${flags[@]}" --window-size=1280,1000 --screenshot="$work/shot.png" "file://$work/report/index.html" \
  >/dev/null 2>&1
read -r w h mean sd < <("$stats" "$work/shot.png")
echo "screenshot ${w}x${h}, luminance mean $mean, stddev $sd"
awk -v sd="$sd" 'BEGIN { exit !(sd > 0.02) }' || { echo "report test: the screenshot is blank" >&2; exit 1; }
