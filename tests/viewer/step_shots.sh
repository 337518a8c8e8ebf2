#!/bin/sh
# Screenshots of the doorbell's and the motor's build, step by step, for the
# tutorial in docs/kit.md: each is the build script cut after a step, then the
# mouse moved to the contraption and the wheel turned to zoom in there.
#   sh tests/viewer/step_shots.sh build/apps/alloy docs/images
alloy=${1:?usage: step_shots.sh ALLOY OUTDIR}
out=${2:?usage: step_shots.sh ALLOY OUTDIR}
dir=$(mktemp -d) || exit 1
trap 'rm -rf "$dir"' EXIT
here=$(dirname "$0")

# shot SCRIPT LAST_FRAME X Y NOTCHES NAME: the script's events up to LAST_FRAME,
# zoomed about (X, Y), the mouse then moved off the parts (no tooltip over them).
shot() {
  awk -v last="$2" '/^[0-9]/ { if ($1 + 0 <= last) print; next } { print }' \
    "$here/scripts/$1.script" >"$dir/s.script"
  f=$(($2 + 2))
  {
    echo "$f move $3 $4"
    echo "$((f + 1)) wheel $5"
    echo "$((f + 2)) move $7 $8"
  } >>"$dir/s.script"
  frames=$((f + 5))
  SDL_AUDIODRIVER=dummy "$alloy" view --script "$dir/s.script" --frames "$frames" \
    --size 1100x700 --screenshot "$out/$6" >/dev/null 2>&1 || { echo "failed: $6" >&2; exit 1; }
  echo "$out/$6"
}

shot doorbell 31 0.18 0.11 7 kit_doorbell_step1.png 0.0 0.2    # battery, switch, striker on its axle, pad
shot doorbell 71 0.18 0.11 7 kit_doorbell_step2.png 0.0 0.2    # rest, armature, hammer, finger, interrupter
shot doorbell 84 0.18 0.11 7 kit_doorbell_step3.png 0.0 0.2    # the coil and the bell
shot doorbell 102 0.18 0.11 7 kit_doorbell_step4.png 0.0 0.2   # wired
shot motor 16 0.24 0.17 6 kit_motor_step1.png 0.05 0.3        # battery, hub on its axle
shot motor 92 0.24 0.17 6 kit_motor_step2.png 0.05 0.3        # eight spokes glued to the hub
shot motor 132 0.24 0.17 6 kit_motor_step3.png 0.05 0.3       # rod, coils, bias magnet
shot motor 178 0.24 0.17 6 kit_motor_step4.png 0.05 0.3       # wired
