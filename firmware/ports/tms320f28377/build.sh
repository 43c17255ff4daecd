#!/bin/sh
# build.sh OUTDIR -IDIR... -- SOURCE.c... : build OUTDIR/fw.out for the
# TMS320F28377S with TI's C2000 compiler (cl2000), from the project root.
# cl2000 is taken from $CL2000, else $C2000_CGT_ROOT/bin, else PATH.
set -eu
out=$1
shift
port=$(dirname "$0")

cl=${CL2000:-}
if [ -z "$cl" ]; then
    if [ -n "${C2000_CGT_ROOT:-}" ] && [ -x "$C2000_CGT_ROOT/bin/cl2000" ]; then
        cl=$C2000_CGT_ROOT/bin/cl2000
    elif command -v cl2000 >/dev/null 2>&1; then
        cl=$(command -v cl2000)
    else
        echo "build.sh: cl2000 not found: TI's C2000 code generation tools are not packaged by Debian;" \
             "install Code Composer Studio or the C2000 CGT and put cl2000 on PATH (or set C2000_CGT_ROOT)" >&2
        exit 2
    fi
fi
cgt=$(dirname "$(dirname "$cl")")

incs=""
while [ "$#" -gt 0 ] && [ "$1" != "--" ]; do
    incs="$incs $1"
    shift
done
[ "$#" -gt 0 ] && shift

# C99, large memory model, FPU32, EABI; strict IEEE-style float (no
# reassociation, no TMU: sqrtf and division stay library/IEEE operations);
# every warning is an error.
flags="-v28 -ml -mt --float_support=fpu32 --abi=eabi --c99 -O2 --fp_mode=strict --fp_reassoc=off
       --define=MPC_TARGET_C28X --define=MPCGEN_FP_CONTRACT_OFF=1 --display_error_number --emit_warnings_as_errors -I$cgt/include"

mkdir -p "$out"
objs=""
for src in "$@"; do
    obj="$out/$(echo "$src" | tr '/' '_' | sed 's/\.c$/.obj/')"
    # shellcheck disable=SC2086
    "$cl" $flags $incs --output_file="$obj" -c "$src"
    objs="$objs $obj"
done
# shellcheck disable=SC2086
"$cl" $flags -z --rom_model --stack_size=0x400 --heap_size=0 --reread_libs --entry_point=code_start \
    -m"$out/fw.map" -i"$cgt/lib" -o "$out/fw.out" $objs "$port/f28377s.cmd" -llibc.a
echo "built $out/fw.out (see $out/fw.map)"
