#!/usr/bin/env bash
# littoral's whole test suite on a fresh machine (Debian 12, a Rust
# toolchain, Python 3.10 or newer): installs what the tests need where it is
# missing, then runs every test.
#
#   1. Debian packages (as root): GDAL (gdal-bin) and Chromium, which read
#      the outputs and open the HTML report; python3-venv where Python
#      cannot make a virtual environment; Slurm and munge, brought up as
#      a single-node cluster by .ci/slurm-up.sh for the `littoral plan` test.
#   2. A Python virtual environment ($LITTORAL_VENV, default .venv) with
#      Spectral Python, OpenEXR, numpy and nanodisort (DISORT, for the
#      atmosphere) for the client tests, and the
#      Python package (pip install ./python) with its test extras.
#   3. cargo test --locked; pytest python/tests; cargo fmt --all --check;
#      cargo clippy --all-targets and on the Python bindings, -D warnings.
#
# A plain `cargo test` runs without any of this; the client tests then say
# what they skipped (see README "Testing").
set -euo pipefail
cd "$(dirname "$0")/.."
export CARGO_TERM_COLOR=never
say() { echo "test.sh: $*"; }

# 1. Debian packages.
missing=()
command -v gdalinfo >/dev/null 2>&1 || missing+=(gdal-bin)
command -v chromium >/dev/null 2>&1 || missing+=(chromium)
# Debian's own Python makes virtual environments only with python3-venv.
python3 -c "import ensurepip, venv" >/dev/null 2>&1 || missing+=(python3-venv)
if ((${#missing[@]})); then
  if [[ $(id -u) -ne 0 ]]; then
    say "error: install ${missing[*]} (apt-get, as root) and run again" >&2
    exit 1
  fi
  say "installing ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  apt-get install -y -q "${missing[@]}" >/dev/null 2>&1 ||
    { apt-get update -q >/dev/null && apt-get install -y -q "${missing[@]}" >/dev/null; }
fi
.ci/slurm-up.sh
export LITTORAL_REQUIRE_SLURM=1

# 2. Python: a virtual environment (a stock Debian Python refuses a bare
# pip install), first on PATH so that the client tests' python3 is its.
venv=$(realpath -m "${LITTORAL_VENV:-.venv}")
if [[ ! -x $venv/bin/python ]]; then
  say "making the virtual environment $venv"
  python3 -m venv "$venv"
fi
export PATH="$venv/bin:$PATH"
export PYO3_PYTHON="$venv/bin/python"
export PIP_ROOT_USER_ACTION=ignore PIP_DISABLE_PIP_VERSION_CHECK=1
pip() { python -m pip -q "$@"; }
python -c "import spectral, OpenEXR, numpy, nanodisort" >/dev/null 2>&1 ||
  pip install spectral OpenEXR numpy nanodisort

# 3. The tests. The Python package is built with the test profile, so that
# it shares the build cargo test just made.
export LITTORAL_REQUIRE_CLIENTS=1
cargo test --locked
say "installing the Python package (pip install ./python)"
MATURIN_PEP517_ARGS="--profile dev" pip install "./python[test]"
LITTORAL_BIN_DIR="$PWD/target/debug" python -m pytest -q python/tests
cargo fmt --all --check
cargo clippy --locked --all-targets -- -D warnings
cargo clippy --locked -p littoral-python -- -D warnings
