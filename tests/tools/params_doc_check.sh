#!/usr/bin/env bash
# A parameter table of a doc (the lines between its `<!-- MARKER -->` and `<!-- /MARKER -->`)
# is what the program prints with OPTION (e.g. teleop_master --print-parameters).
# Usage: params_doc_check.sh PROGRAM OPTION MARKER DOC.md
set -euo pipefail
exe=$1
option=$2
marker=$3
doc=$4
table=$(sed -n "/^<!-- $marker -->\$/,/^<!-- \\/$marker -->\$/p" "$doc" | sed '1d;$d')
if [ -z "$table" ]; then
  echo "FAILED  $doc: no table between <!-- $marker --> and <!-- /$marker -->"
  exit 1
fi
if ! diff -u <(printf '%s\n' "$table") <("$exe" "$option"); then
  echo "FAILED  $doc: the $marker table differs from $exe $option" \
    "(lines with - are the doc's, + the program's); paste the program's output between the markers"
  exit 1
fi
echo "ok      $doc: the $marker table is $(basename "$exe") $option"
