#!/usr/bin/env bash
# The hard scenes of issue 58 side by side: `parallax synth --layout street | weak | twin`
# reconstructed by Parallax, COLMAP 3.8 (Debian's `colmap`, when installed) and COLMAP 4.2
# (../shared/tools/colmap4/bin/colmap or $COLMAP4: its incremental `mapper` and its
# `global_mapper`), each with the scene's known PINHOLE intrinsics, exhaustive matching and
# $THREADS threads. One line per tool and scene: the models and their sizes, then for every
# model together (`parallax evaluate` against the scene's gt/) the median and largest rotation
# error, the largest centre error in % of the scene's scale, the views more than 1 % off (a
# view placed on the other twin is off by the temples' spacing) and the wall time.
#
# Usage: bench/hard_scenes.sh [WORK_DIR] (default /tmp/parallax_hard_scenes; scenes rendered
# once and kept). Environment: VIEWS (30; twin 40), THREADS (2), LAYOUTS ("street weak twin").
set -euo pipefail
bench_name=hard_scenes.sh
source "$(dirname "$0")/bench_common.sh"
work="${1:-/tmp/parallax_hard_scenes}"
threads="${THREADS:-2}"
layouts="${LAYOUTS:-street weak twin}"
colmap38="$(command -v colmap || true)"
colmap42="${COLMAP4:-$repo/../shared/tools/colmap4/bin/colmap}"
[[ -x "$colmap42" ]] || colmap42=""
mkdir -p "$work"

# evaluate TOOL SCENE SECONDS MODEL_DIRS...: the line of the table.
evaluate() {
  local tool=$1 scene=$2 seconds=$3
  shift 3
  local jsons=()
  for model in "$@"; do
    "$binary" evaluate "$model" --gt "$work/$scene/gt" --json -q > "$model.eval.json" 2>/dev/null &&
      jsons+=("$model.eval.json")
  done
  python3 - "$tool" "$scene" "$seconds" "${jsons[@]}" <<'EOF'
import json, sys
tool, scene, seconds, files = sys.argv[1], sys.argv[2], float(sys.argv[3]), sys.argv[4:]
sizes, rotations, centres, off, total = [], [], [], 0, None
for f in files:
    d = json.load(open(f))
    total = d["images_gt"]
    registered = [i for i in d["images"] if i["registered"]]
    sizes.append(len(registered))
    for i in registered:
        rotations.append(i["rotation_error_deg"])
        centres.append(100 * i["center_error_relative"])
        off += i["center_error_relative"] > 0.01
rotations.sort()
median = rotations[len(rotations) // 2] if rotations else float("nan")
print(f"{scene:7s} {tool:16s} models {len(sizes)} {'+'.join(map(str, sorted(sizes, reverse=True))) or '-':>9s}"
      f" of {total}  rotation {median:.4f} / {max(rotations, default=float('nan')):.4f} deg"
      f"  centre max {max(centres, default=float('nan')):8.3f} %  off {off:2d}  {seconds:6.1f} s")
EOF
}

# colmap_run NAME BINARY EXTRACTION_PREFIX MATCHING_PREFIX MAPPER SCENE
colmap_run() {
  local name=$1 colmap=$2 extraction=$3 matching=$4 mapper=$5 scene=$6
  local out="$work/$scene.$name" images="$work/$scene"
  rm -rf "$out" && mkdir -p "$out/sparse"
  local params
  params=$(awk 'NR==1{f=$1; cx=$3} NR==2{cy=$3} END{print f "," f "," cx "," cy}' "$images/K.txt")
  local start=$SECONDS
  {
    "$colmap" feature_extractor --database_path "$out/db.db" --image_path "$images" \
      --ImageReader.single_camera 1 --ImageReader.camera_model PINHOLE \
      --ImageReader.camera_params "$params" "--$extraction.num_threads" "$threads" \
      "--$extraction.use_gpu" 0
    "$colmap" exhaustive_matcher --database_path "$out/db.db" "--$matching.num_threads" "$threads" \
      "--$matching.use_gpu" 0
    if [[ $mapper == global_mapper ]]; then
      "$colmap" global_mapper --database_path "$out/db.db" --image_path "$images" \
        --output_path "$out/sparse"
    else
      "$colmap" mapper --database_path "$out/db.db" --image_path "$images" \
        --output_path "$out/sparse" --Mapper.num_threads "$threads" \
        --Mapper.ba_refine_focal_length 0 --Mapper.ba_refine_extra_params 0
    fi
  } > "$out/log.txt" 2>&1 || echo "$bench_name: $name failed on $scene (see $out/log.txt)" >&2
  evaluate "$name" "$scene" $((SECONDS - start)) "$out"/sparse/*/
}

for scene in $layouts; do
  views="${VIEWS:-30}"
  [[ $scene == twin && -z "${VIEWS:-}" ]] && views=40
  if [[ ! -f "$work/$scene/K.txt" ]]; then
    "$binary" synth --layout "$scene" --views "$views" --output "$work/$scene" --threads "$threads" \
      -q > /dev/null
  fi
  out="$work/$scene.parallax"
  rm -rf "$out"
  start=$(date +%s.%N)
  "$binary" reconstruct --images "$work/$scene" --output "$out" --intrinsics "$work/$scene/K.txt" \
    --threads "$threads" -q > "$out.log" 2>&1 || true
  seconds=$(python3 -c "import time; print(time.time() - $start)")
  evaluate parallax "$scene" "$seconds" "$out"/sparse/*/
  if [[ -n "$colmap38" ]]; then
    colmap_run colmap3.8 "$colmap38" SiftExtraction SiftMatching mapper "$scene"
  fi
  if [[ -n "$colmap42" ]]; then
    colmap_run colmap4.2 "$colmap42" FeatureExtraction FeatureMatching mapper "$scene"
    colmap_run colmap4.2-global "$colmap42" FeatureExtraction FeatureMatching global_mapper "$scene"
  fi
done
