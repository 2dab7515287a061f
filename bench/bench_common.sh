# Sourced by bench/run.sh and bench/scaling.sh: the checkout, the parallax binary and GNU time.
# Sets `repo` and `binary`; exits with a one-line error (prefixed with $bench_name) when the
# binary or /usr/bin/time is missing.
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
binary="${PARALLAX_BINARY:-}"
if [[ -z "$binary" ]]; then
  for candidate in "$repo"/build/parallax "$repo"/build-*/parallax; do
    if [[ -x "$candidate" ]]; then binary="$candidate"; break; fi
  done
fi
[[ -x "$binary" ]] || { echo "$bench_name: no parallax binary (set PARALLAX_BINARY)" >&2; exit 1; }
[[ -x /usr/bin/time ]] || {
  echo "$bench_name: /usr/bin/time missing: PARALLAX_BENCH_DEPS=1 scripts/install-deps.sh" >&2
  exit 1
}
