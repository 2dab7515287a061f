#!/usr/bin/env bash
# The mapper at scale (issue 15), side by side with COLMAP's mapper on the same database.
#
#   bench/mapper_scaling.sh [VIEWS...]    # default: 300 1000
#
# Per size, once (cached in the scene folder): `parallax synth --layout aerial --views N`,
# `parallax features`, `parallax match --pairs auto`, each timed. Then on that database:
#   1. parallax mapper (defaults), timed, evaluated against the exact cameras;
#   2. COLMAP 3.8 `colmap mapper` and, when ../shared/tools/colmap4 is set up, COLMAP 4.2's, on
#      copies of the same database, for sizes up to PARALLAX_COLMAP_MAX_VIEWS (default 300:
#      COLMAP 3.8's mapping time grows far faster with the views; docs/mapper-scaling.md has its
#      1,000-view run). PARALLAX_SKIP_COLMAP=1 leaves them out,
#      PARALLAX_COLMAP_VERSIONS="3.8" runs only those named, and PARALLAX_COLMAP_TIMEOUT=SECONDS
#      stops a COLMAP mapper that runs longer (its row then says it did not finish).
# End to end is features + matching + Parallax's mapper. Errors are after a similarity
# alignment to the ground truth: median rotation error and median centre error in % of the
# scene's extent. Needs PARALLAX_BENCH_DEPS=1 scripts/install-deps.sh (GNU time, COLMAP 3.8).
# Results in ${PARALLAX_BENCH_OUT:-/tmp/parallax_mapper_scaling}/results.jsonl.
set -euo pipefail
bench_name=mapper_scaling
source "$(dirname "$0")/bench_common.sh"
out="${PARALLAX_BENCH_OUT:-/tmp/parallax_mapper_scaling}"
views=("$@")
[[ ${#views[@]} -eq 0 ]] && views=(300 1000)
mkdir -p "$out"
results="$out/results.jsonl"
colmap4="$repo/../shared/tools/colmap4/bin/colmap"
colmap_timeout="${PARALLAX_COLMAP_TIMEOUT:-0}" # seconds; 0: no limit

# Runs a command under GNU time into LOG; LOG.time holds "wall_seconds peak_kb".
timed() {
  local log=$1
  shift
  /usr/bin/time -f "%e %M" -o "$log.time" "$@" >"$log" 2>&1
}
seconds_of() { awk '{ print $1 }' "$1.time"; }
megabytes_of() { awk '{ printf "%.0f", $2 / 1024 }' "$1.time"; }

# One JSON line: tool, views, the mapper's seconds and MB, the model's accuracy and size.
record() {
  local tool=$1 n=$2 log=$3 model_dir=$4 scene=$5 extra=$6
  local models
  models=$(find "$model_dir" -mindepth 1 -maxdepth 1 -type d | wc -l)
  "$binary" evaluate "$model_dir/0" --gt "$scene/synth_par.txt" --json >"$log.evaluation.json"
  python3 - "$tool" "$n" "$(seconds_of "$log")" "$(megabytes_of "$log")" "$models" "$extra" \
    "$log.evaluation.json" <<'EOF' | tee -a "$results"
import json, sys
tool, n, seconds, megabytes, models, extra, evaluation = sys.argv[1:8]
e = json.load(open(evaluation))
row = {"tool": tool, "views": int(n), "mapping_s": float(seconds), "peak_mb": int(megabytes),
       "models": int(models), "registered": e["images_registered"],
       "rotation_error_deg_median": e["rotation_error_deg"]["median"],
       "center_error_pct_median": 100 * e["center_error_relative"]["median"],
       "points3D": e["points3D"]}
row.update(json.loads(extra or "{}"))
print(json.dumps(row))
EOF
}

for n in "${views[@]}"; do
  scene="$out/aerial_$n"
  mkdir -p "$scene"
  if [[ ! -f "$scene/images/gt/overlap_pairs.txt" ]]; then
    echo "$bench_name: rendering $n views" >&2
    timed "$scene/synth.log" "$binary" synth --layout aerial --views "$n" --output "$scene/images" -q
  fi
  if [[ ! -f "$scene/match.log.time" ]]; then
    rm -f "$scene/database.db"
    echo "$bench_name: features and matching ($n views)" >&2
    timed "$scene/features.log" "$binary" features --images "$scene/images" --database "$scene/database.db" -q
    timed "$scene/match.log" "$binary" match --database "$scene/database.db" --pairs auto
  fi
  features_s=$(seconds_of "$scene/features.log")
  match_s=$(seconds_of "$scene/match.log")

  run="$scene/parallax"
  rm -rf "$run" && mkdir -p "$run"
  echo "$bench_name: parallax mapper ($n views)" >&2
  timed "$run/mapper.log" "$binary" mapper --database "$scene/database.db" --image-path "$scene/images" \
    --output "$run" --no-text
  extra=$(python3 - "$run/summary.json" "$features_s" "$match_s" "$(seconds_of "$run/mapper.log")" <<'EOF'
import json, sys
summary = json.load(open(sys.argv[1]))
features, match, mapping = map(float, sys.argv[2:5])
print(json.dumps({"features_s": features, "matching_s": match, "end_to_end_s": features + match + mapping,
                  "ba_share": summary["mapper"]["bundle_adjustment_s"] / summary["timings_s"]["mapping"]}))
EOF
)
  record parallax "$n" "$run/mapper.log" "$run/sparse" "$scene/images" "$extra"

  [[ "${PARALLAX_SKIP_COLMAP:-0}" == "1" || "$n" -gt "${PARALLAX_COLMAP_MAX_VIEWS:-300}" ]] && continue
  for version in ${PARALLAX_COLMAP_VERSIONS:-3.8 4.2}; do
    tool="colmap-$version"
    colmap_binary=colmap
    [[ $version == 4.2 ]] && colmap_binary="$colmap4"
    command -v "$colmap_binary" >/dev/null || { echo "$bench_name: $tool missing, skipped" >&2; continue; }
    run="$scene/$tool"
    rm -rf "$run" && mkdir -p "$run/sparse"
    cp "$scene/database.db" "$run/database.db"
    echo "$bench_name: $tool mapper ($n views)" >&2
    status=0
    timed "$run/mapper.log" timeout "$colmap_timeout" "$colmap_binary" mapper \
      --database_path "$run/database.db" --image_path "$scene/images" --output_path "$run/sparse" ||
      status=$?
    # 124 is timeout's own status; any other failure of COLMAP still stops the bench.
    if [[ $status -eq 124 ]]; then
      # COLMAP logs "Registering image #ID (K)" before it tries its K-th image.
      reached=$(sed -n 's/^Registering image #[0-9]* (\([0-9]*\))$/\1/p' "$run/mapper.log" | tail -1)
      registered=$((${reached:-1} - 1))
      echo "$bench_name: $tool did not finish $n views within $colmap_timeout s ($registered registered)" >&2
      echo "{\"tool\": \"$tool\", \"views\": $n, \"unfinished_after_s\": $colmap_timeout, \"registered_when_stopped\": $registered}" >>"$results"
      continue
    fi
    [[ $status -eq 0 ]] || exit "$status"
    record "$tool" "$n" "$run/mapper.log" "$run/sparse" "$scene/images" "{}"
  done
done

echo
echo "| views | tool | mapping (s) | peak (MB) | BA share | end to end (s) | registered | models | median rotation error (deg) | median centre error (% of scene) |"
echo "|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|"
python3 - "$results" <<'EOF'
import json, sys
for line in open(sys.argv[1]):
    r = json.loads(line)
    if "unfinished_after_s" in r:
        print("| %d | %s | did not finish in %d s | | | | %s when stopped | | | |" % (
            r["views"], r["tool"], r["unfinished_after_s"], r.get("registered_when_stopped", "")))
        continue
    share = "%.0f %%" % (100 * r["ba_share"]) if "ba_share" in r else ""
    total = "%.0f" % r["end_to_end_s"] if "end_to_end_s" in r else ""
    print("| %d | %s | %.1f | %d | %s | %s | %d | %d | %.4f | %.4f |" % (
        r["views"], r["tool"], r["mapping_s"], r["peak_mb"], share, total, r["registered"],
        r["models"], r["rotation_error_deg_median"], r["center_error_pct_median"]))
EOF
