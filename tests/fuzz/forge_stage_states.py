#!/usr/bin/env python3
# Usage: tests/fuzz/forge_stage_states.py ALLOY SOURCE_TREE OUT_DIR [CHANGES_PER_STAGE [SCENES]]
# e.g.   tests/fuzz/forge_stage_states.py build/apps/alloy . /tmp/forged 80
# (docs/security.md, "A forged save"). Needs libxxhash and libzstd (Debian).
# Forge the stage-state section (SSTA) of saves of every bundled scene: each
# stage's own bytes get one value changed (NaN, 1e300, -1, 0, huge ints, a
# byte flipped) or are cut/extended; the checksum is rebuilt, so the reader
# of that stage sees the damage. Then `alloy check` and `alloy run --steps 10`.
# A finding: a signal (rc >= 128), a timeout (124), or rc not in {0, 2}.
import struct, subprocess, sys, random, os

# The save container (runtime/save_file.cpp): magic, format, flags, sizes,
# XXH3-64 of everything but itself, meta, body (zstd when flags & 1).
import ctypes
lib=ctypes.CDLL("libxxhash.so.0"); lib.XXH3_64bits.restype=ctypes.c_uint64; lib.XXH3_64bits.argtypes=[ctypes.c_char_p, ctypes.c_size_t]
zs=ctypes.CDLL("libzstd.so.1"); zs.ZSTD_decompress.restype=ctypes.c_size_t
def parse(b):
    fmt,flags,ms,sb,rb=struct.unpack('<IIQQQ',b[8:40])
    meta=b[48:48+ms]; body=b[48+ms:48+ms+sb]
    if flags&1:
        out=ctypes.create_string_buffer(rb)
        n=zs.ZSTD_decompress(out, ctypes.c_size_t(rb), body, ctypes.c_size_t(len(body)))
        body=out.raw[:n]
    return fmt,meta,body
def build(meta, body, fmt=1, raw=None):
    pre=b'ALLOYSAV'+struct.pack('<IIQQQ',fmt,0,len(meta),len(body),len(body) if raw is None else raw)
    h=lib.XXH3_64bits(pre+meta+body, len(pre)+len(meta)+len(body))
    return pre+struct.pack('<Q',h)+meta+body
def sections(body):
    i=0; out=[]
    while i+12<=len(body):
        tag=body[i:i+4]; n=struct.unpack('<Q',body[i+4:i+12])[0]; out.append((tag,i,n)); i+=12+n
    return out

ALLOY = sys.argv[1]
ROOT = sys.argv[2]          # a source tree (mods/)
OUT = sys.argv[3]
PER_STAGE = int(sys.argv[4]) if len(sys.argv) > 4 else 25
os.makedirs(OUT, exist_ok=True)
rnd = random.Random(16)

def u64(b, i): return struct.unpack_from('<Q', b, i)[0]

def ssta_states(body):
    for tag, i, n in sections(body):
        if tag == b'SSTA':
            j = i + 12; end = j + n
            count = u64(body, j); j += 8
            out = []
            for _ in range(count):
                ln = u64(body, j); j += 8
                name = body[j:j+ln].decode(); j += ln
                bl = u64(body, j); j += 8
                out.append((name, j, bl)); j += bl
            return i, n, out
    raise SystemExit('no SSTA')

def replace_stage(body, sec_i, sec_n, states, k, new_bytes):
    name, j, bl = states[k]
    nb = body[:j-8] + struct.pack('<Q', len(new_bytes)) + new_bytes + body[j+bl:]
    delta = len(new_bytes) - bl
    # fix the SSTA section's size
    nb = nb[:sec_i+4] + struct.pack('<Q', sec_n + delta) + nb[sec_i+12:]
    return nb

VALUES = [struct.pack('<d', float('nan')), struct.pack('<d', 1e300), struct.pack('<d', -1.0),
          struct.pack('<d', 0.0), struct.pack('<Q', 0xFFFFFFFFFFFFFFFF), struct.pack('<Q', 1 << 40),
          struct.pack('<I', 0xFFFFFFFF), struct.pack('<I', 7), struct.pack('<d', float('inf'))]

def mutations(bts):
    n = len(bts)
    muts = []
    for _ in range(PER_STAGE):
        r = rnd.random()
        if n == 0 or r < 0.08:
            cut = rnd.randint(0, max(0, n - 1)); muts.append(('cut%d' % cut, bts[:cut]))
        elif r < 0.14:
            muts.append(('ext', bts + bytes(rnd.randrange(256) for _ in range(rnd.randint(1, 16)))))
        elif r < 0.3:
            i = rnd.randrange(n); b = bytearray(bts); b[i] ^= 1 << rnd.randrange(8)
            muts.append(('flip%d' % i, bytes(b)))
        else:
            v = rnd.choice(VALUES)
            if n < len(v): continue
            i = rnd.randrange(0, n - len(v) + 1)
            if len(v) == 8: i -= i % 4
            b = bytearray(bts); b[i:i+len(v)] = v
            muts.append(('v%d_%s' % (i, v.hex()[:6]), bytes(b)))
    return muts

scenes = sys.argv[5].split(',') if len(sys.argv) > 5 else ['doorbell','motor','hoist','generator','rigid_demo','two_engines','magic','space']
findings = []; total = 0; codes = {}
for sc in scenes:
    base = os.path.join(OUT, sc + '.alloysave')
    r = subprocess.run(['timeout', '60', ALLOY, 'run', os.path.join(ROOT, 'mods', sc), '--seconds', '0.5', '--quiet', '--save', base], cwd=ROOT, capture_output=True, text=True)
    if r.returncode != 0:
        print('cannot save', sc, r.returncode, r.stderr[:300]); continue
    fmt, meta, body = parse(open(base, 'rb').read())
    sec_i, sec_n, states = ssta_states(body)
    print(sc, [(s[0], s[2]) for s in states], flush=True)
    for k, (name, j, bl) in enumerate(states):
        for tag, nbts in mutations(body[j:j+bl]):
            nb = replace_stage(body, sec_i, sec_n, states, k, nbts)
            f = os.path.join(OUT, 'case.alloysave')
            open(f, 'wb').write(build(meta, nb))
            for cmd in (['check', f], ['run', f, '--steps', '10', '--quiet']):
                total += 1
                p = subprocess.run(['timeout', '20', ALLOY] + cmd, cwd=ROOT, capture_output=True, text=True)
                codes[p.returncode] = codes.get(p.returncode, 0) + 1
                if p.returncode not in (0, 2):
                    keep = os.path.join(OUT, 'find_%s_%s_%s.alloysave' % (sc, name, tag))
                    open(keep, 'wb').write(open(f, 'rb').read())
                    findings.append((sc, name, tag, cmd[0], p.returncode, (p.stderr or p.stdout)[-300:]))
                    print('FINDING', findings[-1], flush=True)
print('runs', total, 'exit codes', codes, 'findings', len(findings))
