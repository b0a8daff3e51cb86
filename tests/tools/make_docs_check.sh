#!/usr/bin/env bash
# deploy/make_docs.sh --check on this checkout passes, and on a copy of the docs it finds a
# picture without a recipe and a link to a picture that does not exist.
set -uo pipefail
src="$1"
bash "$src/deploy/make_docs.sh" --check "$src" || { echo "FAIL: --check on the checkout"; exit 1; }
tmp="$(mktemp -d /tmp/teleop_make_docs_check.XXXXXX)"
trap 'rm -rf "$tmp"' EXIT
mkdir -p "$tmp/docs"
cp -r "$src/docs/results" "$tmp/docs/results"
cp "$src"/docs/*.md "$tmp/docs/"
cp "$src/README.md" "$tmp/README.md"
: >"$tmp/docs/results/stray.png"
echo "![gone](results/gone.png)" >>"$tmp/docs/tools.md"
out="$(bash "$src/deploy/make_docs.sh" --check "$tmp" 2>&1)"
status=$?
echo "$out"
[ "$status" -eq 1 ] || { echo "FAIL: --check exited $status on a stray picture and a dead link"; exit 1; }
grep -q "stray.png has no recipe" <<<"$out" || { echo "FAIL: the stray picture not named"; exit 1; }
grep -q "results/gone.png, which does not exist" <<<"$out" || { echo "FAIL: the dead link not named"; exit 1; }
echo "PASS"
