#!/bin/bash
# usage: cost.sh N SECONDS [engine args]: wall time of pile.lua with N disks, ahead on and off, 2 runs each
N=$1; SEC=$2; shift 2
for rep in 1 2; do for a in true false; do
  sed "s/^local N = .*/local N = $N/; s/^local AHEAD = .*/local AHEAD = $a/" docs/experiments/adv21/pile.lua > /tmp/adv21_pile_$$.lua
  /usr/bin/time -f "%U user %e wall" ${ALLOY:-build/apps/alloy} run /tmp/adv21_pile_$$.lua --seconds $SEC --quiet "$@" 2>&1 | grep -E "ran|user" | tr '\n' ' '; echo " N=$N ahead=$a $*"
done; done
rm -f /tmp/adv21_pile_$$.lua
