#!/bin/sh
# Regenerate the expected outputs of the interpreter conformance corpus with
# LinuxCNC 2.9's stand-alone interpreter (Debian 12 package linuxcnc-uspace
# 2.9.0~pre1+git20230208.f1270d6ed7, /usr/bin/rs274).
#
# usage: ./make_expected.sh [NNN_topic.ngc ...]     (default: every [0-9]*.ngc)
#
# For every program NNN_topic.ngc in this folder it runs, from a scratch copy
# of this folder (so that every path is relative, rs274 may rewrite the var
# file and LOGOPEN may create files without touching the corpus):
#
#   rs274 -g -t tool.tbl -v params.var $(cat NNN_topic.args) NNN_topic.ngc \
#         </dev/null >NNN_topic.out 2>NNN_topic.err ; echo $? >NNN_topic.rc
#
# params.var is copied afresh before every program.  NNN_topic.args is
# optional (extra rs274 options, e.g. "-b" or "-i ini/corpus.ini").
# NNN_topic.out, .err and .rc are copied back into this folder, and for
# programs named *_varfile_* also NNN_topic.var: params.var as rs274
# rewrote it at exit (parameter persistence).
set -eu

RS274=${RS274:-rs274}
here=$(cd "$(dirname "$0")" && pwd)
scratch=$(mktemp -d "${TMPDIR:-/tmp}/interp_corpus.XXXXXX")
trap 'rm -rf "$scratch"' EXIT INT TERM

cd "$here"
if [ $# -eq 0 ]; then
    set -- [0-9]*.ngc
fi

# The pristine inputs: programs, sidecars, tool table, var file, INI files
# and subroutine folders.  Expected outputs are not needed in the copy.
mkdir "$scratch/corpus"
tar -C "$here" --exclude='*.out' --exclude='*.err' --exclude='*.rc' \
    --exclude='[0-9]*.var' \
    -cf - . | tar -C "$scratch/corpus" -xf -

cd "$scratch/corpus"
count=0
for prog in "$@"; do
    prog=$(basename "$prog")
    stem=${prog%.ngc}
    extra=""
    if [ -f "$stem.args" ]; then
        extra=$(cat "$stem.args")
    fi
    cp "$here/params.var" params.var
    rm -f params.var.bak
    # shellcheck disable=SC2086  # $extra is a list of options
    set +e
    timeout 30 "$RS274" -g -t tool.tbl -v params.var $extra "$prog" \
        </dev/null >"$stem.out" 2>"$stem.err"
    rc=$?
    set -e
    echo "$rc" >"$stem.rc"
    cp "$stem.out" "$stem.err" "$stem.rc" "$here/"
    case "$stem" in
        *_varfile_*) cp params.var "$here/$stem.var" ;;
    esac
    count=$((count + 1))
done

# Expected outputs must not depend on the machine.
if grep -l -e "$scratch" -e "$here" -e '/tmp/' -- "$here"/*.out "$here"/*.err 2>/dev/null; then
    echo "make_expected.sh: WARNING: absolute paths in the files above" >&2
fi
echo "make_expected.sh: $count program(s) done" >&2
