#!/usr/bin/env bash
# One-time machine set-up for hdi (idempotent). The only machine-level step of the project:
#  - Debian's HDF5 C library + pkg-config, which the `hdf5-metno` crate links (see docs/hdf5.md);
#  - Debian's Chromium, which renders `hdi report`'s page headless in the tests;
#  - a Python venv with h5py/pyarrow (the tests check that others can read our files) and
#    jsonschema (every `--json` output is validated against its schema in docs/schemas/).
set -euo pipefail
cd "$(dirname "$0")/.."

need_apt=0
for pkg in libhdf5-dev pkg-config chromium; do
  dpkg -s "$pkg" >/dev/null 2>&1 || need_apt=1
done
if [ "$need_apt" = 1 ]; then
  SUDO=""
  [ "$(id -u)" = 0 ] || SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends \
    libhdf5-dev pkg-config chromium >/dev/null
fi

# Cross-check tools for the tests (h5py opens our HDF5 with no plugins; pyarrow our Parquet).
if [ ! -x .venv/bin/python ] || ! .venv/bin/python -c "import h5py, pyarrow, jsonschema" 2>/dev/null; then
  python3 -m venv .venv
  .venv/bin/pip install --quiet --disable-pip-version-check h5py numpy pyarrow jsonschema
fi
