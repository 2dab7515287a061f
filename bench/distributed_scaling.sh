#!/usr/bin/env bash
# A distributed run's cost (issue 19): `parallax reconstruct` on one rendered aerial survey
# under `mpirun -np K` for each K, each from an empty output folder, on this machine.
#
#   bench/distributed_scaling.sh [VIEWS] [RANKS...]     # default: 1000 views; 1 2 4 ranks
#
# Prints one markdown table: each stage's wall time, the total, the coordinator's time alone
# (storing the features, choosing the pairs, merging the pair shards, merging and refining the
# clusters' models)
# and its share of the total, and the bytes the ranks read and wrote per image. From the
# share s and the one-rank total T, Amdahl's law predicts the wall time on M machines of
# this size as T (s + (1 - s) / M) (an upper bound on the speed-up: it ignores the extra
# merges of more ranks). Ranks past the core count share cores: there the table shows
# overhead, not speed.
#
# Environment:
#   BENCH_OUT          output folder (default: /tmp/parallax-distributed-VIEWS)
#   BENCH_SCENE        an aerial survey already rendered (default: render one into BENCH_OUT)
#   BENCH_THREADS      threads per rank (default: cores / ranks, at least 1)
#   PARALLAX_BINARY    the parallax executable (default: build/parallax)
set -euo pipefail
bench_name=distributed_scaling.sh
source "$(dirname "${BASH_SOURCE[0]}")/bench_common.sh"
views="${1:-1000}"
shift || true
ranks=("$@")
[[ ${#ranks[@]} -eq 0 ]] && ranks=(1 2 4)
out="${BENCH_OUT:-/tmp/parallax-distributed-$views}"
command -v mpirun >/dev/null || { echo "$bench_name: mpirun missing (install-deps.sh)" >&2; exit 1; }
"$binary" version | grep -q 'MPI' || { echo "$bench_name: $binary built without MPI" >&2; exit 1; }
# Unbound: mpirun binds each of two ranks to one core by default, which would run a rank's
# threads on one core (and, since Parallax counts the cores a rank may use, a one-rank run on
# one thread). Each rank gets cores / ranks threads instead.
mpi_flags=(--oversubscribe --bind-to none)
[[ "$(id -u)" == 0 ]] && mpi_flags+=(--allow-run-as-root)

mkdir -p "$out"
scene="${BENCH_SCENE:-$out/aerial_$views}"
if [[ ! -d "$scene" ]]; then
  echo "$bench_name: rendering $views views into $scene" >&2
  "$binary" synth --layout aerial --views "$views" --output "$scene" >"$out/synth.log" 2>&1
fi

rows=()
for k in "${ranks[@]}"; do
  run="$out/ranks-$k"
  rm -rf "$run"
  threads="${BENCH_THREADS:-$(( $(nproc) / k > 0 ? $(nproc) / k : 1 ))}"
  echo "$bench_name: $k rank(s), $threads thread(s) each -> $run" >&2
  /usr/bin/time -f "%e %M" -o "$run.time" \
    mpirun "${mpi_flags[@]}" -np "$k" "$binary" reconstruct --images "$scene" --output "$run" \
    --threads "$threads" >"$run.log" 2>&1 || { echo "$bench_name: run failed, see $run.log" >&2; exit 1; }
  rows+=("$(python3 - "$run.log" "$run.time" "$k" "$views" <<'EOF'
import re, sys
log = open(sys.argv[1]).read()
wall, peak_kb = open(sys.argv[2]).read().split()[-2:]
ranks, views = int(sys.argv[3]), int(sys.argv[4])
def stage(name):
    found = re.findall(r'^%s: ([0-9.]+) s' % name, log, re.M)
    return float(found[-1]) if found else float('nan')
# Storing the features, choosing pairs, merging pairs, merging and refining the clusters' models.
alone = re.search(r'^rank 0 alone: (.*)$', log, re.M)
alone_s = sum(float(x) for x in re.findall(r'([0-9.]+) s', alone.group(1))) if alone else 0.0
io = re.findall(r'read ([0-9.]+) MB, wrote ([0-9.]+) MB', log)
read = sum(float(r) for r, _ in io) / views if io else float('nan')
written = sum(float(w) for _, w in io) / views if io else float('nan')
total = float(wall)
print('| %d | %.1f | %.1f | %.1f | %.1f | %.1f (%.1f %%) | %.2f / %.2f | %.0f |' % (
    ranks, stage('features'), stage('matching'), stage('mapping'), total, alone_s,
    100 * alone_s / total, read, written, int(peak_kb) / 1024))
EOF
)")
done

echo "### $views-view aerial survey, $(nproc) cores"
echo
echo "| ranks | features (s) | matching (s) | mapping (s) | total wall (s) | rank 0 alone (s, share) | MB read / written per image, all ranks | largest process (MB) |"
echo "|---:|---:|---:|---:|---:|---:|---:|---:|"
printf '%s\n' "${rows[@]}"
