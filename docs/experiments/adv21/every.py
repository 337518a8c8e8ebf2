#!/usr/bin/env python3
"""adv21: `ahead` with multi-rate stepping. glide (a bar at 0.2 m/s onto a
contact, pressed on by a gravity of 2 m/s^2 along +x so that it stays) at dt = 1/960 s with world every = { STAGE = K }; the
touch is placed at world-step fractions across two of the stage's periods.
Prints the step of the first `connected` with and without ahead, and the touch
time in world steps. The stage's own step is K dt: a prediction of half a
*world* step would miss touches between dt/2 and K dt/2 after the boundary."""
import json, os, subprocess, sys, tempfile
ALLOY = os.environ.get("ALLOY", "build/apps/alloy")
T = """local kit = require "kit"
world {{ dt = 1/960, seconds = {secs!r}, every = {{ {stage} = {k} }}, {use}
  settings = {{ ["gravity.uniform"] = {{ g = {{ 2, 0, 0 }} }},
               electricity_from_collisions = {{ ahead = {ahead} }} }} }}
kit.battery {{ name = "bat", at = {{ 0, 0.5 }} }}
kit.contact {{ name = "c", at = {{ 0.01, 0 }}, props = {{ restitution = 0 }} }}
kit.bar {{ name = "bar", material = "brass", at = {{ {x!r}, 0 }}, length = 0.1, width = 0.01,
          velocity = {{ 0.2, 0 }}, props = {{ restitution = 0 }} }}
kit.wire {{ name = "w1", from = "bat", from_terminal = 1, to = "c" }}
kit.wire {{ name = "w0", from = "bat", from_terminal = 0, to = "bar" }}
"""
stage = sys.argv[1] if len(sys.argv) > 1 else "electricity"
k = int(sys.argv[2]) if len(sys.argv) > 2 else 4
eng = sys.argv[3] if len(sys.argv) > 3 else "ode"
use = 'use = { rigid_body = "rigid_body.box2d" },' if eng == "box2d" else ""
dt = 1 / 960
for i in range(0, 2 * k * 4):
    tt = 16 + i / 4 + 0.1          # touch time in world steps
    res = {}
    for ahead in ("true", "false"):
        src = T.format(secs=(tt + 4 * k + 4) * dt, stage=stage, k=k, use=use, ahead=ahead, x=-(tt * dt * 0.2 + 0.5 * 2 * (tt * dt) ** 2) - 0.05)
        with tempfile.TemporaryDirectory() as d:
            p = os.path.join(d, "s.lua"); e = os.path.join(d, "e.jsonl"); open(p, "w").write(src)
            r = subprocess.run([ALLOY, "run", p, "--events", e, "--quiet"], capture_output=True, text=True)
            if r.returncode: res[ahead] = r.stderr[-150:]; continue
            ev = [json.loads(l) for l in open(e)]
        c = [x["step"] for x in ev if x["type"] == "connected"]
        b = [x["step"] for x in ev if x["type"] == "contact_began"]
        res[ahead] = (c[0] - 1 - tt if c else None, b[:1])
    print(f"{eng} every {stage}={k} touch at {tt:6.2f} steps: ahead (conn start - touch, began) {res['true']}  off {res['false']}")
