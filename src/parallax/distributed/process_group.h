#pragma once

#include <cstdint>
#include <string>
#include <type_traits>
#include <vector>

namespace parallax {

// The processes of one distributed run: the ranks of the MPI job that started this process
// (mpirun, srun), when Parallax was built with MPI; otherwise this process alone, rank 0 of 1,
// for which every collective call returns at once. Only the thread that made the group may
// call it (MPI_THREAD_FUNNELED); worker threads never do.
class ProcessGroup {
 public:
  // Joins the MPI job when an MPI launcher started this process (see StartedByMpiLauncher);
  // MPI is finalised when the group is destroyed.
  ProcessGroup();
  ~ProcessGroup();
  ProcessGroup(const ProcessGroup&) = delete;
  ProcessGroup& operator=(const ProcessGroup&) = delete;

  int Rank() const { return rank_; }
  int Size() const { return size_; }
  // Rank 0 decides (selects pairs, partitions, merges); the others follow.
  bool IsCoordinator() const { return rank_ == 0; }
  bool IsDistributed() const { return size_ > 1; }

  // Returns once every rank has called it. Waiting ranks sleep instead of spinning, so that
  // a rank merging or adjusting alone gets the cores of the ranks waiting for it.
  void Barrier() const;
  // Every rank gets the coordinator's `bytes`.
  void Broadcast(std::string* bytes) const;
  // Every rank gets the coordinator's `values` (trivially copyable elements).
  template <typename T>
  void Broadcast(std::vector<T>* values) const;
  // Every rank's `values` (the same count on every rank), by rank, on every rank.
  std::vector<std::vector<int64_t>> GatherAll(const std::vector<int64_t>& values) const;
  // Ends every rank of the job with `exit_code` after an error on this one: the others may be
  // waiting for it in a collective call that would otherwise never return.
  [[noreturn]] void Abort(int exit_code) const;

 private:
  int rank_ = 0;
  int size_ = 1;
  bool joined_mpi_ = false;
};

// A counter that the ranks of a group share, for handing out work as ranks free up: each call
// of Next(), on any rank, returns the next of 0, 1, 2, ... (each value to one caller). Creating
// and destroying it are collective calls.
class SharedCounter {
 public:
  explicit SharedCounter(const ProcessGroup& group);
  ~SharedCounter();
  SharedCounter(const SharedCounter&) = delete;
  SharedCounter& operator=(const SharedCounter&) = delete;
  int64_t Next();

 private:
  const ProcessGroup& group_;
  int64_t local_value_ = 0;  // Without MPI.
  void* window_ = nullptr;   // MPI_Win, with MPI.
};

// Whether Parallax was built with MPI (CMake found it; PARALLAX_WITH_MPI).
bool BuiltWithMpi();
// Whether an MPI launcher started this process: OpenMPI's mpirun (OMPI_COMM_WORLD_SIZE), a
// PMIx launcher such as srun --mpi=pmix (PMIX_RANK), or a PMI one (PMI_SIZE).
bool StartedByMpiLauncher();

template <typename T>
void ProcessGroup::Broadcast(std::vector<T>* values) const {
  static_assert(std::is_trivially_copyable_v<T>);
  if (!IsDistributed()) return;
  std::string bytes;
  if (IsCoordinator()) {
    bytes.assign(reinterpret_cast<const char*>(values->data()), values->size() * sizeof(T));
  }
  Broadcast(&bytes);
  values->resize(bytes.size() / sizeof(T));
  if (!bytes.empty())
    std::copy(bytes.begin(), bytes.end(), reinterpret_cast<char*>(values->data()));
}

}  // namespace parallax
