#!/usr/bin/env bash
# Runs each libFuzzer target of tests/fuzz for a while (`make fuzz`):
#
#   tests/fuzz/run_fuzzers.sh BUILD_DIR SECONDS [TARGET...]
#
# Each target starts from its seed corpus (tests/fuzz/corpus/<target> and the
# source folders that seed_dirs names for it, all read only) and keeps what it
# learns in BUILD_DIR/fuzz-corpus/<target>. A crash, a
# sanitizer report, a leak, a timeout (FUZZ_TIMEOUT seconds for one input) or
# more memory than FUZZ_RSS_MB stops that target and leaves the input in
# BUILD_DIR/fuzz-artifacts/<target>/; every target still runs, and the script
# fails at the end if any of them found something. FUZZ_FLAGS adds libFuzzer
# flags (e.g. "-fork=1 -ignore_crashes=1" to keep going after a finding);
# FUZZ_LOG_DIR is where each target's log goes (default BUILD_DIR).
set -uo pipefail

build=${1:?usage: run_fuzzers.sh BUILD_DIR SECONDS [TARGET...]}
seconds=${2:?usage: run_fuzzers.sh BUILD_DIR SECONDS [TARGET...]}
shift 2
targets=("$@")
[ ${#targets[@]} -eq 0 ] && targets=(scene mod mod_api cli save)

here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
# The target's read-only seed folders: corpus/<target> and seed_dirs' lines.
seeds() {
  [ -d "$here/corpus/$1" ] && echo "$here/corpus/$1"
  while read -r target dir; do
    [ "$target" = "$1" ] && [ -d "$root/$dir" ] && echo "$root/$dir"
  done < <(grep -v '^#' "$here/seed_dirs")
}
timeout=${FUZZ_TIMEOUT:-10}
rss=${FUZZ_RSS_MB:-2048}
# Sanitizer errors stop the run; leaks are reported at exit of each input's
# process state by libFuzzer's -detect_leaks.
export ASAN_OPTIONS=${ASAN_OPTIONS:-abort_on_error=1:detect_leaks=1:allocator_may_return_null=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-halt_on_error=1:print_stacktrace=1}

logs=${FUZZ_LOG_DIR:-$build}
mkdir -p "$logs"
failed=()
for t in "${targets[@]}"; do
  bin=$build/tests/fuzz/fuzz_$t
  [ -x "$bin" ] || { echo "run_fuzzers: no $bin (build it with: make fuzz)"; exit 2; }
  work=$build/fuzz-corpus/$t
  artifacts=$build/fuzz-artifacts/$t
  mkdir -p "$work" "$artifacts"
  mapfile -t seed_dirs < <(seeds "$t")
  echo "== fuzz_$t: $seconds s (timeout $timeout s per input, $rss MB)"
  # shellcheck disable=SC2086
  if "$bin" -max_total_time="$seconds" -timeout="$timeout" -rss_limit_mb="$rss" -detect_leaks=1 \
      -dict="$here/lua.dict" -artifact_prefix="$artifacts/" -print_final_stats=1 \
      ${FUZZ_FLAGS:-} "$work" "${seed_dirs[@]}" 2>"$logs/fuzz-$t.log"; then
    grep -E '^stat::(number_of_executed_units|average_exec_per_sec)' "$logs/fuzz-$t.log" | tr '\n' ' '
    grep -E 'exec/s' "$logs/fuzz-$t.log" | tail -1
    echo "corpus $(ls "$work" | wc -l) inputs"
  else
    echo "fuzz_$t FAILED: see $logs/fuzz-$t.log and $artifacts/"
    grep -E '^(==[0-9]+==ERROR|SUMMARY|.*runtime error)' "$logs/fuzz-$t.log" | head -5
    failed+=("$t")
  fi
done
if [ ${#failed[@]} -gt 0 ]; then
  echo "fuzzing found problems in: ${failed[*]}"
  exit 1
fi
