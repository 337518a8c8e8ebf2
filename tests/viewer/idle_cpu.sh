#!/bin/sh
# How much CPU the viewer takes under a real X server (Xvfb), paused and
# running: the process's own CPU time (user + system, from /proc/PID/stat)
# over `seconds` of wall time, as a percentage of one core. A measurement,
# not a test (its figures depend on the machine); docs/kit.md quotes it.
#
#   idle_cpu.sh ALLOY_BINARY [SCENE] [seconds]
set -u
alloy=$1
scene=${2:-mods/doorbell}
seconds=${3:-10}
if ! command -v Xvfb >/dev/null 2>&1; then
  echo "SKIP: Xvfb is not installed"
  exit 77
fi
n=150
while [ -e "/tmp/.X$n-lock" ] && [ $n -lt 199 ]; do n=$((n + 1)); done
# -noreset: the server would reset when its last client leaves (the first
# viewer, killed), and refuse the second viewer meanwhile (docs/kit.md).
Xvfb ":$n" -screen 0 1100x700x24 -nolisten tcp -noreset >/dev/null 2>&1 &
xpid=$!
trap 'kill $xpid 2>/dev/null' EXIT
export DISPLAY=":$n"
i=0
while ! xdotool getdisplaygeometry >/dev/null 2>&1 && [ $i -lt 100 ]; do sleep 0.1; i=$((i + 1)); done
ticks() { awk '{ print $14 + $15 }' "/proc/$1/stat"; }
hz=$(getconf CLK_TCK)
for mode in --paused ""; do
  SDL_AUDIODRIVER=dummy "$alloy" view "$scene" --size 1100x700 $mode >/dev/null 2>&1 &
  vpid=$!
  sleep 3  # loaded and drawing
  t0=$(ticks $vpid)
  sleep "$seconds"
  t1=$(ticks $vpid)
  kill $vpid
  wait $vpid 2>/dev/null
  echo "$scene ${mode:-running}: $(echo "$t0 $t1 $hz $seconds" | awk '{ printf "%.1f", 100 * ($2 - $1) / $3 / $4 }') % of a core over $seconds s"
done
