#!/bin/sh
# Usage: mpi_summary.sh MPIEXEC FIVEBAR SOURCE_DIR WORK_DIR
# Runs `fivebar optimize` on the shipped tasks with one process (--threads 1 and 2) and under
# `mpirun -np 2`, and requires the same summary.csv from all three, the wall_time_s column
# (column 8) aside.
set -eu
mpiexec=$1 fivebar=$2 src=$3 work=$4
rm -rf "$work" && mkdir -p "$work"
run() { "$@" "$src/datasets/scenes/paper.yaml" --tasks "$src/datasets/tasks/paper_tasks.yaml" --no-plots --no-refine > /dev/null; }
run "$fivebar" optimize --out "$work/t1" --threads 1
run "$fivebar" optimize --out "$work/t2" --threads 2
run "$mpiexec" --allow-run-as-root --oversubscribe -np 2 "$fivebar" optimize --out "$work/mpi" --threads 1
for d in t1 t2 mpi; do cut -d, -f1-7,9- "$work/$d/summary.csv" > "$work/$d.csv"; done
cmp "$work/t1.csv" "$work/t2.csv"
cmp "$work/t1.csv" "$work/mpi.csv"
echo "summary.csv identical for --threads 1, --threads 2 and mpirun -np 2"
