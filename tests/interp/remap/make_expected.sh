#!/bin/bash
# Record what LinuxCNC 2.9's rs274 prints for the programs of each scenario of this folder
# (see README.md).
#
#   ./make_expected.sh [scenario ...]        (default: every scenario)
#
# Each program prog*.ngc of a scenario runs in a scratch copy of the scenario's folder, with
# this project's standard glue folder (task/interp/python/glue) copied in as glue/, as:
#
#   rs274 -g -i test.ini $(cat args) prog.ngc </dev/null >prog.out 2>prog.err
#   echo $? >prog.rc
#
# (with PYTHONUNBUFFERED=1, so that Python's output keeps its place in rs274's), and the
# scratch folder's path in the outputs (Python tracebacks) replaced by SCRATCH.
set -eu
here=$(cd "$(dirname "$0")" && pwd)
glue="$here/../../../task/interp/python/glue"
command -v rs274 >/dev/null || { echo "rs274 (LinuxCNC) is not installed" >&2; exit 1; }
if [ $# -eq 0 ]; then
    set -- $(cd "$here" && ls -d */ | tr -d /)
fi
scratch=$(mktemp -d "${TMPDIR:-/tmp}/remap-expected.XXXXXX")
trap 'rm -rf "$scratch"' EXIT
for name in "$@"; do
    name=${name%/}
    args=$(cat "$here/$name/args" 2>/dev/null || true)
    for program in "$here/$name"/prog*.ngc; do
        base=$(basename "$program" .ngc)
        work="$scratch/$name.$base"
        mkdir -p "$work/glue"
        (cd "$here/$name" && tar -c --exclude='prog*.out' --exclude='prog*.err' \
            --exclude='prog*.rc' --exclude='__pycache__' .) | tar -x -C "$work"
        cp "$glue/stdglue.py" "$work/glue/"
        set +e
        (cd "$work" && PYTHONUNBUFFERED=1 timeout 60 rs274 -g -i test.ini $args "$base.ngc" \
            </dev/null >"$here/$name/$base.out" 2>"$here/$name/$base.err")
        echo $? >"$here/$name/$base.rc"
        set -e
        # Python tracebacks name the scratch folder: SCRATCH stands for it
        sed -i "s|$work|SCRATCH|g" "$here/$name/$base.out" "$here/$name/$base.err"
        echo "$name/$base: exit status $(cat "$here/$name/$base.rc")"
    done
done
