#include "fivebar/trajectory/distributed.h"

#include <cstdlib>
#include <string>

#ifdef FIVEBAR_HAVE_MPI
#include <mpi.h>
#endif

namespace fivebar::trajectory {
namespace {

struct World {
  int rank = 0, size = 1;
  bool initialized_here = false;
  World() {
#ifdef FIVEBAR_HAVE_MPI
    // only under mpirun: a singleton MPI_Init is slow and needs the runtime
    const bool launched = std::getenv("OMPI_COMM_WORLD_SIZE") || std::getenv("PMI_SIZE") ||
                          std::getenv("PMIX_RANK");
    if (!launched) return;
    int flag = 0;
    MPI_Initialized(&flag);
    if (!flag) {
      MPI_Init(nullptr, nullptr);
      initialized_here = true;
    }
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &size);
#endif
  }
  ~World() {
#ifdef FIVEBAR_HAVE_MPI
    int finalized = 0;
    MPI_Finalized(&finalized);
    if (initialized_here && !finalized) MPI_Finalize();
#endif
  }
};

World& world() {
  static World w;
  return w;
}

}  // namespace

int process_rank() { return world().rank; }
int process_count() { return world().size; }

bool built_with_mpi() {
#ifdef FIVEBAR_HAVE_MPI
  return true;
#else
  return false;
#endif
}

std::vector<TaskResult> run_distributed(int count, int threads,
                                        const std::function<TaskResult(int)>& work,
                                        const std::function<void(int, int)>& progress) {
  const int rank = process_rank(), size = process_count();
  // this rank's items: i = rank, rank + size, ...
  const int mine = count > rank ? (count - rank + size - 1) / size : 0;
  std::vector<TaskResult> local = run_parallel(
      mine, threads, [&](int j) { return work(rank + j * size); }, progress);
  if (size == 1) return local;
#ifdef FIVEBAR_HAVE_MPI
  // gather the encoded results on rank 0
  std::string bytes;
  std::vector<long long> lengths;
  for (const TaskResult& r : local) {
    const std::string e = encode(r);
    lengths.push_back(static_cast<long long>(e.size()));
    bytes += e;
  }
  int nbytes = static_cast<int>(bytes.size());
  std::vector<int> counts(size), displs(size);
  MPI_Gather(&nbytes, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, MPI_COMM_WORLD);
  int nlen = static_cast<int>(lengths.size());
  std::vector<int> len_counts(size), len_displs(size);
  MPI_Gather(&nlen, 1, MPI_INT, len_counts.data(), 1, MPI_INT, 0, MPI_COMM_WORLD);
  std::string all;
  std::vector<long long> all_lengths;
  if (rank == 0) {
    int total = 0, total_len = 0;
    for (int r = 0; r < size; ++r) {
      displs[r] = total;
      total += counts[r];
      len_displs[r] = total_len;
      total_len += len_counts[r];
    }
    all.resize(total);
    all_lengths.resize(total_len);
  }
  MPI_Gatherv(bytes.data(), nbytes, MPI_CHAR, all.data(), counts.data(), displs.data(), MPI_CHAR,
              0, MPI_COMM_WORLD);
  MPI_Gatherv(lengths.data(), nlen, MPI_LONG_LONG, all_lengths.data(), len_counts.data(),
              len_displs.data(), MPI_LONG_LONG, 0, MPI_COMM_WORLD);
  if (rank != 0) return {};
  // results of rank r are items r, r + size, ... in order
  std::vector<TaskResult> results(count);
  for (int r = 0; r < size; ++r) {
    size_t pos = static_cast<size_t>(displs[r]);
    for (int j = 0; j < len_counts[r]; ++j) {
      const size_t n = static_cast<size_t>(all_lengths[len_displs[r] + j]);
      results[r + j * size] = decode(all.substr(pos, n));
      pos += n;
    }
  }
  return results;
#else
  return local;
#endif
}

void broadcast_results(std::vector<TaskResult>* results) {
  if (process_count() == 1) return;
#ifdef FIVEBAR_HAVE_MPI
  std::string bytes;
  std::vector<long long> lengths;
  if (process_rank() == 0) {
    for (const TaskResult& r : *results) {
      const std::string e = encode(r);
      lengths.push_back(static_cast<long long>(e.size()));
      bytes += e;
    }
  }
  long long sizes[2] = {static_cast<long long>(lengths.size()),
                        static_cast<long long>(bytes.size())};
  MPI_Bcast(sizes, 2, MPI_LONG_LONG, 0, MPI_COMM_WORLD);
  lengths.resize(static_cast<size_t>(sizes[0]));
  bytes.resize(static_cast<size_t>(sizes[1]));
  MPI_Bcast(lengths.data(), static_cast<int>(sizes[0]), MPI_LONG_LONG, 0, MPI_COMM_WORLD);
  MPI_Bcast(bytes.data(), static_cast<int>(sizes[1]), MPI_CHAR, 0, MPI_COMM_WORLD);
  if (process_rank() == 0) return;
  results->clear();
  size_t pos = 0;
  for (long long n : lengths) {
    results->push_back(decode(bytes.substr(pos, static_cast<size_t>(n))));
    pos += static_cast<size_t>(n);
  }
#endif
}

}  // namespace fivebar::trajectory
