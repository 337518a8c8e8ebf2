#!/usr/bin/env python3
"""adv21: a predicted touch that never happens. A brass bar turns about a hinge
at its end (no gravity) toward a brass contact; the hinge's stop halts it
0.2 mm (at the corner) before it would touch. Battery - bar, battery - contact.
Without ahead nothing ever connects. With ahead: count connected events.
Writes the scene of each phase to /tmp and prints the events."""
import json, math, os, subprocess, sys
ALLOY = os.environ.get("ALLOY", "build/apps/alloy")
T = """local kit = require "kit"
world {{ dt = {dt!r}, seconds = 0.3, {use}
  settings = {{ ["gravity.uniform"] = {{ g = {{ 0, 0, 0 }} }},
               electricity_from_collisions = {{ ahead = {ahead} }} }} }}
kit.battery {{ name = "bat", at = {{ 0, 0.5 }} }}
kit.bar {{ name = "bar", material = "brass", at = {{ 0.05, 0 }}, length = 0.1, width = 0.01,
          velocity = {{ 0, {vy!r} }}, spin = {w!r}, props = {{ restitution = 0 }} }}
kit.hinge {{ name = "h", a = "bar", anchor = {{ 0, 0 }}, limits = {{ {lo!r}, 1 }} }}
kit.contact {{ name = "c", at = {{ 0.08, {yc!r} }}, size = {{ 0.02, 0.01 }}, props = {{ restitution = 0 }} }}
kit.wire {{ name = "w1", from = "bat", from_terminal = 1, to = "c" }}
kit.wire {{ name = "w0", from = "bat", from_terminal = 0, to = "bar" }}
"""
def main():
    engine = sys.argv[1] if len(sys.argv) > 1 else "ode"
    gap = float(sys.argv[2]) if len(sys.argv) > 2 else 0.0002
    n = int(sys.argv[3]) if len(sys.argv) > 3 else 240
    dt = 1.0 / n; w = 2.0; wdt = w * dt
    use = 'use = { rigid_body = "rigid_body.box2d" },' if engine == "box2d" else ""
    for k in range(8):
        thc = 0.1 + k * wdt / 8
        yc_top = (-0.005 - 0.09 * math.sin(thc)) / math.cos(thc)
        ths = thc - gap / 0.09
        res = {}
        for ahead in ("true", "false"):
            src = T.format(dt=dt, use=use, ahead=ahead, vy=-w * 0.05, w=-w, lo=-ths, yc=yc_top - 0.005)
            p = f"/tmp/a21_ph_{engine}_{k}_{ahead}.lua"; e = p + ".jsonl"
            open(p, "w").write(src)
            r = subprocess.run([ALLOY, "run", p, "--events", e, "--quiet"], capture_output=True, text=True)
            if r.returncode: res[ahead] = "ERR " + r.stderr[-200:]; continue
            ev = [json.loads(l) for l in open(e)]
            res[ahead] = [(x["step"], x["type"]) for x in ev if x["type"] in ("connected", "disconnected", "contact_began", "contact_ended")]
        print(f"{engine} phase {k}: ahead {res['true']}  | off {res['false']}")
main()
