#!/usr/bin/env bash
# The `colmap` drop-in's subcommands one by one against COLMAP 4.2 ($COLMAP4, default
# ../shared/tools/colmap4/bin/colmap) on one folder of photos (default templeRing). Three chains
# run the same sequence of subcommands: the drop-in with COLMAP 3.x flags, the drop-in with 4.x
# flags, and COLMAP 4.2 with 4.x flags; each chain works on its own outputs. For every step it
# prints the wall time of each chain, the files each wrote (the layout: file names under the
# step's output, compared with COLMAP 4.2's), and, for models, the registered images as COLMAP
# 4.2's model_analyzer reads them back.
#
# Usage: bench/colmap_subcommands.sh [IMAGES] [WORK_DIR]   Environment: THREADS (2).
set -euo pipefail
bench_name=colmap_subcommands.sh
source "$(dirname "$0")/bench_common.sh"
data="${PARALLAX_DATA:-$repo/../shared/data}"
images="${1:-$data/templeRing/images}"
work="${2:-/tmp/parallax_colmap_subcommands}"
threads="${THREADS:-2}"
colmap4="${COLMAP4:-$repo/../shared/tools/colmap4/bin/colmap}"
dropin="$(dirname "$binary")/colmap"
[[ -x "$dropin" ]] || { echo "$bench_name: no colmap drop-in beside $binary" >&2; exit 1; }
[[ -x "$colmap4" ]] || { echo "$bench_name: no COLMAP 4.2 at $colmap4" >&2; exit 1; }
rm -rf "$work" && mkdir -p "$work"
results="$work/results.txt"

# step CHAIN STEP OUTPUT -- COMMAND...: runs it, records time, layout and registered images.
step() {
  local chain=$1 name=$2 output=$3
  shift 4
  local start end layout registered=""
  start=$(date +%s.%N)
  if ! "$@" >>"$work/$chain.log" 2>&1; then
    echo "$chain $name FAILED (see $work/$chain.log)" >&2
    exit 1
  fi
  end=$(date +%s.%N)
  if [[ -d "$output" ]]; then
    layout=$(cd "$output" && find . -type f ! -name '*.log' | sed 's|^\./||' | sort |
      sed -E 's/[0-9]+\.(png|jpg|JPG)$/N.\1/' | sort -u | tr '\n' ' ')
    if [[ -f "$output/cameras.bin" ]]; then
      registered=$("$colmap4" model_analyzer --path "$output" 2>&1 |
        sed -n 's/.*Registered images: //p' | head -1)
    fi
  else
    layout=$(basename "$output")
  fi
  printf '%s\t%s\t%s\t%s\t%s\n' "$name" "$chain" "$(python3 -c "print(round($end - $start, 2))")" \
    "${registered:--}" "$layout" >>"$results"
}

