#!/usr/bin/env bash
# The layering check passes on the tree and fails on a copy with a planted bad include (codec -> client);
# likewise the check that nothing cites a path outside the repository.
set -euo pipefail
src="$1"
bash "$src/scripts/check_layering.sh" "$src"
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
for d in common store codec client builder server bench cli; do [ -d "$src/$d" ] && cp -r "$src/$d" "$tmp/"; done
echo '#include "client/shadow_map.hpp"' >> "$tmp/codec/decoded_tile.cpp"
if out=$(bash "$src/scripts/check_layering.sh" "$tmp" 2>&1); then
  echo "FAIL: the planted include codec -> client was not caught"; exit 1
fi
grep -q 'codec/decoded_tile.cpp (codec) includes client/' <<<"$out" || { echo "FAIL: wrong message: $out"; exit 1; }
echo "planted include caught: $out"

# No path outside the repository is cited: passes on the tree, fails on a planted citation.
bash "$src/scripts/check_no_outside_refs.sh" "$src"
outside_doc="DESIGN"  # the planted citation, assembled so this file itself cites nothing outside
echo "// see ../shared/${outside_doc}.md" >> "$tmp/codec/decoded_tile.cpp"
if out=$(bash "$src/scripts/check_no_outside_refs.sh" "$tmp" 2>&1); then
  echo "FAIL: the planted citation outside the repo was not caught"; exit 1
fi
grep -q "codec/decoded_tile.cpp:.*${outside_doc}.md" <<<"$out" || { echo "FAIL: wrong message: $out"; exit 1; }
echo "planted outside citation caught: $out"
