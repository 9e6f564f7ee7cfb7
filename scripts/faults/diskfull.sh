#!/usr/bin/env bash
# Disk-full campaign (docs/reliability.md, "Fault campaigns"): `processed/` on a tmpfs too
# small for the run, so the disk fills mid-run. For each size (a fraction of what a clean run
# writes) the run must fail with a clear "no space left" error naming the instance or file,
# `hdi verify` must exit 0 (nothing half-written is in the store: a failed stage leaves at most
# a work dir, never trusted), and after the tmpfs is grown the next run must complete with
# results equal to a clean run's. Needs root (mount). Prints one result-table row.
#
#   scripts/faults/diskfull.sh [FRACTIONS="0.05 0.3 0.6 0.9"]   FAULTS_PIPELINE=shipped|small
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
[ "$(id -u)" = 0 ] || { echo "diskfull.sh: needs root (mount -t tmpfs)" >&2; exit 2; }
MNT=""
cleanup() {
  if [ -n "$MNT" ] && mountpoint -q "$MNT"; then umount "$MNT" || true; fi
  cleanup_work
}
trap cleanup EXIT
FRACTIONS=${1:-0.05 0.3 0.6 0.9}
START=$(ms_now)

cold_reference "$WORK/ref"
# What a clean run occupies on a tmpfs (the same filesystem kind as the test).
NEED_KB=$(du -sk "$WORK/ref/processed" | cut -f1)
log "a clean run writes $NEED_KB KiB"
fails=0
details=()
for f in $FRACTIONS; do
  P=$WORK/p-$f
  new_project "$P"
  mkdir -p "$P/processed"
  size_kb=$(python3 -c "print(max(64, int($NEED_KB * $f)))")
  MNT=$P/processed
  mount -t tmpfs -o size=${size_kb}k tmpfs "$MNT"
  ok=1
  if (cd "$P" && "$HDI" run --jobs "${FAULTS_JOBS:-2}" >/dev/null 2>"$WORK/full.log"); then
    echo "size $f: the run succeeded on ${size_kb} KiB (not full?)" >&2; ok=0
  fi
  err=$(grep '^error:' "$WORK/full.log" || true)
  log "size $f (${size_kb} KiB): $err"
  grep -v '^error:' "$WORK/full.log" | grep -i 'FAILED\|skipped' | head -5 >&2 || true
  if ! grep -qi 'no space left' <<<"$err"; then
    echo "size $f: the error does not say \"no space left\": $(tail -5 "$WORK/full.log")" >&2; ok=0
  fi
  # …and names the instance (`name`) whose result could not be written.
  if ! grep -q '`[A-Za-z0-9_-]*`' <<<"$err"; then
    echo "size $f: the error names no instance: $err" >&2; ok=0
  fi
  if grep -q 'panicked' "$WORK/full.log"; then echo "size $f: panic" >&2; ok=0; fi
  # Nothing half-written trusted: every entry in the store verifies (the full disk may even
  # refuse the verify's own nothing — it writes nothing).
  if ! (cd "$P" && "$HDI" verify --all >"$WORK/verify.out" 2>&1); then
    echo "size $f: hdi verify after the failed run: $(cat "$WORK/verify.out")" >&2; ok=0
  fi
  # More space: the same directory, grown; the next run completes.
  mount -o remount,size=$((NEED_KB * 3 + 65536))k "$MNT"
  if ! (cd "$P" && "$HDI" run --jobs "${FAULTS_JOBS:-2}" >/dev/null 2>"$WORK/rerun.log"); then
    echo "size $f: the run with space failed: $(tail -3 "$WORK/rerun.log")" >&2; ok=0
  elif ! same_as_reference "$P/processed"; then
    echo "size $f: results differ from the clean run" >&2; ok=0
  elif ! (cd "$P" && "$HDI" verify >"$WORK/verify.out" 2>&1); then
    echo "size $f: hdi verify after the rerun: $(cat "$WORK/verify.out")" >&2; ok=0
  fi
  umount "$MNT"; MNT=""
  [ $ok = 1 ] || fails=$((fails + 1))
  short=$(sed -e 's/^error: //' <<<"$err" | cut -c1-160)
  details+=("$f: $short")
done
secs=$(( ($(ms_now) - START) / 1000 ))
result=PASS
[ $fails = 0 ] || result="FAIL ($fails)"
for d in "${details[@]}"; do log "$d"; done
row "disk full at $(wc -w <<<"$FRACTIONS") sizes ($FAULTS_PIPELINE)" "$result" \
  "each run failed with \"no space left\" naming the instance, verify clean, the run after growing the tmpfs equal to the clean run" "$secs"
[ $fails = 0 ]
