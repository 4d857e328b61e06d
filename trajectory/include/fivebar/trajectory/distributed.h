// Work split across MPI ranks when the library is built with MPI (FIVEBAR_HAVE_MPI) and the
// process was started by mpirun; a single process otherwise.
#pragma once

#include <functional>
#include <vector>

#include "fivebar/trajectory/batch.h"

namespace fivebar::trajectory {

/// Rank of this process and number of processes (0 and 1 without MPI). The first call
/// initializes MPI when the environment shows an MPI launch (OMPI_COMM_WORLD_SIZE, PMI_SIZE or
/// PMIX_RANK set); MPI is finalized at exit.
int process_rank();
int process_count();
/// True if the library was built with MPI support.
bool built_with_mpi();

/// run_parallel over the items i with i % process_count() == process_rank(), then gathered on
/// rank 0: rank 0 returns all `count` results in index order (identical to a one-process run,
/// since each result depends only on i); the other ranks return an empty vector. `progress`
/// sees this rank's items only.
std::vector<TaskResult> run_distributed(int count, int threads,
                                        const std::function<TaskResult(int)>& work,
                                        const std::function<void(int, int)>& progress = {});

/// Sends rank 0's `results` to every rank (a no-op in one process), so that every rank can take
/// the same decision from them (the outer loop of `fivebar design`).
void broadcast_results(std::vector<TaskResult>* results);

}  // namespace fivebar::trajectory
