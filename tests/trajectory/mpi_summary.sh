#!/bin/sh
# Usage: mpi_summary.sh MPIEXEC FIVEBAR SOURCE_DIR WORK_DIR
# Runs `fivebar optimize` on the shipped tasks with one process (--threads 1 and 2) and under
# `mpirun -np 2`, and requires the same summary.csv from all three, the wall_time_s column
# (column 8) aside; and the same for `fivebar design` (design_history.csv, design.json).
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
# design: every rank runs the same outer loop; rank 0 writes what one process writes
design() { out=$1; shift; "$@" design --out "$out" "$src/datasets/scenes/paper.yaml" --tasks "$src/datasets/tasks/paper_tasks.yaml" \
  --vary mechanism.links.1.length=0.045:0.065 --max-designs 4 --threads 1 --no-plots > /dev/null; }
design "$work/d1" "$fivebar"
design "$work/dmpi" "$mpiexec" --allow-run-as-root --oversubscribe -np 2 "$fivebar"
cmp "$work/d1/design_history.csv" "$work/dmpi/design_history.csv"
grep -v wall_time_s "$work/d1/design.json" > "$work/d1.json"
grep -v wall_time_s "$work/dmpi/design.json" > "$work/dmpi.json"
cmp "$work/d1.json" "$work/dmpi.json"
echo "design_history.csv and design.json identical for one process and mpirun -np 2"
