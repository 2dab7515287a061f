#!/usr/bin/env bash
# Gaussian splatting's convert.py sequence (feature_extractor, exhaustive_matcher, mapper,
# model_aligner --alignment_type plane, image_undistorter; written down from the script) through
# Parallax's `colmap` drop-in and through COLMAP 4.2 ($COLMAP4, default
# ../shared/tools/colmap4/bin/colmap), both with COLMAP 4.x flags, on one folder of photos
# (default $PARALLAX_DATA/templeRing/images). Prints each tool's wall time per step and the
# registered images of each model (distorted/sparse/<k>) as COLMAP 4.2's model_analyzer reads
# them; sparse/0 is the one convert.py undistorts.
#
# Usage: bench/colmap_dropin.sh [IMAGES] [WORK_DIR]   Environment: THREADS (2).
set -euo pipefail
bench_name=colmap_dropin.sh
source "$(dirname "$0")/bench_common.sh"
data="${PARALLAX_DATA:-$repo/../shared/data}"
images="${1:-$data/templeRing/images}"
work="${2:-/tmp/parallax_colmap_dropin}"
threads="${THREADS:-2}"
colmap4="${COLMAP4:-$repo/../shared/tools/colmap4/bin/colmap}"
dropin="$(dirname "$binary")/colmap"
[[ -x "$dropin" ]] || { echo "$bench_name: no colmap drop-in beside $binary" >&2; exit 1; }

run_sequence() {
  local name=$1 colmap=$2 source="$work/$1"
  rm -rf "$source" && mkdir -p "$source/distorted/sparse"
  local times=() start
  start=$(date +%s.%N)
  step() {
    "$colmap" "$@" >> "$source/log.txt" 2>&1
    local now
    now=$(date +%s.%N)
    times+=("$1 $(python3 -c "print(round($now - $start, 1))")")
    start=$now
  }
  step feature_extractor --database_path "$source/distorted/database.db" --image_path "$images" \
    --ImageReader.single_camera 1 --ImageReader.camera_model OPENCV \
    --FeatureExtraction.use_gpu 0 --FeatureExtraction.num_threads "$threads"
  step exhaustive_matcher --database_path "$source/distorted/database.db" \
    --FeatureMatching.use_gpu 0 --FeatureMatching.num_threads "$threads"
  step mapper --database_path "$source/distorted/database.db" --image_path "$images" \
    --output_path "$source/distorted/sparse" --Mapper.ba_global_function_tolerance=0.000001 \
    --Mapper.num_threads "$threads"
  step model_aligner --input_path "$source/distorted/sparse/0" \
    --database_path "$source/distorted/database.db" --alignment_max_error 0.1 \
    --alignment_type plane --output_path "$source/distorted/sparse/0"
  step image_undistorter --image_path "$images" --input_path "$source/distorted/sparse/0" \
    --output_path "$source" --output_type COLMAP
  local registered="" model
  for model in "$source"/distorted/sparse/*/; do
    registered+=" $(basename "$model"):$("$colmap4" model_analyzer --path "$model" 2>&1 |
      sed -n 's/.*Registered images: //p' | head -1)"
  done
  echo "$name: ${times[*]} s; registered per model${registered} (read by COLMAP 4.2)"
}

run_sequence parallax-colmap "$dropin"
run_sequence colmap4.2 "$colmap4"
