#!/bin/sh
# The robustness table of docs/doorbell.md: the doorbell at four steps and
# three battery voltages, 10 s each (the scene's own settings), from the
# bell's strikes in `alloy run --events`. Prints one Markdown row per case.
#
#   bench/doorbell_robustness.sh [BUILD_DIR [--edge]]   (default: build; from the source tree)
#   --edge: the voltages near where it stops ringing instead
set -eu
alloy=$(pwd)/${1:-build}/apps/alloy   # finds mods/ in its own source tree
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
row() { # label dt emf
  cat >scene.lua <<LUA
world { dt = $2, seconds = 10, settings = { ["gravity.uniform"] = { g = { 0, -9.81, 0 } },
                                            rigid_body = { solver = "step" } } }
require "doorbell.layout" { emf = $3 }
at(0.5, "switch_bar", { pinned = false })
LUA
  if ! "$alloy" run scene.lua --quiet --events events.jsonl >/dev/null; then
    echo "| $1 | the run failed |"
    return
  fi
  python3 - "$1" "$2" <<'PY'
import json, sys
label, dt = sys.argv[1], sys.argv[2]
num, den = (float(x) for x in dt.split("/")) if "/" in dt else (float(dt), 1.0)
dt = num / den
strikes = [json.loads(l) for l in open("events.jsonl")]
strikes = [e for e in strikes if e["type"] == "sound" and e["a"] == "bell"]
t = [e["time"] for e in strikes]
if len(t) < 3:
    print(f"| {label} | {len(t)} | does not ring | | | |")
    sys.exit()
gaps = [b - a for a, b in zip(t, t[1:])]
period = (t[-1] - t[0]) / (len(t) - 1)
speed = sum(e["speed"] for e in strikes) / len(strikes)
print(f"| {label} | {len(t)} | {period * 1e3:.1f} ms ({period / dt:.0f} steps) | "
      f"{min(gaps) * 1e3:.1f} – {max(gaps) * 1e3:.1f} | "
      f"{(max(gaps) - min(gaps)) / period * 100:.1f} % | {speed:.2f} m/s |")
PY
}
if [ "${2:-}" = --edge ]; then  # how far from the edge
  row "9 V, 1/240" 1/240 9
  row "15 V, 1/240" 1/240 15
  row "10.4 V, 1/1920" 1/1920 10.4
  row "10 V, 1/1920" 1/1920 10
  exit 0
fi
row "**dt 1/240, 12 V (the scene)**" 1/240 12
row "dt 1/480" 1/480 12
row "dt 1/960" 1/960 12
row "dt 1/1920" 1/1920 12
row "10.8 V (−10 %), 1/240" 1/240 10.8
row "13.2 V (+10 %), 1/240" 1/240 13.2
row "10.8 V, 1/480" 1/480 10.8
row "13.2 V, 1/480" 1/480 13.2
row "10.8 V, 1/1920" 1/1920 10.8
