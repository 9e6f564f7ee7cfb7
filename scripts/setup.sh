#!/usr/bin/env bash
# One-time machine set-up for hdi (idempotent). The only machine-level step of the project:
#  - Debian's HDF5 C library + pkg-config, which the `hdf5-metno` crate links (see docs/hdf5.md);
#  - a Python venv with h5py/pyarrow, used by the tests to check that others can read our files.
set -euo pipefail
cd "$(dirname "$0")/.."

need_apt=0
for pkg in libhdf5-dev pkg-config; do
  dpkg -s "$pkg" >/dev/null 2>&1 || need_apt=1
done
if [ "$need_apt" = 1 ]; then
  SUDO=""
  [ "$(id -u)" = 0 ] || SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends \
    libhdf5-dev pkg-config >/dev/null
fi

# Cross-check tools for the tests (h5py opens our HDF5 with no plugins; pyarrow our Parquet).
if [ ! -x .venv/bin/python ] || ! .venv/bin/python -c "import h5py, pyarrow" 2>/dev/null; then
  python3 -m venv .venv
  .venv/bin/pip install --quiet --disable-pip-version-check h5py numpy pyarrow
fi
