#!/bin/sh
# What magnetic_forces' near_field (an air-cored coil's near field as a
# current sheet, on by default since session 20) costs: each scene run with
# near_field forced on and forced off, interleaved, the cheapest of REPS runs
# of each, from `alloy run --profile` (us per step of the whole step and of
# the two stages that evaluate the sheet: magnetic_forces, its forces, and
# electricity_from_magnetism, the coils' flux). Also whether the two runs end
# in the same state (`--hash`). Prints one Markdown row per scene.
#
#   bench/near_field_cost.sh [BUILD_DIR [REPS]]   (default: build 3; from the source tree)
set -eu
src=$(pwd)
alloy=$src/${1:-build}/apps/alloy   # finds mods/ in its own source tree
reps=${2:-3}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# The scene's text behind a prelude that wraps world{} to set near_field.
variant() { # scene on|off -> file
  out="$work/$(echo "$1" | tr '/.' '__')_$2.lua"
  value=true
  [ "$2" = off ] && value=false
  cat >"$out" <<LUA
do
  local scene_world = world
  world = function(w)
    w.settings = w.settings or {}
    w.settings.magnetic_forces = w.settings.magnetic_forces or {}
    w.settings.magnetic_forces.near_field = $value
    return scene_world(w)
  end
end
LUA
  cat "$src/$1" >>"$out" || exit 1
  echo "$out"
}
# us/step: the whole step (the phases' sum), magnetic_forces, electricity_from_magnetism; the hash
measure() { # file seconds
  "$alloy" run "$1" --quiet --profile --hash --seconds "$2" 2>&1 | awk '
    $1 == "magnetic_forces" { mf = $(NF-1) }
    $1 == "electricity_from_magnetism" { em = $(NF-1) }
    /^    (advance|derive|interact|publish|edits and rebuilds) / { total += $(NF-2) }
    /hash/ { hash = $NF }
    END { printf "%s %s %s %s\n", total, mf, em, hash }'
}
echo "| scene | s | step on (us) | step off (us) | ratio | magnetic_forces on / off (us) | electricity_from_magnetism on / off (us) | same state |"
echo "| --- | --- | --- | --- | --- | --- | --- | --- |"
for entry in mods/motor/scene.lua:5 mods/doorbell/scene.lua:5 mods/hoist/scene.lua:5 \
             mods/generator/scene.lua:5 tests/coupled/scenes/magnet_through_air_coil.lua:1.2; do
  scene=${entry%:*}
  seconds=${entry#*:}
  on=$(variant "$scene" on)
  off=$(variant "$scene" off)
  best_on="" best_off=""
  i=0
  while [ $i -lt "$reps" ]; do
    a=$(measure "$on" "$seconds")
    b=$(measure "$off" "$seconds")
    best_on=$(printf '%s\n%s\n' "$best_on" "$a" | awk 'NF' | sort -g | head -1)
    best_off=$(printf '%s\n%s\n' "$best_off" "$b" | awk 'NF' | sort -g | head -1)
    i=$((i + 1))
  done
  echo "$scene $seconds $best_on $best_off" | awk '{
    same = ($6 == $10) ? "yes" : "no"
    printf "| %s | %s | %.1f | %.1f | %.2f | %.1f / %.1f | %.1f / %.1f | %s |\n",
      $1, $2, $3, $7, $3 / $7, $4, $8, $5, $9, same }'
done
