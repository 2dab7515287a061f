#!/usr/bin/env bash
# End-to-end benchmark: Parallax against COLMAP on the same images with the same known
# intrinsics, side by side.
#
#   bench/run.sh [DATASET...]        # default: templeRing fountain-P11
#   BENCH_RUNS=2 bench/run.sh templeRing fountain-P11   # issue 21's table: two runs each
#
# For each data set (a folder of $PARALLAX_DATA with images/ and ground truth) and each run:
#   1. parallax reconstruct --intrinsics K (features, matching + verification, mapping);
#   2. each COLMAP present, one after the other: COLMAP 3.8 (`colmap` on the PATH, Debian's
#      package) and COLMAP 4.2 (../shared/tools/colmap4/bin/colmap, or $COLMAP4): feature_extractor
#      (PINHOLE, one camera, the same K, CPU SIFT), exhaustive_matcher (CPU), mapper
#      (intrinsics fixed);
#   3. the mapping stage alone on each COLMAP's database, i.e. on the same matches:
#      parallax mapper --database DB against that COLMAP's mapper;
#   4. parallax evaluate of every model against the ground truth.
# Every command runs under /usr/bin/time -v (wall time, peak resident memory). The results go
# to stdout as markdown tables (every ratio COLMAP / Parallax) and to $BENCH_OUT/results.json.
#
# Environment:
#   PARALLAX_DATA     data sets (default: ../shared/data beside the checkout)
#   PARALLAX_BINARY   the parallax executable (default: build/parallax, then build-*/parallax)
#   BENCH_OUT         output folder (default: /tmp/parallax-bench-YYYYmmdd-HHMMSS)
#   BENCH_THREADS     threads for every tool (default: all cores)
#   BENCH_RUNS        runs of everything per data set (default 1)
#   BENCH_NO_COLMAP=1 skip COLMAP even when installed
#   COLMAP4           COLMAP 4 binary (default ../shared/tools/colmap4/bin/colmap; set it up
#                     with that folder's install-runtime.sh)
# Needs bash, python3 and GNU time (/usr/bin/time; PARALLAX_BENCH_DEPS=1 scripts/install-deps.sh
# installs it and COLMAP).
set -euo pipefail

