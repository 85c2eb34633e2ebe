#!/usr/bin/env bash
# Applies .clang-format to every C++ file in the repository (scripts/format.sh), or only checks
# that it is applied (scripts/format.sh --check: lists the files that differ, exit 1 if any).
set -euo pipefail
cd "$(dirname "$0")/.."
files=$(git ls-files '*.cc' '*.h')
if [ "${1:-}" = "--check" ]; then
  differ=()
  for f in $files; do
    clang-format --style=file "$f" | cmp -s - "$f" || differ+=("$f")
  done
  if [ ${#differ[@]} -gt 0 ]; then
    echo "format: ${#differ[@]} file(s) differ from .clang-format (run scripts/format.sh):" >&2
    printf '  %s\n' "${differ[@]}" >&2
    exit 1
  fi
  echo "format: all $(echo "$files" | wc -w) C++ files follow .clang-format"
else
  echo "$files" | xargs clang-format -i --style=file
fi
