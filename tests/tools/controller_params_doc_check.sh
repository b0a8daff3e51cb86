#!/usr/bin/env bash
# docs/configuration.md's table of the controller's parameters (the lines between its
# `<!-- controller-parameters -->` markers) is what `teleop_master --print-parameters` prints.
# Usage: controller_params_doc_check.sh TELEOP_MASTER DOC.md
set -euo pipefail
exe=$1
doc=$2
if ! diff -u \
  <(sed -n '/^<!-- controller-parameters -->$/,/^<!-- \/controller-parameters -->$/p' "$doc" |
    sed '1d;$d') \
  <("$exe" --print-parameters); then
  echo "FAILED  $doc: the controller's parameter table differs from $exe --print-parameters" \
    "(lines with - are the doc's, + the program's); paste the program's output between the markers"
  exit 1
fi
echo "ok      $doc: the controller's parameter table is teleop_master --print-parameters"
