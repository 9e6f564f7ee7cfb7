# shellcheck shell=bash
# Shared by the fault campaigns in scripts/faults/ (docs/reliability.md, "Fault campaigns").
#
#   HDI=/path/to/hdi          the binary to test (default: the release build of this checkout)
#   FAULTS_PIPELINE=shipped   the shipped pipeline.toml as it is (default), or `small`: the
#                             tests' shrunk copy (tests/common.rs `Project::shipped`: 4-case
#                             sweeps, a 3-evaluation calibration, a short annealing), ~10× faster
#   FAULTS_KEEP=1             keep the temp projects (their paths are printed)
set -euo pipefail

REPO=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
if [ -z "${HDI:-}" ]; then
  for c in "${CARGO_TARGET_DIR:-$REPO/target}/release/hdi" "$REPO/target/release/hdi"; do
    if [ -x "$c" ]; then HDI=$c; break; fi
  done
fi
if [ -z "${HDI:-}" ] || [ ! -x "$HDI" ]; then
  echo "no release hdi: run \`cargo build --release\` or set HDI=/path/to/hdi" >&2
  exit 2
fi
HDI=$(readlink -f "$HDI")
FAULTS_PIPELINE=${FAULTS_PIPELINE:-shipped}
WORK=$(mktemp -d /tmp/hdi-faults.XXXXXX)
chmod 755 "$WORK"
cleanup_work() {
  if [ "${FAULTS_KEEP:-0}" = 1 ]; then
    echo "kept $WORK" >&2
  else
    rm -rf "$WORK"
  fi
}

log() { echo "[$(date -u +%H:%M:%S)] $*" >&2; }

# new_project DIR: a copy of the shipped raw/ and pipeline.toml (shrunk with FAULTS_PIPELINE=small).
new_project() {
  local dir=$1
  mkdir -p "$dir"
  cp -r "$REPO/raw" "$dir/raw"
  if [ "$FAULTS_PIPELINE" = small ]; then
    python3 - "$REPO/pipeline.toml" "$dir/pipeline.toml" <<'PY'
import sys
text = open(sys.argv[1]).read()
# The same shrinking as tests/common.rs Project::shipped().
text = text.replace('actuation_step = "0.2 nm"', 'actuation_step = "5 nm"\nrefine_touchdown = false')
text = text.replace('power_step = "2 mW"', 'power_step = "16 mW"\nrefine_touchdown = false')
text = text.replace("\nmax_evaluations = 400",
    '\nmax_evaluations = 3\nknobs = ["dmw_scale"]\ntargets = ["clearance_8.5nm", "fhm_8.5nm"]\n'
    'held_out = ["regime_solid_start", "full_contact_onset", "touchdown_clearance"]')
text = "".join(l + "\n" for l in text.splitlines()
               if not (l.startswith("start = {") or l.startswith("initial_step = ")
                       or l.startswith("start_fitted_for = ")))
text = text.replace("sa_max_evaluations = 400", "sa_max_evaluations = 12")
text = text.replace('compare_step = "0.2 nm"', 'compare_step = "3 nm"')
text += "\n[report]\nvalidation = false\n"
open(sys.argv[2], "w").write(text)
PY
  else
    cp "$REPO/pipeline.toml" "$dir/pipeline.toml"
  fi
}

# result_hashes PROCESSED: sha256 of every result file, sorted — the store entries and tables,
# without the manifests (times), the engine's bookkeeping under .hdi/ and the HTML report
# (a view with wall times): what tests/pipeline_cache.rs' determinism test and docs/diff.md
# compare. The processed/<name> links are listed with their targets.
result_hashes() {
  local p=$1
  (
    cd "$p"
    find . -type f \
      ! -name manifest.json \
      ! -path './report/*' \
      \( ! -path './.hdi/*' -o -path './.hdi/store/*' \) \
      -print0 | sort -z | xargs -0 -r sha256sum
    find . -maxdepth 1 -type l -printf '%p -> %l\n' | sort
  )
}

# ms_now: wall clock in milliseconds.
ms_now() { date +%s%3N; }

# row CAMPAIGN RESULT DETAIL SECONDS: one row of the table in docs/reliability.md.
row() { printf '| %s | %s | %s | %s s |\n' "$1" "$2" "$3" "$4"; }

# cold_reference DIR: a clean cold run in DIR; sets REF_HASHES (file) and REF_MS.
cold_reference() {
  local dir=$1
  new_project "$dir"
  local t0; t0=$(ms_now)
  (cd "$dir" && "$HDI" run --jobs "${FAULTS_JOBS:-2}" >/dev/null 2>"$dir/ref-run.log") || {
    echo "the clean reference run failed: $(tail -3 "$dir/ref-run.log")" >&2; exit 1; }
  REF_MS=$(( $(ms_now) - t0 ))
  REF_HASHES=$WORK/ref-hashes.txt
  result_hashes "$dir/processed" >"$REF_HASHES"
  log "clean reference: $(wc -l <"$REF_HASHES") result files, cold run $((REF_MS / 1000)) s"
}

# same_as_reference PROCESSED: 0 when the result files equal the reference's.
same_as_reference() {
  local got=$WORK/got-hashes.txt
  result_hashes "$1" >"$got"
  if cmp -s "$got" "$REF_HASHES"; then return 0; fi
  diff "$REF_HASHES" "$got" | head -10 >&2
  return 1
}
