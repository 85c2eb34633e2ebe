#!/usr/bin/env bash
# Which of the project's files, whose code a fuzz target runs, changed since a commit: a target's
# campaign counts for the current code only if this prints nothing. The files are read from the
# target binary's line tables: every .cc file, and every header whose code or types the binary
# uses (an inline function, a struct); a header merely included, or only declaring, does not count.
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
  # Every file of the line tables as a whole path: its directory entry joined with its name (clang
  # names a file relative to the -I folder it was found through, or to the compilation folder).
  mapfile -t paths < <(readelf --debug-dump=rawline "$binary" 2>/dev/null | awk '
    /The Directory Table/ { table = "dir"; split("", dir); next }
    /The File Name Table/ { table = "file"; next }
    table != "" && $1 !~ /^[0-9]+$/ { if ($0 !~ /Entry/) table = ""; next }
    {
      name = $0
      if (!sub(/^[^)]*\): /, "", name)) name = $NF  # after "(indirect line string, offset: N): "
      if (table == "dir") { dir[$1] = name; next }
      if (table == "file") print (name ~ /^\// ? name : dir[$2] "/" name)
    }' | sort -u)
  # No files would make the git diff below list every changed file of the tree.
  [ ${#paths[@]} -gt 0 ] || { echo "fuzz_changed.sh: $binary has no line tables (build it with -g)" >&2; exit 2; }
  # The binary's source tree is the folder that holds its fuzz/TARGET_fuzz.cc; it need not be this one.
  root=
  for p in "${paths[@]}"; do
    [ "${p%/fuzz/${t}_fuzz.cc}" != "$p" ] && { root="${p%/fuzz/${t}_fuzz.cc}"; break; }
  done
  [ -n "$root" ] || { echo "fuzz_changed.sh: $binary names no fuzz/${t}_fuzz.cc in its line tables" >&2; exit 2; }
  mapfile -t files < <(realpath -m --relative-base="$root" -- "${paths[@]}" | grep -v -E '^/|^\.' | sort -u)
  changed=$(git diff --name-only "$commit" HEAD -- "${files[@]}" | tr '\n' ' ')
  echo "$t: ${changed:-unchanged since $commit}"
done
