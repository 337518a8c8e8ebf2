#!/bin/bash
# usage: restore_events.sh SCENE N M [args]: the events of steps N+1..N+M of a
# straight run against those of a run saved at step N and continued M steps.
# Prints the first difference (or "events identical").
S=$1; N=$2; M=$3; shift 3
A=${ALLOY:-build/apps/alloy}; T=/tmp/adv21_re_$$
$A run $S --steps $((N+M)) --quiet --events $T.a.jsonl "$@" >/dev/null 2>&1
$A run $S --steps $N --quiet --save $T.alloysave "$@" >/dev/null 2>&1
$A run $T.alloysave --steps $M --quiet --events $T.b.jsonl >/dev/null 2>&1
python3 - $T.a.jsonl $T.b.jsonl $N "$S $N+$M $*" <<'PY'
import json, sys
def load(p, n):
    out = []
    for l in open(p):
        x = json.loads(l)
        if x["step"] <= n or x["type"] in ("resolver_swapped", "report"): continue
        if x["type"] in ("connected", "disconnected", "circuit_closed", "circuit_opened", "contact_began", "contact_ended"):
            out.append((x["step"], x["type"], x.get("a"), x.get("b")))
    return sorted(out)
n = int(sys.argv[3]); a = load(sys.argv[1], n); b = load(sys.argv[2], n)
if a == b: print(f"events identical ({len(a)})  {sys.argv[4]}"); sys.exit()
d = next(i for i in range(min(len(a), len(b)) + 1) if i >= min(len(a), len(b)) or a[i] != b[i])
print(f"events DIFFER at #{d} of {len(a)}/{len(b)}  {sys.argv[4]}\n  straight {a[max(0,d-1):d+4]}\n  restored {b[max(0,d-1):d+4]}")
PY
rm -f $T.*
