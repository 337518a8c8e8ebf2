#!/bin/bash
# usage: savecheck.sh SCENE N M [extra args]: hash of N+M steps straight vs N steps saved + M continued
S=$1; N=$2; M=$3; shift 3
A=$(${ALLOY:-build/apps/alloy} run $S --steps $((N+M)) --quiet --hash "$@" 2>&1 | grep 'state hash')
${ALLOY:-build/apps/alloy} run $S --steps $N --quiet --save /tmp/adv20_save.alloysave "$@" >/dev/null 2>&1 || echo "save failed"
B=$(${ALLOY:-build/apps/alloy} run /tmp/adv20_save.alloysave --steps $M --quiet --hash 2>&1 | grep 'state hash')
if [ "$A" == "$B" ]; then echo "SAME  $S $N+$M $*: $A"; else echo "DIFF  $S $N+$M $*: straight [$A] restored [$B]"; fi
