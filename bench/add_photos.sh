#!/usr/bin/env bash
# Adding photos to a finished model (issue 17): templeRing reconstructed from its first 37
# views, then rerun after the last 10 are added (they are registered into the first model),
# against a run on all 47 from scratch. Known K; each case RUNS times (default 2), alternated.
#
#   bench/add_photos.sh [RUNS]
#
# Prints, per run: the mapping time of the rerun and of the run from scratch (and their
# ratio), the images registered, and the median centre and rotation errors against the
# ground truth.
# Environment: PARALLAX_DATA, PARALLAX_BINARY, BENCH_OUT (default a temporary folder).
set -euo pipefail

bench_name=add_photos.sh
source "$(dirname "${BASH_SOURCE[0]}")/bench_common.sh"
data="${PARALLAX_DATA:-$repo/../shared/data}/templeRing"
runs="${1:-2}"
out="${BENCH_OUT:-$(mktemp -d)}"
par="$data/templeR_par.txt"
tr -d '\r' <"$par" | awk 'NF == 22 { printf "%s %s %s\n%s %s %s\n%s %s %s\n", $2, $3, $4, $5, $6, $7, $8, $9, $10; exit }' >"$out/K.txt"
mapfile -t views < <(ls "$data/images" | sort)

# "mapping seconds, registered, median centre error, median rotation error" of OUT.
describe() {
  python3 - "$1" "$par" "$binary" <<'PY'
import json, subprocess, sys
out, par, binary = sys.argv[1:]
summary = json.load(open(f"{out}/summary.json"))
metrics = json.loads(subprocess.run([binary, "evaluate", f"{out}/sparse/0", "--gt", par, "--json"],
                                    check=True, capture_output=True, text=True).stdout)
print(f"{summary['timings_s']['mapping']:.2f} s mapping, {summary['images_registered']} registered, "
      f"centre {metrics['center_error']['median']:.5f}, rotation {metrics['rotation_error_deg']['median']:.4f} deg")
PY
}

for run in $(seq 1 "$runs"); do
  added="$out/added-$run" scratch="$out/scratch-$run"
  mkdir -p "$added/photos" "$scratch"
  for view in "${views[@]:0:37}"; do cp "$data/images/$view" "$added/photos/"; done
  "$binary" reconstruct --images "$added/photos" --output "$added/out" --intrinsics "$out/K.txt" -q >/dev/null
  echo "run $run, first 37 views: $(describe "$added/out")"
  for view in "${views[@]:37}"; do cp "$data/images/$view" "$added/photos/"; done
  "$binary" reconstruct --images "$added/photos" --output "$added/out" --intrinsics "$out/K.txt" -q >/dev/null
  echo "run $run, 10 added:       $(describe "$added/out")"
  "$binary" reconstruct --images "$data/images" --output "$scratch" --intrinsics "$out/K.txt" -q >/dev/null
  echo "run $run, 47 from scratch: $(describe "$scratch")"
  python3 - "$added/out/summary.json" "$scratch/summary.json" <<'PY'
import json, sys
added, scratch = (json.load(open(path))["timings_s"]["mapping"] for path in sys.argv[1:])
print(f"mapping time, 10 added / 47 from scratch: {added / scratch:.2f}")
PY
done
