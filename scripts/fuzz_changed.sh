#!/usr/bin/env bash
# Which of the project's files, whose code a fuzz target runs, changed since a commit: a target's
# campaign counts for the current code only if this prints nothing. The files are those the target
# binary's line tables (DWARF 5, clang's default) name: every .cc file, and every header whose
# inline code or types the binary uses or whose functions it calls; a header merely included is
# not named. Nor is a header that holds only macros: the one header of ours with macros,
# sim/check.h, also holds code, so it is named.
#
#   scripts/fuzz_changed.sh COMMIT TARGET...       with the fuzz build in build-fuzz
#   scripts/fuzz_changed.sh --build DIR COMMIT TARGET...
#
# Prints "TARGET: unchanged since COMMIT" or "TARGET: FILE FILE ...", one line a target.
set -euo pipefail
cd "$(dirname "$0")/.."
die() { echo "fuzz_changed.sh: $*" >&2; exit 2; }
build=build-fuzz
if [ "${1:-}" = --build ]; then build="$2"; shift 2; fi
if [ $# -lt 2 ]; then
  echo "usage: scripts/fuzz_changed.sh [--build DIR] COMMIT TARGET..." >&2
  exit 2
fi
commit="$1"
shift
command -v readelf >/dev/null || die "readelf not found (Debian's binutils)"
git rev-parse --verify --quiet "$commit^{commit}" >/dev/null || die "$commit is not a commit here"
for t in "$@"; do
  binary="$build/bin/${t}_fuzz"
  [ -x "$binary" ] || die "$binary not built (scripts/fuzz.sh builds it)"
  # Every file of the line tables as a whole path: its directory entry joined with its name (clang
  # names a file relative to the -I folder it was found through, or to the compilation folder).
  # Before DWARF 5 the compilation folder is not in the line table, so such tables are refused.
  mapfile -t paths < <(readelf --debug-dump=rawline "$binary" | awk '
    /DWARF Version:/ && $NF + 0 < 5 { old = 1 }
    /The Directory Table/ { table = "dir"; split("", dir); next }
    /The File Name Table/ { table = "file"; next }
    table != "" && $1 !~ /^[0-9]+$/ { if ($0 !~ /Entry/) table = ""; next }
    table != "" {
      name = $0
      sub(/^[^)]*\): /, "", name)  # the text after "(indirect line string, offset: N): "
      if (table == "dir") dir[$1] = name
      else print (name ~ /^\// ? name : dir[$2] "/" name)
    }
    END { if (old) print "!old" }' | sort -u)
  # No files would make the git diff below list every changed file of the tree.
  [ ${#paths[@]} -gt 0 ] || die "$binary has no line tables (build it with -g)"
  # The binary's source tree is the folder that holds its fuzz/TARGET_fuzz.cc; it need not be this
  # one (a build of another worktree), but it must be one.
  root=
  for p in "${paths[@]}"; do
    [ "$p" != "!old" ] || die "$binary has line tables older than DWARF 5 (build it with -gdwarf-5)"
    tree="${p%/fuzz/${t}_fuzz.cc}"
    [ "$tree" != "$p" ] || continue
    [ -z "$root" ] || [ "$root" = "$tree" ] ||
      die "$binary was built from two trees, $root and $tree"
    root="$tree"
  done
  [ -n "$root" ] || die "$binary names no fuzz/${t}_fuzz.cc in its line tables"
  # Files outside the tree (system and library headers) come out absolute and are left out.
  mapfile -t files < <(realpath -m --relative-base="$root" -- "${paths[@]}" |
    grep -v -E '^/|^\.' | sort -u)
  changed=$(git diff --name-only "$commit" HEAD -- "${files[@]}" | tr '\n' ' ')
  echo "$t: ${changed:-unchanged since $commit}"
done
