#!/usr/bin/env bash
# Fails, naming each file, when a tracked C++ file does not follow
# .clang-format: `clang-format-14 -i FILE` lays it out. Run by ctest as
# format_check; ops/install-deps.sh installs clang-format-14.
set -uo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.." || exit 1
if ! files=$(git ls-files '*.cc' '*.h' 2>/dev/null) || [ -z "$files" ]; then
  echo "format_check: not a git checkout, cannot list the tracked files" >&2
  exit 1
fi
# One call over every file; each misplaced line is a warning naming its file.
bad=$(xargs clang-format-14 --dry-run <<<"$files" 2>&1 >/dev/null | grep -oE '^[^:]+:[0-9]+:[0-9]+: (warning|error)' | cut -d: -f1 | sort -u)
if [ -n "$bad" ]; then
  while IFS= read -r f; do echo "$f: not laid out as .clang-format says (run: clang-format-14 -i $f)" >&2; done <<<"$bad"
  exit 1
fi
echo "format_check: $(wc -l <<<"$files") files follow .clang-format"
