#!/usr/bin/env bash
# Pair selection at scale, side by side with COLMAP 3.8: recall of the verified pairs against
# the survey's ground truth, pairs attempted per image, and the time of each.
#
#   bench/pair_selection.sh [VIEWS...]    # default: 300
#
# Per size: `parallax synth --layout aerial --views N`, `parallax features` into one database,
# then on copies of it
#   1. parallax match --pairs retrieval (defaults: 40 retrieved + 2 rounds of 20 loop pairs),
#   2. COLMAP 3.8: vocab_tree_builder on the same database, then vocab_tree_matcher on CPU
#      with PARALLAX_COLMAP_NUM_IMAGES retrieved images per image (default 40, the same budget;
#      COLMAP's own default is 100). PARALLAX_SKIP_COLMAP=1 leaves COLMAP out.
# Recall is bench/pair_recall.py: the share of gt/overlap_pairs.txt pairs with >= 100 shared
# scene points that the database verified, with --explain's account of the pairs missed
# after an attempt (putative matches, and those that agree with the true cameras).
# Needs PARALLAX_BENCH_DEPS=1 scripts/install-deps.sh.
# Results in ${PARALLAX_BENCH_OUT:-/tmp/parallax_pair_selection}/results.jsonl.
set -euo pipefail
bench_name=pair_selection
source "$(dirname "$0")/bench_common.sh"
command -v colmap >/dev/null || { echo "$bench_name: colmap missing (PARALLAX_BENCH_DEPS=1)" >&2; exit 1; }
out="${PARALLAX_BENCH_OUT:-/tmp/parallax_pair_selection}"
views=("$@")
[[ ${#views[@]} -eq 0 ]] && views=(300)
mkdir -p "$out"
results="$out/results.jsonl"

# Runs a command under GNU time; prints its wall seconds.
timed() {
  local log=$1
  shift
  /usr/bin/time -f "%e" -o "$log.time" "$@" >"$log" 2>&1
  cat "$log.time"
}

recall() {
  python3 "$repo/bench/pair_recall.py" --database "$1" --overlap-pairs "$2/gt/overlap_pairs.txt" --explain
}

for n in "${views[@]}"; do
  scene="$out/aerial_$n"
  if [[ ! -f "$scene/gt/overlap_pairs.txt" ]]; then
    echo "$bench_name: rendering $n views" >&2
    "$binary" synth --layout aerial --views "$n" --output "$scene" -q
  fi
  if [[ ! -f "$scene/features.db" ]]; then
    echo "$bench_name: extracting features" >&2
    "$binary" features --images "$scene" --database "$scene/features.db" -q
  fi

  run="$scene/parallax"
  rm -rf "$run" && mkdir -p "$run"
  cp "$scene/features.db" "$run/database.db"
  echo "$bench_name: parallax match --pairs retrieval ($n views)" >&2
  seconds=$(timed "$run/match.log" "$binary" match --database "$run/database.db" --pairs retrieval)
  echo "{\"tool\": \"parallax retrieval\", \"views\": $n, \"seconds\": $seconds, \"recall\": $(recall "$run/database.db" "$scene")}" | tee -a "$results"

  [[ "${PARALLAX_SKIP_COLMAP:-0}" == "1" ]] && continue
  for num_images in ${PARALLAX_COLMAP_NUM_IMAGES:-40}; do
    run="$scene/colmap_$num_images"
    rm -rf "$run" && mkdir -p "$run"
    cp "$scene/features.db" "$run/database.db"
    echo "$bench_name: COLMAP 3.8 vocab_tree_builder + vocab_tree_matcher, $num_images images ($n views)" >&2
    build_seconds=$(timed "$run/builder.log" colmap vocab_tree_builder --database_path "$run/database.db" \
      --vocab_tree_path "$run/vocab_tree.bin")
    match_seconds=$(timed "$run/matcher.log" colmap vocab_tree_matcher --database_path "$run/database.db" \
      --VocabTreeMatching.vocab_tree_path "$run/vocab_tree.bin" --VocabTreeMatching.num_images "$num_images" \
      --SiftMatching.use_gpu 0)
    echo "{\"tool\": \"colmap 3.8 vocab_tree num_images=$num_images\", \"views\": $n, \"tree_seconds\": $build_seconds, \"seconds\": $match_seconds, \"recall\": $(recall "$run/database.db" "$scene")}" | tee -a "$results"
  done
done
