#!/usr/bin/env bash
# Kill campaign (docs/reliability.md, "Fault campaigns"): `kill -9` a cold `hdi run` at N
# random points (seeded), after each a full rerun; the rerun must succeed, its result files must
# equal a clean run's (sha256; manifests, run logs and the report excluded) and `hdi verify`
# must exit 0. Prints one result-table row; exit 1 on any failure.
#
#   scripts/faults/kill.sh [N=20]        SEED=21  FAULTS_PIPELINE=shipped|small  HDI=…
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
trap cleanup_work EXIT
N=${1:-20}
SEED=${SEED:-21}
START=$(ms_now)

cold_reference "$WORK/ref"
P=$WORK/p
new_project "$P"
RANDOM=$SEED
fails=0
killed=0
leftovers=0
for i in $(seq 1 "$N"); do
  rm -rf "$P/processed"
  # A point uniformly in 2–98 % of the clean cold run's wall time.
  frac=$(( 2 + RANDOM % 97 ))
  delay_ms=$(( REF_MS * frac / 100 ))
  (cd "$P" && exec "$HDI" run --jobs "${FAULTS_JOBS:-2}" >/dev/null 2>"$WORK/killed.log") &
  pid=$!
  sleep "$(printf '%d.%03d' $((delay_ms / 1000)) $((delay_ms % 1000)))"
  what="finished before the kill"
  if kill -0 "$pid" 2>/dev/null; then
    kill -9 "$pid" 2>/dev/null || true
    killed=$((killed + 1))
    what="killed"
  fi
  wait "$pid" 2>/dev/null || true
  tmp_left=$(find "$P/processed/.hdi/tmp" -mindepth 1 -maxdepth 1 2>/dev/null | wc -l)
  entries=$(find "$P/processed/.hdi/store" -mindepth 2 -maxdepth 2 2>/dev/null | wc -l)
  leftovers=$((leftovers + tmp_left))
  ok=1
  if ! (cd "$P" && "$HDI" run --jobs "${FAULTS_JOBS:-2}" >/dev/null 2>"$WORK/rerun.log"); then
    echo "kill $i: the rerun failed: $(tail -2 "$WORK/rerun.log")" >&2; ok=0
  fi
  if [ $ok = 1 ] && ! same_as_reference "$P/processed"; then
    echo "kill $i: results differ from the clean run" >&2; ok=0
  fi
  if [ $ok = 1 ] && ! (cd "$P" && "$HDI" verify >"$WORK/verify.out" 2>&1); then
    echo "kill $i: hdi verify: $(cat "$WORK/verify.out")" >&2; ok=0
  fi
  [ $ok = 1 ] || fails=$((fails + 1))
  log "kill $i/$N at ${frac} % (${delay_ms} ms): $what; $entries entries and $tmp_left work dirs left; rerun $([ $ok = 1 ] && echo ok || echo FAILED)"
done
secs=$(( ($(ms_now) - START) / 1000 ))
result=PASS
[ $fails = 0 ] || result="FAIL ($fails)"
row "kill -9 × $N (seed $SEED, $FAULTS_PIPELINE)" "$result" \
  "$killed killed mid-run, $((N - killed)) finished first; $leftovers leftover work dirs, never trusted; every rerun equal to the clean run, verify clean" "$secs"
[ $fails = 0 ]
