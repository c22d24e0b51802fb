#!/usr/bin/env bash
# Fails when a tracked file cites a path outside the repository (docs/architecture.md, top): the
# project's design lives in docs/, so no code or doc may point at the shared design notes outside the repo.
# Allowed: ../shared/scenes, the shared test scenes' documented location beside the checkout.
# Usage: scripts/check_no_outside_refs.sh [ROOT] (default: the repo; a plain folder works too).
set -euo pipefail
root="${1:-$(cd "$(dirname "$0")/.." && pwd)}"
cd "$root"
if git rev-parse --is-inside-work-tree >/dev/null 2>&1 && [ "$(git rev-parse --show-toplevel)" = "$(pwd -P)" ]; then
  files() { git ls-files -co --exclude-standard; }
else
  files() { find . -type f -not -path './build*' -not -path './.git/*' | sed 's|^\./||'; }
fi
pattern='DESIGN\.md|\.\./shared/([^s]|s[^c])|/work/'
hits=$(files | grep -vE '^(scripts/check_no_outside_refs\.sh|tests/layering_check_test\.sh)$' |
       while IFS= read -r f; do [ -f "$f" ] && grep -HnIE "$pattern" "$f" || true; done)
if [ -n "$hits" ]; then
  echo "$hits"
  echo "outside refs: the lines above cite a path outside the repository (cite docs/architecture.md instead)" >&2
  exit 1
fi
echo "outside refs: ok"
