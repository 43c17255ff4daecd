#!/usr/bin/env bash
# The whole test suite (slow tests included), after the same set-up as main.sh.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/bootstrap.sh
export MPCGEN_CACHE="${MPCGEN_CACHE:-$PWD/.venv/mpcgen-cache}"
exec .venv/bin/python -m pytest -q -n 2 "$@"
