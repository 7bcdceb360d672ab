#!/usr/bin/env bash
# Checks that every C++ file in git follows .clang-format; never rewrites anything.
#   scripts/check_format.sh            all tracked *.cpp / *.hpp
#   scripts/check_format.sh FILE...    only these
# Exit 0 when all are formatted, 1 when some are not (each listed, with the first differing lines),
# 2 when clang-format-14 is missing. To fix a file: clang-format-14 -i FILE.
set -euo pipefail
cd "$(dirname "$0")/.."

format=${CLANG_FORMAT:-clang-format-14}
if ! command -v "$format" >/dev/null; then
  echo "check_format: $format not found (Debian: apt-get install clang-format-14)" >&2
  exit 2
fi

if (($#)); then
  files=("$@")
else
  mapfile -t files < <(git ls-files '*.cpp' '*.hpp')
fi

bad=0
for f in "${files[@]}"; do
  if ! diff_text=$("$format" --style=file:.clang-format "$f" | diff -u --label "$f" --label "$f (formatted)" "$f" -); then
    sed -n 1,12p <<<"$diff_text"
    bad=$((bad + 1))
  fi
done
if ((bad)); then
  echo "check_format: $bad of ${#files[@]} files are not formatted (clang-format-14 -i FILE fixes one)" >&2
  exit 1
fi
echo "check_format: ${#files[@]} files formatted"
