#!/bin/bash
# usage: run.sh SCENE SECONDS [extra args...]  -> residue/moved, magnetism mismatch, moved, at 1/240 1/480 1/960
S=$1; T=$2; shift 2
for dt in 0.004166666666666667 0.0020833333333333333 0.0010416666666666667; do
  out=$(${ALLOY:-build/apps/alloy} run $S --seconds $T --energy --quiet --dt $dt "$@" 2>&1)
  rc=$?
  res=$(echo "$out" | grep 'residue / energy moved' | awk '{print $NF, $(NF-1)}')
  mm=$(echo "$out" | grep 'mismatch of magnetism' | awk '{print $(NF-1)}')
  mv=$(echo "$out" | grep '  energy moved' | awk '{print $(NF-1)}')
  sw=$(echo "$out" | grep 'switching' | awk '{print $(NF-1)}')
  own=$(echo "$out" | grep 'left by the stages' | awk '{print $(NF-1)}')
  nan=$(echo "$out" | grep -ci 'nan\|inf ' )
  printf "dt=1/%-4.0f rc=%s resid=%-12s mism=%-10s moved=%-10s switching=%-10s own=%-10s nan=%s\n" $(echo "1/$dt" | bc -l) $rc "$res" "$mm" "$mv" "$sw" "$own" "$nan"
  [ $rc -ne 0 ] && echo "$out" | tail -3
done
