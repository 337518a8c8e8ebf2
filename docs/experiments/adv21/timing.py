#!/usr/bin/env python3
"""adv21 timing sweep: a brass bar glides at V onto a contact (glide template).
For each engine, dt, touch fraction: the step whose advance first carries the
connection, with and without `ahead`. Prints the connect boundary time minus
the touch time, in steps. Promise: with ahead in [-0.5, +1) and never later
than without."""
import json, os, subprocess, sys, tempfile
ALLOY = os.environ.get("ALLOY", "build/apps/alloy")
TEMPLATE = """local kit = require "kit"
world {{ dt = {dt!r}, seconds = {secs!r}, {use}
  settings = {{ ["gravity.uniform"] = {{ g = {{ 0, 0, 0 }} }},
               electricity_from_collisions = {{ ahead = {ahead} }} }} }}
kit.battery {{ name = "bat", at = {{ 0, 0.5 }} }}
kit.contact {{ name = "c", at = {{ 0.01, 0 }} }}
kit.bar {{ name = "bar", material = "brass", at = {{ {x!r}, 0 }}, length = 0.1, width = 0.01,
          velocity = {{ {v!r}, 0 }}, angle = {ang!r}, spin = {spin!r} }}
kit.wire {{ name = "w1", from = "bat", from_terminal = 1, to = "c" }}
kit.wire {{ name = "w0", from = "bat", from_terminal = 0, to = "bar" }}
"""
def run(dt, gap, v, ahead, engine, ang=0.0, spin=0.0, steps_to=None):
    use = 'use = { rigid_body = "rigid_body.box2d" },' if engine == "box2d" else ""
    t_touch = gap / v
    secs = t_touch + 6 * dt
    src = TEMPLATE.format(dt=dt, secs=secs, use=use, ahead="true" if ahead else "false",
                          x=-gap - 0.05, v=v, ang=ang, spin=spin)
    with tempfile.TemporaryDirectory() as d:
        p = os.path.join(d, "s.lua"); e = os.path.join(d, "e.jsonl")
        open(p, "w").write(src)
        r = subprocess.run([ALLOY, "run", p, "--events", e, "--quiet"], capture_output=True, text=True)
        if r.returncode != 0:
            return None, r.stderr[-300:]
        ev = [json.loads(l) for l in open(e)]
    began = [x["step"] for x in ev if x["type"] == "contact_began"]
    conn = [x["step"] for x in ev if x["type"] == "connected"]
    disc = [x["step"] for x in ev if x["type"] == "disconnected"]
    return (began[:1], conn[:1], disc[:1]), None

if __name__ == "__main__":
    v = float(sys.argv[1]) if len(sys.argv) > 1 else 0.2
    engines = sys.argv[2].split(",") if len(sys.argv) > 2 else ["ode", "box2d"]
    for engine in engines:
        for n in (60, 240, 1920):
            dt = 1.0 / n
            for k in (5, 20):
                for f in (0.05, 0.3, 0.45, 0.55, 0.7, 0.95):
                    t = (k - 1 + f) * dt       # touch inside step k at fraction f
                    gap = t * v
                    a, err = run(dt, gap, v, True, engine)
                    b, err2 = run(dt, gap, v, False, engine)
                    if a is None or b is None:
                        print(engine, n, k, f, "ERROR", err or err2); continue
                    ca = a[1][0] if a[1] else None; cb = b[1][0] if b[1] else None
                    # connect boundary = start of the step whose advance carries it = (step-1)*dt
                    da = None if ca is None else (ca - 1) - (k - 1 + f)
                    db = None if cb is None else (cb - 1) - (k - 1 + f)
                    flag = ""
                    if da is None: flag = "NOCONNECT"
                    elif da < -0.5 - 1e-9: flag = "EARLY>half"
                    elif db is not None and da > db: flag = "LATER"
                    print(f"{engine:5s} 1/{n:<5d} step {k:2d} f={f:.2f} began(a)={a[0]} conn ahead={ca} off={cb} "
                          f"early_by(ahead)={da if da is None else round(da,3)} off={db if db is None else round(db,3)} "
                          f"disc(a)={a[2]} {flag}")
