#!/usr/bin/env bash
# Coverage-guided fuzzing of hdi's readers with afl.rs on stable Rust (docs/reliability.md,
# "Coverage-guided fuzzing").
#
#   bash scripts/fuzz.sh TARGET SECONDS
#       TARGET: height_map | every_reader | ldv | pipeline | manifest | all
#
# Installs cargo-afl (and its AFL++ runtime) if missing, builds the targets of fuzz/, then runs
# afl-fuzz on TARGET for SECONDS from the seed corpus fuzz/corpus/TARGET (or, if it exists, resumes
# the earlier run's queue). Exits 1 if a crash or hang was found and prints where the inputs are.
# `all` runs each target for SECONDS in turn.
#
# Environment: HDI_FUZZ_TARGET_DIR (build dir, default /var/tmp/hdi-fuzz-target),
# HDI_FUZZ_OUT (findings, default /var/tmp/hdi-fuzz-out), AFL_OPT_LEVEL (hdi's opt-level in the
# fuzz build, default 1: the build is most of a short run's time).
set -euo pipefail
cd "$(dirname "$0")/.."
root="$PWD"

targets=(height_map every_reader ldv pipeline manifest)
if [ $# -ne 2 ] || ! [[ "$2" =~ ^[0-9]+$ ]]; then
  echo "usage: $0 TARGET SECONDS   (TARGET: ${targets[*]} | all)" >&2
  exit 2
fi
target="$1"
seconds="$2"
if [ "$target" = all ]; then
  status=0
  for t in "${targets[@]}"; do
    bash "$0" "$t" "$seconds" || status=1
  done
  exit "$status"
fi
case " ${targets[*]} " in
  *" $target "*) ;;
  *)
    echo "unknown fuzz target '$target' (have: ${targets[*]})" >&2
    exit 2
    ;;
esac

# --- tooling: cargo-afl, pinned, and AFL++ built from the source it ships (needs make and cc).
AFL_VERSION=0.18.2
if ! cargo afl --version 2>/dev/null | grep -q "$AFL_VERSION"; then
  echo "fuzz.sh: installing cargo-afl $AFL_VERSION" >&2
  cargo install --locked --quiet cargo-afl --version "$AFL_VERSION"
fi
# `config --build` refuses (non-zero) when the runtime is already built: that is the idempotent case.
cargo afl config --build >/dev/null 2>&1 || true

# --- build: release profile, instrumentation on hdi and the targets only (fuzz/rustc-wrapper.sh).
# Not --locked: fuzz/Cargo.lock is a copy of the main Cargo.lock plus afl, and cargo refreshes it
# when hdi's dependencies move.
export CARGO_TARGET_DIR="${HDI_FUZZ_TARGET_DIR:-/var/tmp/hdi-fuzz-target}"
export RUSTC_WRAPPER="$root/fuzz/rustc-wrapper.sh"
export AFL_OPT_LEVEL="${AFL_OPT_LEVEL:-1}"
(cd fuzz && cargo afl build --release --quiet --bin "$target")
bin="$CARGO_TARGET_DIR/release/$target"

# --- run
out="${HDI_FUZZ_OUT:-/var/tmp/hdi-fuzz-out}/$target"
mkdir -p "$out"
# every_reader feeds each input to every height-map reader: it starts from height_map's seeds.
corpus="$target"
[ "$target" = every_reader ] && corpus=height_map
input="$root/fuzz/corpus/$corpus"
# Resume a previous run's queue (afl-fuzz's `-i -`) so long runs add up.
[ -d "$out/default/queue" ] && input=-
dict=()
[ -f "$root/fuzz/dict/$corpus.dict" ] && dict=(-x "$root/fuzz/dict/$corpus.dict")
scratch="$(mktemp -d /dev/shm/hdi-fuzz-XXXXXX 2>/dev/null || mktemp -d)"
trap 'rm -rf "$scratch"' EXIT
# CI machines have no core_pattern/CPU-governor tuning and share cores with others: skip those
# checks and the CPU binding. -t: a hang is an input taking over 2 s; -m: 2 GB address limit off
# (the readers' own limits are what is tested; RSS is watched by the memory-bounds figures).
AFL_SKIP_CPUFREQ=1 AFL_I_DONT_CARE_ABOUT_MISSING_CRASHES=1 AFL_NO_AFFINITY=1 \
  AFL_NO_UI=1 AFL_QUIET=1 AFL_SKIP_CRASHES=1 AFL_NO_WARN_INSTABILITY=1 TMPDIR="$scratch" \
  cargo afl fuzz -V "$seconds" -t 2000 -m none "${dict[@]}" -i "$input" -o "$out" -- "$bin" \
  >"$out/afl.log" 2>&1 || {
  echo "fuzz.sh: afl-fuzz failed; its log:" >&2
  tail -40 "$out/afl.log" >&2
  exit 1
}

stats="$out/default/fuzzer_stats"
get() { sed -n "s/^$1 *: *//p" "$stats"; }
crashes="$(find "$out/default/crashes" -type f -name 'id:*' 2>/dev/null | wc -l)"
hangs="$(find "$out/default/hangs" -type f -name 'id:*' 2>/dev/null | wc -l)"
echo "fuzz $target: $(get execs_done) execs in $(get run_time) s ($(get execs_per_sec)/s)," \
  "corpus $(get corpus_count), edges $(get edges_found)/$(get total_edges) ($(get bitmap_cvg))," \
  "crashes $crashes, hangs $hangs"
if [ "$crashes" != 0 ] || [ "$hangs" != 0 ]; then
  echo "fuzz $target: FOUND crashes/hangs; inputs in $out/default/crashes and $out/default/hangs" >&2
  echo "  replay one: $bin < FILE" >&2
  exit 1
fi
