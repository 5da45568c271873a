#!/usr/bin/env bash
# Whole-process figures for `make bench`: start-up time and peak memory of `cmam --help` and of
# `cmam check` on a two-triangle scene, and whole renders of the bundled scenes at 1 and 64 spp
# (wall time, CPU time, peak memory; the median of RUNS runs, RUNS_64 at 64 spp).
#
# With PBRT set to a pbrt-v3 binary, the renders run with it as well, the two programs in turn
# (cmam, pbrt, cmam, pbrt, ...), on the same scene file with the same sampler and thread count,
# and the table adds the ratios of the medians (cmam / pbrt; below 1: cmam is faster). On a
# machine shared with other work, read CPU time: wall time then includes waiting for a core.
#
# usage: scripts/process-bench.sh CMAM      (env: RUNS=5 RUNS_64=3 THREADS=nproc PBRT=)
set -euo pipefail

CMAM=${1:?usage: process-bench.sh CMAM}
RUNS=${RUNS:-5}
RUNS_64=${RUNS_64:-3}
THREADS=${THREADS:-$(nproc)}
PBRT=${PBRT:-}
ROOT=$(cd "$(dirname "$0")/.." && pwd)
if [[ -n $PBRT && ! -x $PBRT ]]; then
  echo "process-bench: PBRT=$PBRT is not an executable" >&2
  exit 1
fi

