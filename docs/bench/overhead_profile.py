#!/usr/bin/env python3
"""The harness's own costs in a callgrind profile of World::step.

Reads a callgrind output file (valgrind --tool=callgrind; see
docs/performance.md "Harness overhead on rigid bodies" for the commands) and
prints the top harness costs as a share of all instructions recorded (the
recording is World::step and what it calls, so 100 % is the step time).

A function is "harness" when it belongs to the runtime (runtime/: World,
WorldView, ResolverAccess, Scope, PropertyStore, PropertyRegistry, columns,
Event, Profile). Its cost is its own instructions plus those of the C and C++
library calls it makes directly (malloc, free, memcpy, string compares,
clock_gettime): what the harness spends, not the physics it calls into.

    python3 docs/bench/overhead_profile.py FILE [--top N]
"""
import re
import sys
from collections import defaultdict

HARNESS = re.compile(
    r"(^|[^:\w])alloy::(World|WorldView|ResolverAccess|Scope|PropertyStore|PropertyRegistry|"
    r"ColumnBase|Column<|ColumnWriter|ColumnView|detail::|Event|Profile|now_seconds|"
    r"PluginRegistry|PluginSettings|closest_name|frozen_message)"
    r"|std::vector<alloy::(Event|StageTiming)"
)
LIBRARY_OBJ = re.compile(r"libc\.so|libstdc\+\+|libm\.so|ld-linux|vdso")
LIBRARY_NAME = re.compile(r"^(malloc|free|_int_|operator new|operator delete|mem|str|__mem|__str|"
                          r"clock_gettime|__clock_gettime|cfree|calloc|realloc)")


def is_harness(fn):
    # The qualified name only, before the argument list: a resolver's
    # advance(alloy::ResolverAccess&) is not the harness.
    return bool(fn) and bool(HARNESS.search(fn.split("(")[0]))


def parse(path):
    """Self cost per function, direct calls (caller, callee, callee object, cost), total."""
    fns, objs = {}, {}
    self_cost = defaultdict(int)
    calls = []
    fn_obj = {}
    total = 0
    fn = ob = cfn = cob = None
    in_call = False

    def resolve(table, text):
        # "(12) name" defines id 12, "(12)" alone refers to it (name compression).
        m = re.match(r"\((\d+)\)\s*(.*)", text)
        if not m:
            return text
        key, name = m.group(1), m.group(2)
        if name:
            table[key] = name
            return name
        return table.get(key, key)

    with open(path, errors="replace") as f:
        for line in f:
            line = line.rstrip("\n")
            if not line:
                continue
            if line[0].isdigit() or line[0] in "+-*":
                parts = line.split()
                if len(parts) < 2:
                    continue
                cost = int(parts[1])
                if in_call:  # the line after calls=: the call's inclusive cost
                    calls.append((fn, cfn, cob, cost))
                    in_call = False
                    cob = None
                else:
                    self_cost[fn] += cost
                    total += cost
                continue
            key, _, value = line.partition("=")
            if key == "ob":
                ob = resolve(objs, value)
            elif key == "fn":
                fn = resolve(fns, value)
                fn_obj.setdefault(fn, ob)
            elif key == "cob":
                cob = resolve(objs, value)
            elif key == "cfn":
                cfn = resolve(fns, value)
            elif key == "calls":
                in_call = True
    calls = [(caller, callee, fn_obj.get(callee, cob if cob else ""), cost) for caller, callee, cob, cost in calls]
    return self_cost, calls, total


def short(name):
    name = re.sub(r"std::__cxx11::basic_string<char, std::char_traits<char>, std::allocator<char> >", "std::string", name)
    name = re.sub(r"std::basic_string_view<char, std::char_traits<char> >", "std::string_view", name)
    return name if len(name) <= 110 else name[:107] + "..."


def main():
    args = sys.argv[1:]
    top = 12
    if "--top" in args:
        i = args.index("--top")
        top = int(args[i + 1])
        del args[i : i + 2]
    if len(args) != 1:
        print(__doc__)
        return 2
    self_cost, calls, total = parse(args[0])
    harness = defaultdict(int)
    for fn, cost in self_cost.items():
        if is_harness(fn):
            harness[fn] += cost
    for caller, callee, obj, cost in calls:
        library = LIBRARY_OBJ.search(obj or "") or LIBRARY_NAME.match(callee or "")
        if is_harness(caller) and library and not is_harness(callee):
            harness[caller] += cost
    rows = sorted(harness.items(), key=lambda kv: -kv[1])
    all_harness = sum(harness.values())
    print(f"instructions recorded: {total:,}")
    print(f"harness total: {all_harness:,} ({100.0 * all_harness / total:.2f} %)")
    print("| harness function (own + direct library calls) | % of step |")
    print("| --- | --- |")
    for fn, cost in rows[:top]:
        print(f"| `{short(fn)}` | {100.0 * cost / total:.2f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
