#!/usr/bin/env bash
# clang-tidy over the project's own code with the checked-in .clang-tidy (every finding an error).
#   deploy/tidy.sh --all       every translation unit of server/, client/, common/ and tests/
#   deploy/tidy.sh --changed   (CI, deploy/run_tests.sh) the units whose source changed since the
#                              commit named in .ci/tidy-clean, and for each changed header one unit
#                              that includes it (its own .cpp where there is one); the header's
#                              findings come through that unit (.clang-tidy's HeaderFilterRegex)
#   deploy/tidy.sh --all --record   as --all, and on a clean run writes HEAD's commit into
#                              .ci/tidy-clean (commit that file)
#   deploy/tidy.sh FILE...     those sources
# Reads BUILD_DIR (default: build; it must be built: the IDL's generated headers and ninja's
# dependency log are used). Exit 0 clean, 1 findings, 2 a usage or set-up error.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build_dir="${BUILD_DIR:-$root/build}"
jobs="${TIDY_JOBS:-2}"
baseline_file="$root/.ci/tidy-clean"

tidy="$(command -v clang-tidy-14 || command -v clang-tidy || true)"
if [ -z "$tidy" ]; then
  echo "deploy/tidy.sh: clang-tidy not found (apt-get install clang-tidy)" >&2
  exit 2
fi
if [ ! -f "$build_dir/compile_commands.json" ]; then
  echo "deploy/tidy.sh: $build_dir/compile_commands.json missing: build first (deploy/build.sh --tests)" >&2
  exit 2
fi

mode="" record=0 files=()
for a in "$@"; do
  case "$a" in
    --all) mode=all ;;
    --changed) mode=changed ;;
    --record) record=1 ;;
    -*)
      echo "deploy/tidy.sh: unknown argument '$a' (allowed: --all, --changed, --record, FILE...)" >&2
      exit 2
      ;;
    *) files+=("$a") ;;
  esac
done
if [ -z "$mode" ] && [ ${#files[@]} -eq 0 ]; then
  echo "deploy/tidy.sh: say --all, --changed or the files to check" >&2
  exit 2
fi
if [ "$record" = 1 ] && [ "$mode" != all ]; then
  echo "deploy/tidy.sh: --record goes with --all" >&2
  exit 2
fi

list="$(mktemp)"
trap 'rm -f "$list"' EXIT
# the project's translation units (absolute paths), one per line, from the compile database
python3 - "$build_dir/compile_commands.json" "$root" >"$list" <<'EOF'
import json, os, sys
root = os.path.realpath(sys.argv[2])
seen = set()
for e in json.load(open(sys.argv[1])):
    f = os.path.realpath(os.path.join(e["directory"], e["file"]))
    rel = os.path.relpath(f, root)
    if rel.split(os.sep)[0] in ("server", "client", "common", "tests") and f not in seen:
        seen.add(f)
        print(f)
EOF

units=()
case "$mode" in
  all) mapfile -t units <"$list" ;;
  changed)
    base="$(tr -d '[:space:]' <"$baseline_file" 2>/dev/null || true)"
    if [ -n "$base" ] && git -C "$root" merge-base --is-ancestor "$base" HEAD 2>/dev/null; then
      range="$base"
    else
      echo "deploy/tidy.sh: the clean commit in .ci/tidy-clean ('$base') is not in this history:" \
        "checking the last commit's files only" >&2
      range="HEAD~1"
    fi
    mapfile -t changed < <(git -C "$root" diff --name-only --diff-filter=d "$range" HEAD -- \
      'server/*' 'client/*' 'common/*' 'tests/*')
    echo "deploy/tidy.sh: ${#changed[@]} project files changed since ${range:0:12}"
    mapfile -t units < <(python3 - "$root" "$build_dir" "$list" "${changed[@]}" <<'EOF'
import os, subprocess, sys
root, build, listfile, changed = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4:]
units = [l.strip() for l in open(listfile) if l.strip()]
unit_set = set(units)
picked = []
def pick(u):
    if u not in picked:
        picked.append(u)
headers = []
for rel in changed:
    f = os.path.realpath(os.path.join(root, rel))
    if f in unit_set:
        pick(f)
    elif rel.endswith((".hpp", ".h", ".hh", ".ipp")):
        headers.append(f)
if headers:
    # ninja's dependency log: every header each object was compiled with
    deps = subprocess.run(["ninja", "-C", build, "-t", "deps"], capture_output=True,
                          text=True).stdout
    import json
    cc = json.load(open(os.path.join(build, "compile_commands.json")))
    obj_to_src = {}
    for e in cc:
        # the object file: the "output" key where CMake writes it, else the command's -o
        out = e.get("output")
        if out is None:
            words = e.get("command", "").split()
            if "-o" in words[:-1]:
                out = words[words.index("-o") + 1]
        if out:
            obj_to_src[os.path.normpath(out)] = os.path.realpath(
                os.path.join(e["directory"], e["file"]))
    includers = {}
    src = None
    for line in deps.splitlines():
        if line and not line.startswith(" "):
            src = obj_to_src.get(os.path.normpath(line.split(":")[0]))
        elif src in unit_set:
            h = os.path.realpath(os.path.join(build, line.strip()))
            includers.setdefault(h, []).append(src)
    for h in headers:
        own = os.path.splitext(h)[0] + ".cpp"
        users = includers.get(h, [])
        if own in users:
            pick(own)
        elif users:
            pick(sorted(users)[0])
        else:
            print("deploy/tidy.sh: no translation unit includes " + os.path.relpath(h, root),
                  file=sys.stderr)
print("\n".join(picked))
EOF
    )
    ;;
  *)
    for f in "${files[@]}"; do units+=("$(realpath "$f")"); done
    ;;
esac

if [ ${#units[@]} -eq 0 ] || [ -z "${units[0]}" ]; then
  echo "deploy/tidy.sh: nothing to check"
  exit 0
fi
echo "deploy/tidy.sh: clang-tidy ($("$tidy" --version | grep -o 'version [0-9.]*')) on ${#units[@]} translation units, $jobs at a time"
start=$(date +%s)
status=0
printf '%s\n' "${units[@]}" |
  xargs -P "$jobs" -I{} sh -c '"$0" -p "$1" --quiet "$2" 2>/dev/null || { echo "FAILED $2"; exit 1; }' \
    "$tidy" "$build_dir" {} || status=1
echo "deploy/tidy.sh: $((${#units[@]})) units in $(($(date +%s) - start)) s, $([ $status = 0 ] && echo clean || echo 'findings above')"
if [ $status = 0 ] && [ "$record" = 1 ]; then
  git -C "$root" rev-parse HEAD >"$baseline_file"
  echo "deploy/tidy.sh: .ci/tidy-clean now names $(cat "$baseline_file") (commit it)"
fi
exit $status
