#!/usr/bin/env bash
# Runs every benchmark program in full mode (or --quick), one after the other
# so that their timings do not disturb each other, and regenerates the tables
# in docs/performance.md and the CSV and SVG files in docs/bench/.
#
#   bench/run_all.sh BUILD_DIR [--quick]
#
# A program exits 1 when a goal it checks was missed: the run goes on and the
# summary lists it; the script then exits 1. Any other failure stops the run.
set -u
build=${1:?usage: bench/run_all.sh BUILD_DIR [--quick]}
shift
args=("$@")
quick=0
for a in "${args[@]}"; do [ "$a" = --quick ] && quick=1; done
if [ $quick = 1 ]; then
  args+=(--out "$build/bench-quick" --docs "")
fi

# Cheapest first: a broken build shows in seconds, not after the sweeps.
order=(sound lua_stage rigid engines work_precision scaling coupled multirate stress)
programs=()
for name in "${order[@]}"; do
  [ -x "$build/bench/alloy_bench_$name" ] && programs+=("$build/bench/alloy_bench_$name")
done
for p in "$build"/bench/alloy_bench_*; do  # any program not in the list, last
  [ -x "$p" ] || continue
  case " ${programs[*]} " in *" $p "*) ;; *) programs+=("$p") ;; esac
done

missed=()
start=$(date +%s)
for p in "${programs[@]}"; do
  name=$(basename "$p")
  echo "== $name ${args[*]}"
  t0=$(date +%s)
  "$p" "${args[@]}"
  rc=$?
  t1=$(date +%s)
  case $rc in
    0) echo "== $name: done in $((t1 - t0)) s" ;;
    1) echo "== $name: done in $((t1 - t0)) s, a goal was missed (see above)"; missed+=("$name") ;;
    *) echo "== $name failed with exit code $rc" >&2; exit $rc ;;
  esac
done
total=$(( $(date +%s) - start ))
echo "== all benchmarks: $((total / 60)) min $((total % 60)) s"
if [ ${#missed[@]} -gt 0 ]; then
  echo "== goals missed in: ${missed[*]}"
  exit 1
fi
