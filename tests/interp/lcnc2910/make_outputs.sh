#!/bin/sh
# Record, for every program here, the output of the installed LinuxCNC rs274 (the base,
# NAME.rs274.out/.err/.rc) and of ours (the expected 2.9.10 behaviour, NAME.out/.err/.rc).
#
# usage: ./make_outputs.sh [NAME.ngc ...]     (default: every *.ngc)
#
# Both run from a scratch copy of this folder, with a fresh params.var, as
#
#   timeout 10 rs274 -g -t tool.tbl -v params.var NAME.ngc </dev/null     (Debian 12
#       linuxcnc-uspace 2.9.0~pre1+git20230208.f1270d6ed7, /usr/bin/rs274)
#   cnc rs274 -g -t tool.tbl -v params.var NAME.ngc </dev/null
#
# A base run that does not end within 10 s (the endless loops 2.9.10 fixed) records
# rc 124 and no output (it would be endless).  Our outputs are checked by hand against
# the 2.9.10 change each program demonstrates (README.md) before they are committed.
set -eu

RS274=${RS274:-rs274}
here=$(cd "$(dirname "$0")" && pwd)
cnc=${CNC:-$here/../../../.venv/bin/cnc}
scratch=$(mktemp -d "${TMPDIR:-/tmp}/lcnc2910.XXXXXX")
trap 'rm -rf "$scratch"' EXIT INT TERM

cd "$here"
if [ $# -eq 0 ]; then
    set -- *.ngc
fi
for program in "$@"; do
    name=${program%.ngc}
    for who in rs274 ours; do
        rm -rf "$scratch/w" && mkdir "$scratch/w"
        cp "$program" tool.tbl params.var "$scratch/w/"
        if [ "$who" = rs274 ]; then
            suffix=.rs274
            set +e
            (cd "$scratch/w" && timeout 10 "$RS274" -g -t tool.tbl -v params.var "$program" \
                </dev/null >out 2>err)
            rc=$?
            set -e
            if [ "$rc" = 124 ]; then
                : >"$scratch/w/out"
                echo "(killed after 10 s: rs274 did not end)" >"$scratch/w/err"
            fi
        else
            suffix=
            set +e
            (cd "$scratch/w" && "$cnc" rs274 -g -t tool.tbl -v params.var "$program" \
                </dev/null >out 2>err)
            rc=$?
            set -e
        fi
        cp "$scratch/w/out" "$name$suffix.out"
        cp "$scratch/w/err" "$name$suffix.err"
        echo "$rc" >"$name$suffix.rc"
    done
    echo "$name: rs274 exit $(cat "$name.rs274.rc"), ours exit $(cat "$name.rc")"
done
