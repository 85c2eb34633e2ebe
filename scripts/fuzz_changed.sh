#!/usr/bin/env bash
# Which of the project's files, whose code a fuzz target runs, changed since a commit: a target's
# campaign counts for the current code only if this prints nothing. The files are read from the
# target binary's line tables (every .cc and header with code in it), so a file merely included
# does not count and an inline function of a header does.
#
#   scripts/fuzz_changed.sh COMMIT TARGET...       with the fuzz build in build-fuzz
#   scripts/fuzz_changed.sh --build DIR COMMIT TARGET...
#
# Prints "TARGET: unchanged since COMMIT" or "TARGET: FILE FILE ...", one line a target.
set -euo pipefail
cd "$(dirname "$0")/.."
build=build-fuzz
if [ "${1:-}" = --build ]; then build="$2"; shift 2; fi
if [ $# -lt 2 ]; then
  echo "usage: scripts/fuzz_changed.sh [--build DIR] COMMIT TARGET..." >&2
  exit 2
fi
commit="$1"
shift
git rev-parse --verify --quiet "$commit^{commit}" >/dev/null ||
  { echo "fuzz_changed.sh: $commit is not a commit here" >&2; exit 2; }
for t in "$@"; do
  binary="$build/bin/${t}_fuzz"
  [ -x "$binary" ] || { echo "fuzz_changed.sh: $binary not built (scripts/fuzz.sh builds it)" >&2; exit 2; }
  mapfile -t files < <(readelf --debug-dump=rawline "$binary" 2>/dev/null |
    grep -o -E '(sim|render|estimate|fuzz)/[A-Za-z0-9_/]+\.(cc|h)$' | sort -u)
  # No files would make the git diff below list every changed file of the tree.
  [ ${#files[@]} -gt 0 ] || { echo "fuzz_changed.sh: $binary has no line tables (build it with -g)" >&2; exit 2; }
  changed=$(git diff --name-only "$commit" HEAD -- "${files[@]}" | tr '\n' ' ')
  echo "$t: ${changed:-unchanged since $commit}"
done