bench_name=run.sh
source "$(dirname "${BASH_SOURCE[0]}")/bench_common.sh"
data="${PARALLAX_DATA:-$repo/../shared/data}"
threads="${BENCH_THREADS:-$(nproc)}"
out="${BENCH_OUT:-/tmp/parallax-bench-$(date +%Y%m%d-%H%M%S)}"
datasets=("$@")
[[ ${#datasets[@]} -eq 0 ]] && datasets=(templeRing fountain-P11)

runs="${BENCH_RUNS:-1}"

# The COLMAPs to compare with: name, binary, and the flags that changed between versions
# (4.0 renamed SiftExtraction/SiftMatching to FeatureExtraction/FeatureMatching).
colmaps=()
declare -A colmap_binary colmap_extraction colmap_matching
if [[ "${BENCH_NO_COLMAP:-0}" != "1" ]]; then
  # The version from the help text read in full: `grep -q` would stop reading early, and under
  # pipefail the help's SIGPIPE then sometimes counted as no COLMAP at all.
  if command -v colmap >/dev/null && [[ "$(colmap help 2>&1)" == "COLMAP 3"* ]]; then
    colmaps+=(colmap38)
    colmap_binary[colmap38]="$(command -v colmap)"
    colmap_extraction[colmap38]=SiftExtraction
    colmap_matching[colmap38]=SiftMatching
  fi
  colmap4="${COLMAP4:-$repo/../shared/tools/colmap4/bin/colmap}"
  if [[ -x "$colmap4" ]] && [[ "$("$colmap4" help 2>&1)" == "COLMAP 4"* ]]; then
    colmaps+=(colmap42)
    colmap_binary[colmap42]="$colmap4"
    colmap_extraction[colmap42]=FeatureExtraction
    colmap_matching[colmap42]=FeatureMatching
  fi
fi

mkdir -p "$out"
{
  echo "run.sh: parallax $binary, $threads threads, $runs run(s), results in $out"
  for tool in "${colmaps[@]}"; do
    echo "run.sh: $tool = ${colmap_binary[$tool]} ($("${colmap_binary[$tool]}" help 2>&1 | head -1))"
  done
} >&2

# timed NAME CMD...: runs CMD with /usr/bin/time -v, log in $run/NAME.log, measures in NAME.time.
timed() {
  local name="$1"; shift
  echo "run.sh: [$name] $*" >&2
  if ! /usr/bin/time -v -o "$run/$name.time" "$@" >"$run/$name.log" 2>&1; then
    echo "run.sh: [$name] failed, see $run/$name.log" >&2
    return 1
  fi
}

for dataset in "${datasets[@]}"; do
  dir="$data/$dataset"
  [[ -d "$dir/images" ]] || { echo "run.sh: $dir/images not found" >&2; exit 1; }
  for ((r = 1; r <= runs; r++)); do
  run="$out/$dataset/run-$r"
  rm -rf "$run"
  mkdir -p "$run"

  # Known intrinsics: K.txt, or the first K of a Middlebury *_par.txt.
  if [[ -f "$dir/K.txt" ]]; then
    tr -d '\r' <"$dir/K.txt" >"$run/K.txt"
  else
    par="$(ls "$dir"/*_par.txt | head -1)"
    tr -d '\r' <"$par" | awk 'NF == 22 { printf "%s %s %s\n%s %s %s\n%s %s %s\n", $2, $3, $4, $5, $6, $7, $8, $9, $10; exit }' >"$run/K.txt"
  fi
  read -r fx _ cx <<<"$(sed -n 1p "$run/K.txt")"
  read -r _ fy cy <<<"$(sed -n 2p "$run/K.txt")"
  # Ground truth: a Middlebury *_par.txt, or a folder of Strecha .camera files.
  gt="$(ls "$dir"/*_par.txt 2>/dev/null | head -1 || true)"
  [[ -z "$gt" && -d "$dir/gt" ]] && gt="$dir/gt"

  # 1. Parallax end to end.
  timed parallax "$binary" reconstruct --images "$dir/images" --output "$run/parallax" \
    --intrinsics "$run/K.txt" --threads "$threads" || true

  for tool in "${colmaps[@]}"; do
    # 2. COLMAP with the same intrinsics, CPU only.
    colmap="${colmap_binary[$tool]}"
    db="$run/$tool/database.db"
    mkdir -p "$run/$tool/sparse"
    timed "${tool}_features" "$colmap" feature_extractor --database_path "$db" \
      --image_path "$dir/images" --ImageReader.camera_model PINHOLE \
      --ImageReader.single_camera 1 --ImageReader.camera_params "$fx,$fy,$cx,$cy" \
      "--${colmap_extraction[$tool]}.use_gpu" 0 \
      "--${colmap_extraction[$tool]}.num_threads" "$threads" || true
    timed "${tool}_matching" "$colmap" exhaustive_matcher --database_path "$db" \
      "--${colmap_matching[$tool]}.use_gpu" 0 \
      "--${colmap_matching[$tool]}.num_threads" "$threads" || true
    timed "${tool}_mapping" "$colmap" mapper --database_path "$db" --image_path "$dir/images" \
      --output_path "$run/$tool/sparse" --Mapper.num_threads "$threads" \
      --Mapper.ba_refine_focal_length 0 --Mapper.ba_refine_principal_point 0 \
      --Mapper.ba_refine_extra_params 0 || true
    # 3. Parallax's mapper on that COLMAP's database (a copy: the mapper only reads it).
    cp "$db" "$run/${tool}_db_copy.db"
    timed "parallax_mapper_$tool" "$binary" mapper --database "$run/${tool}_db_copy.db" \
      --image-path "$dir/images" --output "$run/parallax_mapper_$tool" --ba-threads "$threads" || true
    rm -f "$run/${tool}_db_copy.db"
  done

  # 4. Accuracy of every model against the ground truth (the largest model of each run).
  if [[ -n "$gt" ]]; then
    for name in parallax "${colmaps[@]}" "${colmaps[@]/#/parallax_mapper_}"; do
      model_root="$run/$name/sparse"
      [[ -d "$model_root" ]] || continue
      best=""; best_images=-1
      for model in "$model_root"/*/; do
        [[ -f "$model/images.bin" || -f "$model/images.txt" ]] || continue
        if "$binary" evaluate "${model%/}" --gt "$gt" --json >"$run/eval_tmp.json" 2>/dev/null; then
          images="$(python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["images_registered"])' "$run/eval_tmp.json")"
          if (( images > best_images )); then
            best_images=$images; best="${model%/}"; mv "$run/eval_tmp.json" "$run/eval_$name.json"
          fi
        fi
      done
      rm -f "$run/eval_tmp.json"
      [[ -n "$best" ]] && echo "$best" >"$run/eval_$name.model"
    done
  fi
  done
done

python3 "$repo/bench/summarize.py" "$out" "${datasets[@]}"