work=$(mktemp -d)
made=()  # scene copies written beside the originals (their textures are found from there)
cleanup() {
  rm -rf "$work"
  ((${#made[@]})) && rm -f "${made[@]}"
  return 0
}
trap cleanup EXIT

# One run of a command: prints "wall_s cpu_s peak_MB" (GNU time's CPU and peak resident size;
# wall time from the shell's microsecond clock). Output of the command is discarded.
measure() {
  local t0 t1 stats
  t0=$EPOCHREALTIME
  /usr/bin/time -f "%U %S %M" -o "$work/time" "$@" >/dev/null 2>"$work/stderr" || {
    echo "process-bench: failed: $*" >&2
    cat "$work/stderr" >&2
    exit 1
  }
  t1=$EPOCHREALTIME
  read -r user sys peak <"$work/time"
  awk -v a="$t0" -v b="$t1" -v u="$user" -v s="$sys" -v m="$peak" \
    'BEGIN { printf "%.4f %.2f %.1f\n", b - a, u + s, m / 1024 }'
}

# Median of each column of the lines on stdin.
medians() {
  awk '{ for (i = 1; i <= NF; i++) v[i, NR] = $i; n = NR; nf = NF }
       END {
         for (i = 1; i <= nf; i++) {
           for (j = 1; j <= n; j++) c[j] = v[i, j]
           for (j = 2; j <= n; j++) { x = c[j]; k = j - 1
             while (k >= 1 && c[k] > x) { c[k + 1] = c[k]; k-- } c[k + 1] = x }
           m = (n % 2) ? c[(n + 1) / 2] : (c[n / 2] + c[n / 2 + 1]) / 2
           printf "%s%s", m, (i < nf ? " " : "\n")
         }
       }'
}

cat >"$work/tiny.pbrt" <<'EOF'
LookAt 0 0 5  0 0 0  0 1 0
Camera "perspective" "float fov" 45
Film "image" "integer xresolution" 32 "integer yresolution" 32
WorldBegin
LightSource "point" "point from" [0 0 5] "color I" [10 10 10]
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3]
      "point P" [-1 -1 0  1 -1 0  1 1 0  -1 1 0]
WorldEnd
EOF

echo "Whole process, $(nproc) cores, $THREADS threads; medians of $RUNS runs ($RUNS_64 at 64 spp)."
echo
printf '| %-28s | %9s | %9s | %8s |\n' command "wall s" "CPU s" "peak MB"
printf '|%s|%s|%s|%s|\n' ------------------------------ ----------- ----------- ----------
for cmd in "--help" "check $work/tiny.pbrt"; do
  # shellcheck disable=SC2086
  measure "$CMAM" $cmd >/dev/null  # warm-up
  read -r wall cpu peak < <(for ((i = 0; i < RUNS; i++)); do measure "$CMAM" $cmd; done | medians)
  label="cmam ${cmd/$work\//}"
  printf '| %-28s | %9s | %9s | %8s |\n' "$label" "$wall" "$cpu" "$peak"
done
echo

# Writes COPY: SCENE with its Sampler replaced by a stratified N×N one.
with_spp() {
  local scene=$1 n=$2 copy=$3
  awk -v n="$n" '
    /^[[:space:]]*Sampler/ { skip = 1; next }
    skip && /^[[:space:]]*"/ { next }
    { skip = 0 }
    /^[[:space:]]*WorldBegin/ && !done {
      printf "Sampler \"stratified\" \"integer xsamples\" %d \"integer ysamples\" %d\n", n, n
      done = 1
    }
    { print }' "$scene" >"$copy"
}

if [[ -n $PBRT ]]; then
  printf '| %-22s | %4s | %9s | %9s | %9s | %9s | %8s | %8s | %8s | %8s |\n' scene spp "cmam wall" \
    "pbrt wall" "cmam CPU" "pbrt CPU" "cmam MB" "pbrt MB" "wall c/p" "CPU c/p"
  printf '|%s|%s|%s|%s|%s|%s|%s|%s|%s|%s|\n' ------------------------ ------ ----------- ----------- \
    ----------- ----------- ---------- ---------- ---------- ----------
else
  printf '| %-22s | %4s | %9s | %9s | %8s |\n' scene spp "wall s" "CPU s" "peak MB"
  printf '|%s|%s|%s|%s|%s|\n' ------------------------ ------ ----------- ----------- ----------
fi
for scene in "$ROOT"/scenes/*.pbrt "$ROOT"/scenes/paper/*.pbrt; do
  name=${scene#"$ROOT"/scenes/}
  for spp in 1 64; do
    n=$([[ $spp == 1 ]] && echo 1 || echo 8)
    runs=$([[ $spp == 1 ]] && echo "$RUNS" || echo "$RUNS_64")
    # Beside the original, so that its relative paths resolve as they do for the original.
    copy="$(dirname "$scene")/.bench-$$-$n-$(basename "$scene")"
    made+=("$copy")
    with_spp "$scene" "$n" "$copy"
    c_cmd=("$CMAM" render "$copy" --threads "$THREADS" -o "$work/cmam.exr")
    p_cmd=("$PBRT" --nthreads "$THREADS" --quiet --outfile "$work/pbrt.exr" "$copy")
    : >"$work/c"
    : >"$work/p"
    measure "${c_cmd[@]}" >/dev/null
    [[ -n $PBRT ]] && measure "${p_cmd[@]}" >/dev/null
    for ((i = 0; i < runs; i++)); do
      measure "${c_cmd[@]}" >>"$work/c"
      [[ -n $PBRT ]] && measure "${p_cmd[@]}" >>"$work/p"
    done
    read -r cw cc cm < <(medians <"$work/c")
    if [[ -n $PBRT ]]; then
      read -r pw pc pm < <(medians <"$work/p")
      ratio=$(awk -v a="$cw" -v b="$pw" 'BEGIN { printf "%.2f", a / b }')
      cpu_ratio=$(awk -v a="$cc" -v b="$pc" 'BEGIN { printf "%.2f", (b > 0 ? a / b : 0) }')
      printf '| %-22s | %4s | %9s | %9s | %9s | %9s | %8s | %8s | %8s | %8s |\n' "$name" "$spp" "$cw" \
        "$pw" "$cc" "$pc" "$cm" "$pm" "$ratio" "$cpu_ratio"
    else
      printf '| %-22s | %4s | %9s | %9s | %8s |\n' "$name" "$spp" "$cw" "$cc" "$cm"
    fi
  done
done
