#!/usr/bin/env bash
# Flake hunter: runs the chosen pytest tests N times, each run a fresh `python -m pytest` process in the
# workspace's environment (scripts/env.sh), optionally with one core kept busy the whole time (--load), and
# reports each test that failed at least once: in how many runs, and the first failure's reason. The last line
# is `repeat: N runs, F failures` (F: runs with a failing or erroring test, or a pytest that did not end
# normally); exit status 0 when F is 0, 1 otherwise, 2 on a usage error.
set -uo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)

usage() {
  cat <<'EOF'
usage: scripts/repeat_tests.sh N [--load] [PYTEST ARGS ...]
  Runs `python -m pytest PYTEST ARGS` N times, each in a fresh process, from the repository root (relative
  paths are taken from there), and reports the tests that failed at least once.
  --load  keep one CPU core busy from before the first run until after the last
  example: scripts/repeat_tests.sh 5 --load src/swim_planner/test/test_planner_node.py -k lqr
EOF
}
usage_error() {
  echo "repeat_tests.sh: $1" >&2
  usage >&2
  exit 2
}

case "${1:-}" in
  -h | --help) usage; exit 0 ;;
  "") usage_error "missing N, the number of runs" ;;
esac
[[ $1 =~ ^[1-9][0-9]*$ ]] || usage_error "N must be a positive whole number, not '$1'"
runs=$1
shift
load=0
if [ "${1:-}" = --load ]; then load=1; shift; fi
pytest_args=("$@")

cd "$root" || exit 2
# shellcheck source=scripts/env.sh
source scripts/env.sh
export PYTHONDONTWRITEBYTECODE=1

out=$(mktemp -d "${TMPDIR:-/tmp}/repeat_tests.XXXXXX") || exit 2
keep_out=0
load_pid=
# shellcheck disable=SC2329  # called by the EXIT trap
cleanup() {
  if [ -n "$load_pid" ]; then kill "$load_pid" 2>/dev/null; wait "$load_pid" 2>/dev/null; fi
  [ "$keep_out" -eq 1 ] || rm -rf "$out"
}
trap cleanup EXIT
# Ctrl-C reaches the running pytest too (same process group); the runs done so far are still reported.
interrupted=0
trap 'interrupted=1' INT
trap 'exit 143' TERM

# Every process this script starts dies with it, however it ends (swim_ros.processes: a parent-death signal).
with_me=(python -m swim_ros.processes "$BASHPID")
if [ "$load" -eq 1 ]; then
  "${with_me[@]}" bash -c 'while :; do :; done' &
  load_pid=$!
  echo "load: one core kept busy (pid $load_pid)"
fi

echo "running $runs times: python -m pytest -p no:cacheprovider ${pytest_args[*]}"
done_runs=0
for ((run = 1; run <= runs; run++)); do
  [ "$interrupted" -eq 1 ] && break
  start_us=${EPOCHREALTIME/[.,]/}
  "${with_me[@]}" python -m pytest -p no:cacheprovider -o junit_family=xunit1 --junitxml="$out/run-$run.xml" \
    "${pytest_args[@]}" >"$out/run-$run.log" 2>&1
  status=$?
  [ "$interrupted" -eq 1 ] && break
  echo "$status" >"$out/run-$run.status"
  done_runs=$run
  # pytest's closing summary ("1 failed, 11 passed in 40.12s"), absent when it did not end normally
  summary=$(grep -E ' in [0-9.]+s( \([0-9:]+\))?( =+)?$' "$out/run-$run.log" | tail -n 1 |
    sed -E 's/^=+ //; s/ =+$//')
  [ -n "$summary" ] || summary="no pytest summary"
  elapsed_ds=$(((${EPOCHREALTIME/[.,]/} - start_us) / 100000))
  printf 'run %d/%d: %s (exit %d, %d.%d s)\n' "$run" "$runs" "$summary" "$status" \
    $((elapsed_ds / 10)) $((elapsed_ds % 10))
  # Arguments pytest rejects, or a selection without tests, would fail every run alike: a usage error.
  if [ "$run" -eq 1 ] && { [ "$status" -eq 4 ] || [ "$status" -eq 5 ]; }; then
    tail -n 20 "$out/run-$run.log" >&2
    echo "repeat_tests.sh: pytest exited with status $status (4: arguments rejected, 5: no tests collected)" >&2
    exit 2
  fi
done
[ "$interrupted" -eq 1 ] && echo "interrupted: $done_runs of $runs runs completed"

python "$root/scripts/repeat_tests_report.py" "$out" "$done_runs"
report_status=$?
# The runs' pytest output and junit files stay for inspection when a run failed (the report names the folder).
[ "$report_status" -ne 0 ] && keep_out=1
[ "$interrupted" -eq 1 ] && exit 130
exit "$report_status"
