#!/usr/bin/env bash
# Fails when a project include crosses the allowed layer arrows (docs/architecture.md, "Layers"):
#   common <- store <- codec <- client <- {builder, server} <- bench <- cli;  fuzz, tests, examples: anything.
# builder and server never include each other. Usage: scripts/check_layering.sh [ROOT] (default: the repo).
set -euo pipefail
root="${1:-$(cd "$(dirname "$0")/.." && pwd)}"
declare -A allowed=(
  [common]="common"
  [store]="common store"
  [codec]="common store codec"
  [client]="common store codec client"
  [builder]="common store codec client builder"
  [server]="common store codec client server"
  [capi]="common store codec client capi"
  [bench]="common store codec client builder server bench"
  [cli]="common store codec client builder server bench cli"
)
violations=0
for layer in "${!allowed[@]}"; do
  [ -d "$root/$layer" ] || continue
  while IFS= read -r line; do
    file="${line%%:*}"
    rest="${line#*:}"; rest="${rest#*:}"
    target=$(sed -E 's/.*#include[[:space:]]*"([^/"]+)\/.*/\1/' <<<"$rest")
    [ -n "$target" ] || continue
    case " ${allowed[$layer]} " in
      *" $target "*) ;;
      *) if [ -d "$root/$target" ] && [ -f "$root/$target/CMakeLists.txt" ]; then
           echo "layering: ${file#$root/} ($layer) includes $target/: not allowed (${layer} may include: ${allowed[$layer]})"
           violations=$((violations + 1))
         fi ;;
    esac
  done < <(grep -rnE '^[[:space:]]*#[[:space:]]*include[[:space:]]*"[^/"]+/' "$root/$layer" \
             --include='*.cpp' --include='*.hpp' --include='*.h' --include='*.c' 2>/dev/null || true)
done
if [ "$violations" -gt 0 ]; then
  echo "layering: $violations include(s) cross the allowed arrows" >&2
  exit 1
fi
echo "layering: ok"
