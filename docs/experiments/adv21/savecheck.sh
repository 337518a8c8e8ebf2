#!/bin/bash
# usage: savecheck.sh SCENE N M [extra args]: state hash of N+M steps straight vs
# N steps saved (--save) and M continued from the save (alloy run FILE --steps M --hash).
S=$1; N=$2; M=$3; shift 3
T=/tmp/adv21_save_$$.alloysave
A=$(${ALLOY:-build/apps/alloy} run $S --steps $((N+M)) --quiet --hash "$@" 2>&1 | grep 'state hash')
${ALLOY:-build/apps/alloy} run $S --steps $N --quiet --save $T "$@" >/dev/null 2>&1 || echo "save failed"
B=$(${ALLOY:-build/apps/alloy} run $T --steps $M --quiet --hash 2>&1 | grep 'state hash')
rm -f $T
if [ "$A" == "$B" ]; then echo "SAME  $S $N+$M $*: $A"; else echo "DIFF  $S $N+$M $*: straight [$A] restored [$B]"; fi
