#!/usr/bin/env bash
# The main job: generate, verify and simulate the example configs (two-level SPMSM and IPMSM, T-type).
# Results land in out/ (C sources, verify/sim JSON, plots).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/bootstrap.sh
export PATH="$PWD/.venv/bin:$PATH"
for cfg in examples/seed001_spmsm.toml examples/seed001_ipmsm.toml examples/seed000_tlevel.toml; do
  name=$(basename "$cfg" .toml)
  for target in host stm32h743 tms320f28377; do
    mpcgen generate "$cfg" --target "$target" -o "out/$name/c/$target" -q >/dev/null
  done
  mpcgen verify "$cfg" --states 1000000 --json "out/$name/verify.json"
  mpcgen simulate "$cfg" --json "out/$name/sim.json" --plots "out/$name/plots"
done
echo "main: done; see out/"
