#!/usr/bin/env bash
# Every side-by-side ratio of docs/performance.md in one run (bench/README.md):
#   1. the venv bench/.venv from bench/requirements.txt (made once; VENV=… to use another),
#   2. hdi release (cargo build --release; HDI=… to use a built binary instead),
#   3. bench/compare.py: the same .npy inputs for both sides, hdi and the anchor alternately,
#      best of N, one table (figure, hdi, anchor, ratio, goal).
# Usage: bash bench/compare.sh [--repeat N] [--only two-dof,cwt,fft,roughness,bem] [--json]
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(dirname "$here")"
venv="${VENV:-$here/.venv}"
if [ ! -x "$venv/bin/python" ]; then
    python3 -m venv "$venv"
    "$venv/bin/pip" install --quiet -r "$here/requirements.txt"
fi
if [ -z "${HDI:-}" ]; then
    (cd "$root" && cargo build --release --quiet --bin hdi)
    HDI="${CARGO_TARGET_DIR:-$root/target}/release/hdi"
fi
exec "$venv/bin/python" "$here/compare.py" --hdi "$HDI" "$@"
