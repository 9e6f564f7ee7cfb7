#!/usr/bin/env bash
# Read-only and permission-denied campaign (docs/reliability.md, "Fault campaigns"): after a
# clean run, one instance is made stale (a changed cutoff) and `hdi run` is tried where it
# cannot write:
#   ro-mount    processed/ remounted read-only (a read-only bind mount; chmod means nothing
#               to root)
#   other-user  a non-root user (created: hdifault) running on a processed/ owned by root
#   store-0555  that user owning the project, with processed/.hdi/store/ made read-only
#               (chmod -R a-w): the stage runs, then its commit into the store is refused
# Each must exit non-zero with one clear error naming the cause and the path, change nothing
# in processed/ (apart from the run's views: the report and .hdi/last-run.json), and
# `hdi status` / `hdi verify` (which only read) must still work. Needs root. Prints one row.
#
#   scripts/faults/readonly.sh            FAULTS_PIPELINE=shipped|small
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
[ "$(id -u)" = 0 ] || { echo "readonly.sh: needs root (mount, useradd)" >&2; exit 2; }
MNT=""
cleanup() {
  if [ -n "$MNT" ] && mountpoint -q "$MNT"; then umount "$MNT" || true; fi
  [ -d "$WORK" ] && chown -R root:root "$WORK" 2>/dev/null && chmod -R u+w "$WORK" 2>/dev/null
  cleanup_work
}
trap cleanup EXIT
START=$(ms_now)
USER_NAME=hdifault
id "$USER_NAME" >/dev/null 2>&1 || useradd -M -s /usr/sbin/nologin "$USER_NAME"
as_user() { setpriv --reuid "$USER_NAME" --regid "$USER_NAME" --clear-groups "$@"; }

P=$WORK/p
new_project "$P"
(cd "$P" && "$HDI" run --jobs "${FAULTS_JOBS:-2}" >/dev/null 2>"$WORK/first.log") || {
  echo "the first run failed: $(tail -3 "$WORK/first.log")" >&2; exit 1; }
# One stale instance: the disk surface gets a 250 nm L-filter.
python3 - "$P/pipeline.toml" <<'PY'
import sys
p = sys.argv[1]; t = open(p).read()
old = '[surface.disk]\nfile = "raw/afm/disk_dlc_1um.gwy"\n'
assert old in t
open(p, "w").write(t.replace(old, old + 'filter_l = "250 nm"\n'))
PY

# Every file and link under processed/ with its hash, but the run's views and the accelerator.
state() {
  (cd "$P/processed" && find . \( -type f -o -type l \) \
     ! -path './report/*' ! -name last-run.json ! -name input-hashes.json ! -name lock \
     -print0 | sort -z | xargs -0 -r -I{} sh -c 'if [ -L "{}" ]; then echo "{} -> $(readlink "{}")"; else sha256sum "{}"; fi')
}
fails=0
details=()
try() { # try CASE EXPECTED_WORDS RUNNER…: the run must fail with one error line containing the words
  local name=$1 want=$2; shift 2
  local before; before=$(state)
  local rc=0
  (cd "$P" && "$@" "$HDI" run --jobs "${FAULTS_JOBS:-2}" >/dev/null 2>"$WORK/$name.log") || rc=$?
  local err; err=$(grep '^error:' "$WORK/$name.log" || true)
  local ok=1
  [ $rc != 0 ] || { echo "$name: the run succeeded" >&2; ok=0; }
  [ "$(grep -c '^error:' "$WORK/$name.log")" = 1 ] || { echo "$name: not one error line: $(cat "$WORK/$name.log")" >&2; ok=0; }
  grep -qi "$want" <<<"$err" || { echo "$name: error lacks \"$want\": $err" >&2; ok=0; }
  ! grep -q panicked "$WORK/$name.log" || { echo "$name: panic" >&2; ok=0; }
  [ "$before" = "$(state)" ] || { echo "$name: processed/ changed" >&2; ok=0; }
  # Reading still works: status (exit 1: one instance stale) and verify (exit 0).
  local st=0; (cd "$P" && "$@" "$HDI" status >/dev/null 2>&1) || st=$?
  [ $st = 1 ] || { echo "$name: hdi status exit $st (want 1: stale)" >&2; ok=0; }
  (cd "$P" && "$@" "$HDI" verify >"$WORK/$name.verify" 2>&1) || { echo "$name: hdi verify: $(cat "$WORK/$name.verify")" >&2; ok=0; }
  log "$name: exit $rc: $err"
  details+=("$name: $err")
  [ $ok = 1 ] || fails=$((fails + 1))
}

# 1. A read-only bind mount of processed/.
MNT=$P/processed
mount --bind "$MNT" "$MNT"
mount -o remount,bind,ro "$MNT"
try ro-mount "read-only"
umount "$MNT"; MNT=""

# 2. Another user on a processed/ owned by root (0755).
try other-user "permission denied" as_user

# 3. That user owns the project, but the store is read-only: the stage runs, its commit fails.
chown -R "$USER_NAME:$USER_NAME" "$P"
find "$P/processed/.hdi/store" -type d -exec chmod a-w {} +
try store-0555 "permission denied" as_user
find "$P/processed/.hdi/store" -type d -exec chmod u+w {} +
chown -R root:root "$P"

# Writable again: the stale instance runs.
(cd "$P" && "$HDI" run --jobs "${FAULTS_JOBS:-2}" >/dev/null 2>"$WORK/last.log") || {
  echo "the run with write access failed: $(tail -3 "$WORK/last.log")" >&2; fails=$((fails + 1)); }
(cd "$P" && "$HDI" verify >/dev/null 2>&1) || { echo "verify after the last run failed" >&2; fails=$((fails + 1)); }
for d in "${details[@]}"; do log "$d"; done
row "read-only / permission denied ($FAULTS_PIPELINE)" "$([ $fails = 0 ] && echo PASS || echo "FAIL ($fails)")" \
  "ro bind mount, another user, a read-only store: each one clear error, processed/ unchanged, status and verify work; the run with access completes" \
  "$(( ($(ms_now) - START) / 1000 ))"
[ $fails = 0 ]
