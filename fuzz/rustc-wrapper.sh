#!/usr/bin/env bash
# RUSTC_WRAPPER for the fuzz build (scripts/fuzz.sh). `cargo afl build` puts AFL's coverage
# instrumentation, `-C codegen-units=1 -C opt-level=3` and debug assertions into RUSTFLAGS, i.e.
# on every crate: polars, arrow and the rest would build for half an hour on 2 cores and fill
# AFL's map with edges that are not hdi's. This keeps all of that on hdi and the fuzz targets
# only; dependencies build as in hdi's release profile (opt-level 1, polars-core 0) without
# instrumentation. A panic or crash inside a dependency is still caught (AFL sees the abort);
# only the coverage feedback stays on hdi's own code.
set -euo pipefail
rustc="$1"
shift
crate=""
prev=""
for a in "$@"; do
  if [ "$prev" = "--crate-name" ]; then crate="$a"; break; fi
  prev="$a"
done
case "$crate" in
  hdi | hdi_fuzz | height_map | ldv | pipeline | manifest | "") exec "$rustc" "$@" ;;
esac
opt=1
[ "$crate" = polars_core ] && opt=0
args=()
prev=""
for a in "$@"; do
  if [ "$prev" = "-C" ]; then
    case "$a" in
      passes=sancov* | llvm-args=-sanitizer-coverage* | codegen-units=1 | debug-assertions | overflow_checks | overflow-checks)
        # drop the pair: remove the "-C" already appended
        unset 'args[${#args[@]}-1]'
        prev="$a"
        continue
        ;;
      opt-level=*)
        args+=("opt-level=$opt")
        prev="$a"
        continue
        ;;
    esac
  fi
  args+=("$a")
  prev="$a"
done
exec "$rustc" "${args[@]}"
