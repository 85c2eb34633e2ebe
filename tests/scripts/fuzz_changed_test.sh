#!/usr/bin/env bash
# scripts/fuzz_changed.sh in a throwaway repository, on a binary built as scripts/fuzz.sh builds its
# targets (clang, -O2 with DWARF 5 line tables, absolute source paths), in a folder whose name
# holds a space and a parenthesis. The binary holds sim/used.cc, the inline code of sim/inline.h, a
# type of sim/types.h and a function of <cstring>; sim/declared.h is only included and sim/other.cc
# is not linked. After a commit that changes all five files, only the first three may be named.
set -euo pipefail
fail() { echo "FAIL: $*" >&2; exit 1; }
command -v clang++ >/dev/null || fail "clang++ not found (scripts/setup.sh installs it)"
script="$(cd "$(dirname "$0")/../.." && pwd)/scripts/fuzz_changed.sh"
# The throwaway repository must not reach the one this test runs in (GIT_DIR is set inside git
# hooks), nor depend on the user's git settings (identity, signed commits).
unset GIT_DIR GIT_WORK_TREE GIT_INDEX_FILE GIT_OBJECT_DIRECTORY GIT_COMMON_DIR
export GIT_CONFIG_NOSYSTEM=1 GIT_CONFIG_GLOBAL=/dev/null
repo=$(mktemp -d "${TMPDIR:-/tmp}/fuzz changed (test).XXXXXX")
trap 'rm -rf "$repo"' EXIT
cd "$repo"

# run ARGS...: the script's output (stdout and stderr) in $got, its exit status in $status
run() { status=0; got=$(bash scripts/fuzz_changed.sh "$@" 2>&1) || status=$?; }
expect() {  # expect WANTED_OUTPUT WANTED_STATUS ARGS...
  local wanted="$1" wanted_status="$2"
  shift 2
  run "$@"
  [ "$status" = "$wanted_status" ] || fail "fuzz_changed.sh $* exited $status, not $wanted_status:
$got"
  [ "$got" = "$wanted" ] || fail "fuzz_changed.sh $* printed '$got', not '$wanted'"
}
commit() { git add -A && git -c user.name=test -c user.email=t@example.invalid commit -q -m "$1"; }
flags=(-O2 -g -gdwarf-5)
build() {  # build FOLDER TREE [FLAGS...]: FOLDER/bin/x_fuzz from TREE, compiled inside FOLDER
  local folder="$1" tree="$2"
  shift 2
  mkdir -p "$folder/bin"
  (cd "$folder" &&
    clang++ "${flags[@]}" "$@" -I"$tree" -o bin/x_fuzz "$tree/sim/used.cc" "$tree/fuzz/x_fuzz.cc")
}

git init -q .
mkdir -p scripts sim fuzz
cp "$script" scripts/
printf 'build*/\ncopy/\n' >.gitignore
printf 'inline int Twice(int v) { return 2 * v; }\n' >sim/inline.h
printf 'struct Pair { int first, second; };\n' >sim/types.h
printf 'int Declared(int v);\n' >sim/declared.h
printf '#include "sim/declared.h"\n#include "sim/inline.h"\n#include "sim/types.h"\n' >sim/used.cc
printf '#include <cstring>\nint Used(const char* text) {\n' >>sim/used.cc
printf '  Pair pair{static_cast<int>(std::strlen(text)), 0};\n' >>sim/used.cc
printf '  return Twice(pair.first);\n}\n' >>sim/used.cc
printf 'int Other() { return 3; }\n' >sim/other.cc
printf 'int Used(const char* text);\n' >fuzz/x_fuzz.cc
printf 'int main(int, char** argv) { return Used(argv[0]) > 0 ? 0 : 1; }\n' >>fuzz/x_fuzz.cc
commit first
first=$(git rev-parse HEAD)
build "$repo/build-fuzz" "$repo"

expect "x: unchanged since $first" 0 "$first" x
for f in sim/inline.h sim/types.h sim/declared.h sim/used.cc sim/other.cc; do
  printf '// changed\n' >>"$f"
done
commit second
expect "x: sim/inline.h sim/types.h sim/used.cc " 0 "$first" x
expect "x: unchanged since HEAD" 0 HEAD x
expect "x: sim/inline.h sim/types.h sim/used.cc " 0 --build build-fuzz "$first" x
# A binary built from another copy of the tree (another worktree): the files are found by their
# place in that copy.
copy="$repo/copy"
mkdir -p "$copy" && cp -r sim fuzz "$copy"
build "$copy/build" "$copy"
expect "x: sim/inline.h sim/types.h sim/used.cc " 0 --build "$copy/build" "$first" x
# fuzz/x_fuzz.cc of both trees in one binary: which tree it was built from cannot be told.
mkdir -p build-two/bin
(cd build-two && clang++ "${flags[@]}" -Dmain=copy_main -c "$copy/fuzz/x_fuzz.cc" -o copy.o &&
  clang++ "${flags[@]}" -I"$repo" -o bin/x_fuzz "$repo/sim/used.cc" "$repo/fuzz/x_fuzz.cc" copy.o)
run --build build-two HEAD x
[ "$status" = 2 ] && [[ "$got" == *"was built from two trees"* ]] ||
  fail "a binary of two trees gave exit $status and '$got'"

expect "fuzz_changed.sh: no-such-commit is not a commit here" 2 no-such-commit x
expect "fuzz_changed.sh: build-fuzz/bin/y_fuzz not built (scripts/fuzz.sh builds it)" 2 HEAD y
strip -g -o build-fuzz/bin/z_fuzz build-fuzz/bin/x_fuzz
expect "fuzz_changed.sh: build-fuzz/bin/z_fuzz has no line tables (build it with -g)" 2 HEAD z
build "$repo/build-dwarf4" "$repo" -gdwarf-4
expect "fuzz_changed.sh: build-dwarf4/bin/x_fuzz has line tables older than DWARF 5 (build it with\
 -gdwarf-5)" 2 --build build-dwarf4 HEAD x
expect "usage: scripts/fuzz_changed.sh [--build DIR] COMMIT TARGET..." 2 HEAD
echo "fuzz_changed.sh: all cases pass"
