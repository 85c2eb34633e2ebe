#!/usr/bin/env bash
# scripts/fuzz_changed.sh in a throwaway repository, on a binary built as scripts/fuzz.sh builds its
# targets (clang, line tables, absolute source paths). The binary holds sim/used.cc, the inline code
# of sim/inline.h and a type of sim/types.h; sim/declared.h is only included and sim/other.cc is not
# linked. After a commit that changes all five files, only the first three may be named.
set -euo pipefail
command -v clang++ >/dev/null || { echo "FAIL: clang++ not found (scripts/setup.sh installs it)" >&2; exit 1; }
script="$(cd "$(dirname "$0")/../.." && pwd)/scripts/fuzz_changed.sh"
repo=$(mktemp -d)
trap 'rm -rf "$repo"' EXIT
cd "$repo"
fail() { echo "FAIL: $*" >&2; exit 1; }
expect() {  # expect WANTED_OUTPUT WANTED_STATUS ARGS...: run the script, compare output and status
  local wanted="$1" wanted_status="$2" got status=0
  shift 2
  got=$(scripts/fuzz_changed.sh "$@" 2>&1) || status=$?
  [ "$status" = "$wanted_status" ] || fail "fuzz_changed.sh $* exited $status, not $wanted_status: $got"
  [ "$got" = "$wanted" ] || fail "fuzz_changed.sh $* printed '$got', not '$wanted'"
}
commit() { git add -A && git -c user.name=test -c user.email=test@example.invalid commit -q -m "$1"; }

git init -q .
mkdir -p scripts sim fuzz build-fuzz/bin
cp "$script" scripts/
printf 'inline int Twice(int v) { return 2 * v; }\n' >sim/inline.h
printf 'struct Pair { int first, second; };\n' >sim/types.h
printf 'int Declared(int v);\n' >sim/declared.h
printf '#include "sim/declared.h"\n#include "sim/inline.h"\n#include "sim/types.h"\n' >sim/used.cc
printf 'int Used(int v) { Pair pair{v, 0}; return Twice(pair.first); }\n' >>sim/used.cc
printf 'int Other() { return 3; }\n' >sim/other.cc
printf 'int Used(int v);\nint main(int argc, char**) { return Used(argc) == 2 ? 0 : 1; }\n' >fuzz/x_fuzz.cc
commit first
first=$(git rev-parse HEAD)
clang++ -g -O0 -I"$repo" -o build-fuzz/bin/x_fuzz "$repo/sim/used.cc" "$repo/fuzz/x_fuzz.cc"

expect "x: unchanged since $first" 0 "$first" x
for f in sim/inline.h sim/types.h sim/declared.h sim/used.cc sim/other.cc; do printf '// changed\n' >>"$f"; done
commit second
expect "x: sim/inline.h sim/types.h sim/used.cc " 0 "$first" x
expect "x: unchanged since HEAD" 0 HEAD x
expect "x: sim/inline.h sim/types.h sim/used.cc " 0 --build build-fuzz "$first" x
# A binary built from another copy of the tree (another worktree), compiled from inside its build
# folder as CMake does: the files are found by their place in that copy.
copy="$repo/copy"
mkdir -p "$copy/build/bin" && cp -r sim fuzz "$copy"
(cd "$copy/build" && clang++ -g -O0 -I"$copy" -o bin/x_fuzz "$copy/sim/used.cc" "$copy/fuzz/x_fuzz.cc")
expect "x: sim/inline.h sim/types.h sim/used.cc " 0 --build "$copy/build" "$first" x

expect "fuzz_changed.sh: no-such-commit is not a commit here" 2 no-such-commit x
expect "fuzz_changed.sh: build-fuzz/bin/y_fuzz not built (scripts/fuzz.sh builds it)" 2 HEAD y
strip -g -o build-fuzz/bin/z_fuzz build-fuzz/bin/x_fuzz
expect "fuzz_changed.sh: build-fuzz/bin/z_fuzz has no line tables (build it with -g)" 2 HEAD z
expect "usage: scripts/fuzz_changed.sh [--build DIR] COMMIT TARGET..." 2 HEAD
echo "fuzz_changed.sh: all cases pass"