run_chain() {
  local chain=$1 colmap=$2 generation=$3 w="$work/$1"
  local extraction=FeatureExtraction matching=FeatureMatching ba_iterations=BundleAdjustmentCeres
  local refine_poses=BundleAdjustment.refine_rig_from_world ratio=Mapper.ba_global_frames_ratio
  local leaf=HierarchicalMapper.leaf_max_num_images
  if [[ $generation == 3 ]]; then
    extraction=SiftExtraction matching=SiftMatching ba_iterations=BundleAdjustment
    refine_poses=BundleAdjustment.refine_extrinsics ratio=Mapper.ba_global_images_ratio
    leaf=leaf_max_num_images
  fi
  mkdir -p "$w"
  local db="$w/database.db"
  step "$chain" database_creator "$db" -- "$colmap" database_creator --database_path "$db"
  step "$chain" feature_extractor "$db" -- "$colmap" feature_extractor --database_path "$db" \
    --image_path "$images" --ImageReader.single_camera 1 --ImageReader.camera_model OPENCV \
    --$extraction.use_gpu 0 --$extraction.num_threads "$threads"
  cp "$db" "$w/sequential.db"
  cp "$db" "$w/importer.db"
  # Each image with its next five in name order, as a list for matches_importer.
  ls "$images" | awk '{ names[NR] = $0 } END { for (i = 1; i <= NR; ++i)
    for (j = i + 1; j <= i + 5 && j <= NR; ++j) print names[i], names[j] }' >"$w/pairs.txt"
  step "$chain" exhaustive_matcher "$db" -- "$colmap" exhaustive_matcher --database_path "$db" \
    --$matching.use_gpu 0 --$matching.num_threads "$threads"
  step "$chain" sequential_matcher "$w/sequential.db" -- "$colmap" sequential_matcher \
    --database_path "$w/sequential.db" --SequentialMatching.overlap 10 \
    --$matching.use_gpu 0 --$matching.num_threads "$threads"
  step "$chain" matches_importer "$w/importer.db" -- "$colmap" matches_importer \
    --database_path "$w/importer.db" --match_list_path "$w/pairs.txt" --match_type pairs \
    --$matching.use_gpu 0 --$matching.num_threads "$threads"
  mkdir -p "$w/sparse" "$w/hierarchical"
  step "$chain" mapper "$w/sparse/0" -- "$colmap" mapper --database_path "$db" \
    --image_path "$images" --output_path "$w/sparse" --Mapper.num_threads "$threads" \
    --$ratio 1.1
  step "$chain" hierarchical_mapper "$w/hierarchical/0" -- "$colmap" hierarchical_mapper \
    --database_path "$db" --image_path "$images" --output_path "$w/hierarchical" \
    --$leaf 24 --Mapper.num_threads "$threads"
  # The steps below start from the mapper's largest model (COLMAP 4.2 may make several).
  local best="" best_count=-1 model count
  for model in "$w"/sparse/*/; do
    count=$("$colmap4" model_analyzer --path "$model" 2>&1 | sed -n 's/.*Registered images: //p' |
      head -1)
    if ((count > best_count)); then best=$model best_count=$count; fi
  done
  cp -r "$best" "$w/model"
  echo "$chain: mapper models:$(ls "$w/sparse" | tr '\n' ' ')largest ${best#"$w"/} ($best_count images)" \
    >>"$work/models.txt"
  mkdir -p "$w/adjusted" "$w/aligned" "$w/text" "$w/partial" "$w/registered" "$w/triangulated" \
    "$w/merged" "$w/auto"
  step "$chain" bundle_adjuster "$w/adjusted" -- "$colmap" bundle_adjuster \
    --input_path "$w/model" --output_path "$w/adjusted" \
    --BundleAdjustment.refine_principal_point 1 --$ba_iterations.max_num_iterations 50 \
    --$refine_poses 1
  step "$chain" model_aligner "$w/aligned" -- "$colmap" model_aligner --input_path "$w/model" \
    --output_path "$w/aligned" --alignment_type plane --alignment_max_error 0.1 \
    --database_path "$db"
  step "$chain" model_converter "$w/text" -- "$colmap" model_converter \
    --input_path "$w/model" --output_path "$w/text" --output_type TXT
  step "$chain" model_analyzer model_analyzer -- "$colmap" model_analyzer --path "$w/model"
  # Every fourth image taken out (COLMAP 4.2's image_deleter, for every chain).
  ls "$images" | awk 'NR % 4 == 0' >"$w/removed.txt"
  "$colmap4" image_deleter --input_path "$w/model" --output_path "$w/partial" \
    --image_names_path "$w/removed.txt" >>"$work/$chain.log" 2>&1
  step "$chain" image_registrator "$w/registered" -- "$colmap" image_registrator \
    --database_path "$db" --input_path "$w/partial" --output_path "$w/registered" \
    --Mapper.num_threads "$threads"
  step "$chain" point_triangulator "$w/triangulated" -- "$colmap" point_triangulator \
    --database_path "$db" --image_path "$images" --input_path "$w/partial" \
    --output_path "$w/triangulated" --clear_points 1 --Mapper.num_threads "$threads"
  step "$chain" model_merger "$w/merged" -- "$colmap" model_merger --input_path1 "$w/partial" \
    --input_path2 "$w/model" --output_path "$w/merged"
  step "$chain" image_undistorter "$w/undistorted" -- "$colmap" image_undistorter \
    --image_path "$images" --input_path "$w/model" --output_path "$w/undistorted" \
    --output_type COLMAP
  step "$chain" automatic_reconstructor "$w/auto/sparse/0" -- "$colmap" automatic_reconstructor \
    --workspace_path "$w/auto" --image_path "$images" --single_camera 1 --dense 0 \
    --use_gpu 0 --num_threads "$threads"
}

run_chain parallax-3x "$dropin" 3
run_chain parallax-4x "$dropin" 4
run_chain colmap4.2 "$colmap4" 4

cat "$work/models.txt"
# One line per step: each chain's time and registered images, and whether the drop-in's layout
# (file names) equals COLMAP 4.2's.
python3 - "$results" <<'EOF'
import sys
rows = {}
for line in open(sys.argv[1]):
    name, chain, seconds, registered, layout = line.rstrip("\n").split("\t")
    rows.setdefault(name, {})[chain] = (float(seconds), registered, set(layout.split()))
print(f"{'subcommand':24} {'3.x flags':>10} {'4.x flags':>10} {'COLMAP 4.2':>10} {'ratio':>6}  "
      "registered (3x/4x/4.2)  layout vs COLMAP 4.2")
for name, chains in rows.items():
    p3, p4, c4 = chains["parallax-3x"], chains["parallax-4x"], chains["colmap4.2"]
    ratio = c4[0] / p4[0] if p4[0] > 0 else float("nan")
    missing = sorted(c4[2] - p4[2]); extra = sorted(p4[2] - c4[2])
    layout = "equal" if not missing and not extra else (
        ("lacks " + " ".join(missing) if missing else "") +
        (" adds " + " ".join(extra) if extra else ""))
    print(f"{name:24} {p3[0]:10.2f} {p4[0]:10.2f} {c4[0]:10.2f} {ratio:6.1f}  "
          f"{p3[1]}/{p4[1]}/{c4[1]:<16}  {layout.strip()}")
EOF
