#!/usr/bin/env bash
# Track recovery (issue 20): how much of the true tracks each mapper recovers on synthetic
# scenes whose verified matches were damaged (a share dropped, a share replaced by the
# nearest keypoint of another point), side by side on the same database.
#
#   bench/track_recovery.sh [DROP:WRONG ...]      # default: 0.3:0 0.3:0.05 0.5:0.1
#
# Per damage setting: build-X/bench/track_recovery make, then `parallax mapper` of this build
# with its defaults and with COLMAP's completion, merging and re-triangulation on
# (--tri-complete-hops 5 --tri-merge 1 --tri-retriangulate-ratio 0.2), then of
# PARALLAX_BASELINE_BINARY (an earlier build, optional), then COLMAP 3.8's mapper when
# installed; each model scored by track_recovery score. Needs -DPARALLAX_BUILD_BENCHMARKS=ON (the default).
# Results in ${PARALLAX_BENCH_OUT:-/tmp/parallax_track_recovery}/results.jsonl.
set -euo pipefail
bench_name=track_recovery
source "$(dirname "$0")/bench_common.sh"
out="${PARALLAX_BENCH_OUT:-/tmp/parallax_track_recovery}"
tool="$(dirname "$binary")/bench/track_recovery"
[[ -x "$tool" ]] || { echo "$bench_name: $tool not built" >&2; exit 1; }
settings=("$@")
[[ ${#settings[@]} -eq 0 ]] && settings=(0.3:0 0.3:0.05 0.5:0.1)
mkdir -p "$out"
results="$out/results.jsonl"

# score NAME DROP WRONG MODEL: one JSON line per model into results.jsonl.
score() {
  local name=$1 drop=$2 wrong=$3 model=$4
  if [[ ! -d "$model" ]]; then
    echo "{\"mapper\": \"$name\", \"drop\": $drop, \"wrong\": $wrong, \"failed\": true}" | tee -a "$results"
    return
  fi
  "$tool" score "$scene" "$model" |
    python3 -c 'import json,sys; row={"mapper": sys.argv[1], "drop": float(sys.argv[2]), "wrong": float(sys.argv[3])}; row.update(json.loads(sys.stdin.read())); print(json.dumps(row))' \
      "$name" "$drop" "$wrong" | tee -a "$results"
}

# map NAME BINARY ARGS...: the mapper on a copy of the scene's database, scored.
map() {
  local name=$1 mapper_binary=$2
  shift 2
  local run="$scene/$name"
  rm -rf "$run"
  mkdir -p "$run"
  cp "$scene/database.db" "$run/database.db"
  "$mapper_binary" mapper --database "$run/database.db" --image-path "$scene" --output "$run" \
    --ba-threads 2 "$@" \
    >"$run/log" 2>&1 || true
  score "$name" "$drop" "$wrong" "$run/sparse/0"
}

for setting in "${settings[@]}"; do
  drop=${setting%%:*}
  wrong=${setting##*:}
  scene="$out/drop${drop}_wrong${wrong}"
  "$tool" make "$scene" --drop "$drop" --wrong "$wrong"
  map parallax "$binary"
  map parallax_completion "$binary" --tri-complete-hops 5 --tri-merge 1 --tri-retriangulate-ratio 0.2
  if [[ -n "${PARALLAX_BASELINE_BINARY:-}" ]]; then map baseline "$PARALLAX_BASELINE_BINARY"; fi
  if command -v colmap >/dev/null; then
    mkdir -p "$scene/colmap"
    cp "$scene/database.db" "$scene/colmap/database.db"
    colmap mapper --database_path "$scene/colmap/database.db" --image_path "$scene" \
      --output_path "$scene/colmap" --Mapper.num_threads 2 >"$scene/colmap/log" 2>&1 || true
    score colmap "$drop" "$wrong" "$scene/colmap/0"
  fi
done
