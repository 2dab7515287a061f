#!/usr/bin/env bash
# Scaling of the whole pipeline with the number of views (issue 6): renders a synthetic
# sequence of N views (`parallax synth --layout sequence`), reconstructs it with sequential
# matching, and reports wall time, peak memory and accuracy against the exact cameras.
#
#   bench/scaling.sh [N...]          # default: 100 250 500
#
# Environment: PARALLAX_BINARY (default build/parallax, then build-*/parallax), BENCH_OUT (default
# /tmp/parallax-scaling-YYYYmmdd-HHMMSS), BENCH_OVERLAP (sequential neighbours, default 10).
# Needs GNU time (/usr/bin/time; PARALLAX_BENCH_DEPS=1 scripts/install-deps.sh installs it).
set -euo pipefail

bench_name=scaling.sh
source "$(dirname "${BASH_SOURCE[0]}")/bench_common.sh"
out="${BENCH_OUT:-/tmp/parallax-scaling-$(date +%Y%m%d-%H%M%S)}"
overlap="${BENCH_OVERLAP:-10}"
counts=("$@")
[[ ${#counts[@]} -eq 0 ]] && counts=(100 250 500)
mkdir -p "$out"

# seconds and peak MiB from a `/usr/bin/time -f "%e %M"` file.
read_time() { awk '{ printf "%.1f | %.0f", $1, $2 / 1024 }' "$1"; }

echo "| views | render (s) | reconstruct wall (s) | peak memory (MiB) | registered | points | median rotation error (deg) |"
echo "|---:|---:|---:|---:|---:|---:|---:|"
for n in "${counts[@]}"; do
  run="$out/$n"
  rm -rf "$run"
  mkdir -p "$run"
  /usr/bin/time -f "%e %M" -o "$run/synth.time" \
    "$binary" synth --output "$run/images" --views "$n" --layout sequence -q >"$run/synth.log"
  /usr/bin/time -f "%e %M" -o "$run/reconstruct.time" \
    "$binary" reconstruct --images "$run/images" --output "$run/out" --pairs sequential \
    --overlap "$overlap" -q >"$run/reconstruct.log" 2>&1 || {
    echo "scaling.sh: reconstruct of $n views failed, see $run/reconstruct.log" >&2; exit 1; }
  "$binary" evaluate "$run/out/sparse/0" --gt "$run/images/synth_par.txt" --json >"$run/eval.json"
  stats="$(python3 -c '
import json, sys
e = json.load(open(sys.argv[1]))
print("%s / %s | %s | %.3f" % (e["images_registered"], e["images_gt"], e["points3D"],
                              e["rotation_error_deg"]["median"]))' "$run/eval.json")"
  render="$(awk '{ printf "%.1f", $1 }' "$run/synth.time")"
  echo "| $n | $render | $(read_time "$run/reconstruct.time") | $stats |"
done
