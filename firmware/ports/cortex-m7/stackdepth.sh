#!/bin/sh
# stackdepth.sh BUILD_DIR ROOT... [-- TARGET...] -- worst stack depth of the
# image from GCC's -fstack-usage / -fcallgraph-info=su output (.ci files, VCG
# format).  Calls through function pointers ('__indirect_call') are taken to
# reach any of the TARGET functions (the runtime's timed-call targets).
# Prints:
#   stack: largest frame N bytes in FUNC
#   stack: worst depth N bytes from ROOT: f1(n1) > f2(n2) > ...
# Functions without a .ci node (library code: memcpy, ...) count 0 bytes and
# are marked '?'.  Calls made from assembly are invisible to GCC: ASM_EDGES
# lists them (caller:callee), e.g. the naked Reset_Handler of startup_cm7.c,
# which sets SP and branches to cm7_reset.
set -eu
ASM_EDGES="Reset_Handler:cm7_reset"
dir=$1; shift
roots=""
while [ "$#" -gt 0 ] && [ "$1" != "--" ]; do roots="$roots $1"; shift; done
[ "$#" -gt 0 ] && shift
find "$dir" -name '*.ci' -exec cat {} + | awk -v roots="$roots" -v targets="$*" -v asm_edges="$ASM_EDGES" '
function depth(f,   i, n, best, d, k) {
    if (f in memo) return memo[f]
    if (f in busy) { recursive = 1; return 0 }
    busy[f] = 1
    best = 0; next_of[f] = ""
    n = ncallee[f]
    for (i = 1; i <= n; i++) {
        k = callee[f, i]
        d = depth(k)
        if (d > best || next_of[f] == "") { if (d >= best) { best = d; next_of[f] = k } }
    }
    delete busy[f]
    memo[f] = frame[f] + best
    return memo[f]
}
/^node:/ {
    match($0, /title: "[^"]*"/); t = substr($0, RSTART + 8, RLENGTH - 9)
    node[t] = 1
    b = 0
    if (!(t in frame)) frame[t] = 0
    # declarations of external functions carry no size: keep the size of the definition
    if (match($0, /\\n[0-9]+ bytes/)) {
        s = substr($0, RSTART + 2, RLENGTH - 2); split(s, p, " "); b = p[1] + 0
        known[t] = 1
        if (b > frame[t]) frame[t] = b
    }
    if (b > maxb) { maxb = b; maxf = t }
}
/^edge:/ {
    match($0, /sourcename: "[^"]*"/); s = substr($0, RSTART + 13, RLENGTH - 14)
    match($0, /targetname: "[^"]*"/); d = substr($0, RSTART + 13, RLENGTH - 14)
    if (!((s, d) in seen)) { seen[s, d] = 1; ncallee[s]++; callee[s, ncallee[s]] = d }
}
END {
    ne = split(asm_edges, ae, " ")
    for (i = 1; i <= ne; i++) {
        split(ae[i], e, ":")
        if ((e[1] in node) && !((e[1], e[2]) in seen)) { seen[e[1], e[2]] = 1; ncallee[e[1]]++; callee[e[1], ncallee[e[1]]] = e[2] }
    }
    nt = split(targets, tg, " ")
    for (t in node) {
        for (i = 1; i <= nt; i++) {
            if (t == tg[i] || substr(t, length(t) - length(tg[i])) == ":" tg[i]) {
                ncallee["__indirect_call"]++; callee["__indirect_call", ncallee["__indirect_call"]] = t
            }
        }
    }
    printf "stack: largest frame %d bytes in %s\n", maxb, maxf
    nr = split(roots, r, " ")
    bestd = -1
    for (i = 1; i <= nr; i++) { d = depth(r[i]); if (d > bestd) { bestd = d; bestr = r[i] } }
    line = ""
    f = bestr
    while (f != "") {
        mark = (f in known) ? "" : "?"
        line = line (line == "" ? "" : " > ") f "(" frame[f] + 0 mark ")"
        f = next_of[f]
    }
    printf "stack: worst depth %d bytes from %s: %s%s\n", bestd, bestr, line, recursive ? " (recursion ignored)" : ""
}'
