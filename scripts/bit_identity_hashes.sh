#!/usr/bin/env bash
# Prints the hashes a refactor of the lighting core must keep: every job of
# bench/bench_hashes.cpp (bakes, points, polling, hard cases) and the values
# hash of every bench_emitters scene in its quick families. Run it on the base
# commit and after each step; `diff` the two outputs.
#   bash scripts/bit_identity_hashes.sh > hashes.txt   (after a build)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bench="${OMIS_BUILD_DIR:-$root/build}/bench"
"$bench/omis_bench_hashes"
for flags in "" "--texels" "--per-triangle" "--general" "--texels --per-triangle"; do
    echo "emitters $flags"
    # shellcheck disable=SC2086
    "$bench/omis_bench_emitters" --quick --reps 1 $flags |
        awk 'NR > 2 { for (i = 1; i <= NF; i++) if (length($i) == 16 && $i ~ /^[0-9a-f]+$/) h = $i; print h, $1, $2, $3 }'
done
