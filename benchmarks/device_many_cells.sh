#!/usr/bin/env bash
# The 8 x 8 patch's step on a GPU (issue 25 item 5), as one short script for a lent device
# machine: 64 cells rolling on pairs for 2 ms (benchmarks/many_cells.py part 2) on CUDA and on the
# same machine's CPU, side by side in one run. The tables and many_cells_cost_*.csv land in $OUT
# (default results/bench). Run from the repository root:
#   bash benchmarks/device_many_cells.sh
set -euo pipefail
python3 -m venv .venv && .venv/bin/pip install -q -e '.[test]'
export PYTHONUNBUFFERED=1
out=${OUT:-results/bench}
mkdir -p "$out"
for device in cuda:0 cpu; do
    .venv/bin/python benchmarks/many_cells.py --parts cost --cells 64 --system-cells --remainder-cells --device "$device" \
        2>&1 | tee "$out/many_cells_$device.log"
    cp results/bench/many_cells_cost.csv "$out/many_cells_cost_${device/:/}.csv"
done
