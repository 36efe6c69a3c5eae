#!/usr/bin/env bash
# Regenerates the expected outputs of the benchmark programs (copied from ../shared/reference/programs)
# with LinuxCNC 2.9's rs274, exactly as tests/interp/corpus/make_expected.sh does for the corpus:
# from a scratch copy of this folder, with a fresh params.var for every program.
#   rs274 -g -t tool.tbl -v params.var PROG.ngc </dev/null >PROG.out 2>PROG.err; echo $? >PROG.rc
# tool.tbl is LinuxCNC's sample-configs/sim/sim_mm.tbl (rs274 reads it in inches).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
cd "$here"
progs=("$@")
[ ${#progs[@]} -gt 0 ] || progs=(*.ngc)
scratch=$(mktemp -d "${TMPDIR:-/tmp}/interp-programs.XXXXXX")
trap 'rm -rf "$scratch"' EXIT
for prog in "${progs[@]}"; do
    name=${prog%.ngc}
    rm -rf "$scratch/w"; mkdir "$scratch/w"
    cp tool.tbl params.var "$name.ngc" "$scratch/w/"
    (cd "$scratch/w" && { rs274 -g -t tool.tbl -v params.var "$name.ngc" </dev/null >"$name.out" 2>"$name.err"; echo $? >"$name.rc"; } || true)
    cp "$scratch/w/$name.out" "$scratch/w/$name.err" "$scratch/w/$name.rc" .
done
