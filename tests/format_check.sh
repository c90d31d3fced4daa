#!/usr/bin/env bash
# format_check: every C++ file of the tree keeps the style of .clang-format (Debian 12's
# clang-format 14, installed by ./test.sh). Prints the files that do not, with clang-format's
# first complaints, and how to fix them. Exit 77 (skipped) without clang-format.
#   tests/format_check.sh SOURCE_DIR
set -euo pipefail
cd "$1"
if ! command -v clang-format >/dev/null 2>&1; then
  echo "format_check: clang-format is not installed (./test.sh installs it); skipped"
  exit 77
fi
if git rev-parse --is-inside-work-tree >/dev/null 2>&1; then
  mapfile -t files < <(git ls-files -- '*.cc' '*.h')
else
  mapfile -t files < <(find . -path ./build -prune -o \( -name '*.cc' -o -name '*.h' \) -print | sed 's#^\./##' | sort)
fi
# one clang-format for all files; a file out of style gets warnings that name it
report="$(clang-format --dry-run "${files[@]}" 2>&1 || true)"
mapfile -t bad < <(printf '%s\n' "$report" | grep -oE '^[^ :]+:[0-9]+:[0-9]+: (warning|error):' | cut -d: -f1 | sort -u)
echo "format_check: ${#files[@]} files, ${#bad[@]} not in .clang-format's style"
if [ "${#bad[@]}" -gt 0 ]; then
  printf '%s\n' "$report" | head -30
  echo "fix: clang-format -i ${bad[*]:0:10}"
  exit 1
fi
