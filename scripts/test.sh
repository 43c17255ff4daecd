#!/usr/bin/env bash
# The whole test suite (slow tests included), after the same set-up as main.sh:
# lint (ruff), types (mypy), layer contracts (import-linter), then pytest.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/bootstrap.sh
export MPCGEN_CACHE="${MPCGEN_CACHE:-$PWD/.venv/mpcgen-cache}"
echo "test: ruff check" >&2
.venv/bin/ruff check codegen hil tests
echo "test: mypy codegen hil" >&2
.venv/bin/mypy codegen hil
echo "test: lint-imports (layer contracts)" >&2
.venv/bin/lint-imports
exec .venv/bin/python -m pytest -q -n 2 "$@"
