#!/usr/bin/env bash
# Concurrency campaign (docs/reliability.md, "Fault campaigns"): two cold `hdi run`s started
# together on one processed/, and (when a Slurm cluster answers `sinfo`, e.g. after
# `bash scripts/slurm-local-up.sh`) an `hdi run --executor slurm` whose array writes the case
# cache while a local `hdi run` works on the same store. Both runs must succeed, the result
# files must equal a clean run's and `hdi verify` must exit 0. Prints result-table rows.
#
#   scripts/faults/concurrent.sh          FAULTS_SLURM=auto|0|1  FAULTS_PIPELINE=shipped|small
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
trap cleanup_work EXIT
START=$(ms_now)
cold_reference "$WORK/ref"
fails=0

check() { # check NAME DIR: results equal the reference and verify is clean
  if ! same_as_reference "$2/processed"; then echo "$1: results differ" >&2; return 1; fi
  if ! (cd "$2" && "$HDI" verify >"$WORK/verify.out" 2>&1); then
    echo "$1: hdi verify: $(cat "$WORK/verify.out")" >&2; return 1; fi
}

# 1. Two local runs at once.
P=$WORK/two
new_project "$P"
t0=$(ms_now)
(cd "$P" && "$HDI" run --jobs "${FAULTS_JOBS:-2}" >/dev/null 2>"$WORK/a.log") & a=$!
(cd "$P" && "$HDI" run --jobs "${FAULTS_JOBS:-2}" >/dev/null 2>"$WORK/b.log") & b=$!
ra=0; rb=0
wait $a || ra=$?
wait $b || rb=$?
wall=$(( ($(ms_now) - t0) / 1000 ))
ok=1
[ $ra = 0 ] && [ $rb = 0 ] || { echo "two runs: exit $ra and $rb: $(tail -2 "$WORK/a.log") $(tail -2 "$WORK/b.log")" >&2; ok=0; }
waited=$(cat "$WORK/a.log" "$WORK/b.log" | grep -c 'waiting for another hdi run' || true)
noop=$(cat "$WORK/a.log" "$WORK/b.log" | grep -c 'nothing to do' || true)
[ $ok = 1 ] && { check "two runs" "$P" || ok=0; }
log "two runs: exits $ra/$rb, $waited waited for the lock, $noop found everything cached, ${wall} s (clean cold run $((REF_MS / 1000)) s)"
[ $ok = 1 ] || fails=$((fails + 1))
row "two \`hdi run\` at once ($FAULTS_PIPELINE)" "$([ $ok = 1 ] && echo PASS || echo FAIL)" \
  "both exit 0; the second waited on .hdi/lock ($waited) and then found all cached ($noop); ${wall} s for both against $((REF_MS / 1000)) s for one; results equal, verify clean" \
  "$(( ($(ms_now) - START) / 1000 ))"

# 2. A Slurm array and a local run on one store.
SLURM=${FAULTS_SLURM:-auto}
if [ "$SLURM" = auto ]; then
  if command -v sinfo >/dev/null && sinfo -h -o %a 2>/dev/null | grep -q up; then SLURM=1; else SLURM=0; fi
fi
if [ "$SLURM" = 1 ]; then
  T1=$(ms_now)
  P=$WORK/slurm
  new_project "$P"
  (cd "$P" && "$HDI" run --executor slurm --jobs "${FAULTS_JOBS:-2}" >/dev/null 2>"$WORK/s.log") & s=$!
  # The local run starts once the array is submitted, so both write the case cache at once.
  for _ in $(seq 1 600); do
    grep -q 'submitted as job' "$WORK/s.log" 2>/dev/null && break
    kill -0 $s 2>/dev/null || break
    sleep 0.5
  done
  (cd "$P" && "$HDI" run --jobs "${FAULTS_JOBS:-2}" >/dev/null 2>"$WORK/l.log") & l=$!
  rs=0; rl=0
  wait $s || rs=$?
  wait $l || rl=$?
  ok=1
  [ $rs = 0 ] && [ $rl = 0 ] || { echo "slurm + local: exit $rs and $rl: $(tail -3 "$WORK/s.log") $(tail -3 "$WORK/l.log")" >&2; ok=0; }
  [ $ok = 1 ] && { check "slurm + local" "$P" || ok=0; }
  job=$(grep -o 'slurm: [0-9]* cases in [0-9]* tasks submitted as job(s) [0-9, ]*' "$WORK/s.log" | head -1 || true)
  # Who computed what: the tasks' own counts (`task N: C computed, K cached, F failed`).
  tasks=$(cat "$P"/processed/.hdi/slurm/*.log 2>/dev/null | grep -o 'task [0-9]*: [0-9]* computed, [0-9]* cached' || true)
  by_slurm=$(awk '{s += $3} END {print s + 0}' <<<"$tasks")
  cached_for_slurm=$(awk '{s += $5} END {print s + 0}' <<<"$tasks")
  log "slurm + local: exits $rs/$rl; $job; the array computed $by_slurm cases and found $cached_for_slurm already computed by the local run"
  [ $ok = 1 ] || fails=$((fails + 1))
  row "Slurm array + local \`hdi run\` on one store ($FAULTS_PIPELINE)" "$([ $ok = 1 ] && echo PASS || echo FAIL)" \
    "both exit 0 ($job; the array computed $by_slurm, found $cached_for_slurm done by the local run); results equal to the clean run, verify clean" "$(( ($(ms_now) - T1) / 1000 ))"
else
  log "no Slurm cluster answers sinfo: the Slurm part is skipped (bash scripts/slurm-local-up.sh)"
  row "Slurm array + local \`hdi run\` on one store" "SKIPPED" "no Slurm cluster (sinfo)" 0
fi
[ $fails = 0 ]
