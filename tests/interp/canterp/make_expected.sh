#!/bin/sh
# Regenerates the expected outputs with LinuxCNC 2.9's rs274 and its canterp.so plug-in:
#   cd tests/interp/canterp && sh make_expected.sh
set -u
for f in replay calls; do
    rs274 -p canterp.so -t tool.tbl -g $f.can > $f.out 2> $f.err; echo $? > $f.rc
done
rs274 -p canterp.so -t tool.tbl -g errors.can > errors-stop.out 2> errors-stop.err; echo $? > errors-stop.rc
rs274 -p canterp.so -t tool.tbl -n 0 -g errors.can > errors-continue.out 2> errors-continue.err
echo $? > errors-continue.rc
