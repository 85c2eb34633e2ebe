#!/usr/bin/env bash
# Applies .clang-format to every C++ file in the repository (scripts/format.sh), or only checks
# that it is applied (scripts/format.sh --check: lists the files that differ, exit 1 if any).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install_packages.sh format clang-format
files=$(git ls-files '*.cc' '*.h')
if [ "${1:-}" = "--check" ]; then
  # A few processes for all the files (one process a file took 44 s on 500 of them in CI):
  # --dry-run names each file that differs in its warnings, which -Werror makes errors.
  report=$(echo "$files" | xargs clang-format --dry-run --Werror --style=file 2>&1) || true
  mapfile -t differ < <(printf '%s\n' "$report" |
    sed -n 's/^\(.*\):[0-9]*:[0-9]*: error: code should be clang-formatted.*/\1/p' | sort -u)
  if [ ${#differ[@]} -gt 0 ] || [[ "$report" == *"error:"* ]]; then
    echo "format: ${#differ[@]} file(s) differ from .clang-format (run scripts/format.sh):" >&2
    printf '  %s\n' "${differ[@]}" >&2
    [ ${#differ[@]} -gt 0 ] || printf '%s\n' "$report" >&2  # an error that names no file
    exit 1
  fi
  echo "format: all $(echo "$files" | wc -w) C++ files follow .clang-format"
else
  echo "$files" | xargs clang-format -i --style=file
fi
