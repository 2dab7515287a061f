#include "parallax/distributed/process_group.h"

#include <chrono>
#include <cstdlib>
#include <thread>

#include "parallax/util/check.h"

#ifdef PARALLAX_HAVE_MPI
#include <mpi.h>
#endif

namespace parallax {

bool BuiltWithMpi() {
#ifdef PARALLAX_HAVE_MPI
  return true;
#else
  return false;
#endif
}

bool StartedByMpiLauncher() {
  for (const char* variable : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_SIZE"}) {
    if (std::getenv(variable) != nullptr) return true;
  }
  return false;
}

#ifdef PARALLAX_HAVE_MPI
namespace {

void CheckMpi(int code, const char* call) {
  if (code == MPI_SUCCESS) return;
  char message[MPI_MAX_ERROR_STRING];
  int length = 0;
  MPI_Error_string(code, message, &length);
  PARALLAX_CHECK_MSG(false, std::string(call) + " failed: " + std::string(message, length));
}

// Waits for a non-blocking collective, sleeping between tests: a blocking MPI call polls at
// full speed, which on a shared machine takes the cores from the ranks still working.
void WaitSleeping(MPI_Request* request) {
  auto pause = std::chrono::microseconds(50);
  for (;;) {
    int done = 0;
    CheckMpi(MPI_Test(request, &done, MPI_STATUS_IGNORE), "MPI_Test");
    if (done) return;
    std::this_thread::sleep_for(pause);
    pause = std::min(pause * 2, std::chrono::microseconds(20000));
  }
}

}  // namespace
#endif

ProcessGroup::ProcessGroup() {
#ifdef PARALLAX_HAVE_MPI
  if (!StartedByMpiLauncher()) return;
  int provided = 0;
  CheckMpi(MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided), "MPI_Init_thread");
  joined_mpi_ = true;
  // Errors come back as codes (CheckMpi) rather than ending the process without a message.
  MPI_Comm_set_errhandler(MPI_COMM_WORLD, MPI_ERRORS_RETURN);
  CheckMpi(MPI_Comm_rank(MPI_COMM_WORLD, &rank_), "MPI_Comm_rank");
  CheckMpi(MPI_Comm_size(MPI_COMM_WORLD, &size_), "MPI_Comm_size");
#endif
}

ProcessGroup::~ProcessGroup() {
#ifdef PARALLAX_HAVE_MPI
  if (joined_mpi_) MPI_Finalize();
#endif
}

void ProcessGroup::Barrier() const {
  if (!IsDistributed()) return;
#ifdef PARALLAX_HAVE_MPI
  MPI_Request request;
  CheckMpi(MPI_Ibarrier(MPI_COMM_WORLD, &request), "MPI_Ibarrier");
  WaitSleeping(&request);
#endif
}

void ProcessGroup::Broadcast(std::string* bytes) const {
  PARALLAX_CHECK(bytes != nullptr);
  if (!IsDistributed()) return;
#ifdef PARALLAX_HAVE_MPI
  int64_t size = IsCoordinator() ? static_cast<int64_t>(bytes->size()) : 0;
  MPI_Request request;
  CheckMpi(MPI_Ibcast(&size, 1, MPI_INT64_T, 0, MPI_COMM_WORLD, &request), "MPI_Ibcast");
  WaitSleeping(&request);
  bytes->resize(static_cast<size_t>(size));
  // In chunks: MPI counts are ints.
  constexpr int64_t kChunk = int64_t{1} << 30;
  for (int64_t offset = 0; offset < size; offset += kChunk) {
    const int count = static_cast<int>(std::min(kChunk, size - offset));
    CheckMpi(MPI_Ibcast(bytes->data() + offset, count, MPI_BYTE, 0, MPI_COMM_WORLD, &request),
             "MPI_Ibcast");
    WaitSleeping(&request);
  }
#endif
}

std::vector<std::vector<int64_t>> ProcessGroup::GatherAll(
    const std::vector<int64_t>& values) const {
  if (!IsDistributed()) return {values};
  std::vector<int64_t> all(values.size() * static_cast<size_t>(size_));
#ifdef PARALLAX_HAVE_MPI
  MPI_Request request;
  const int count = static_cast<int>(values.size());
  CheckMpi(MPI_Iallgather(values.data(), count, MPI_INT64_T, all.data(), count, MPI_INT64_T,
                          MPI_COMM_WORLD, &request),
           "MPI_Iallgather");
  WaitSleeping(&request);
#endif
  std::vector<std::vector<int64_t>> by_rank;
  for (int rank = 0; rank < size_; ++rank) {
    by_rank.emplace_back(all.begin() + rank * values.size(),
                         all.begin() + (rank + 1) * values.size());
  }
  return by_rank;
}

void ProcessGroup::Abort(int exit_code) const {
#ifdef PARALLAX_HAVE_MPI
  if (joined_mpi_) MPI_Abort(MPI_COMM_WORLD, exit_code);
#endif
  std::exit(exit_code);
}

SharedCounter::SharedCounter(const ProcessGroup& group) : group_(group) {
#ifdef PARALLAX_HAVE_MPI
  if (!group_.IsDistributed()) return;
  // The counter lives in a window on the coordinator; ranks add to it with atomic
  // fetch-and-add under a shared lock (MPI-3 one-sided), so nobody has to serve requests.
  void* base = nullptr;
  auto* window = new MPI_Win;
  const MPI_Aint size = group_.IsCoordinator() ? sizeof(int64_t) : 0;
  CheckMpi(MPI_Win_allocate(size, sizeof(int64_t), MPI_INFO_NULL, MPI_COMM_WORLD, &base, window),
           "MPI_Win_allocate");
  if (group_.IsCoordinator()) {
    CheckMpi(MPI_Win_lock(MPI_LOCK_EXCLUSIVE, 0, 0, *window), "MPI_Win_lock");
    *static_cast<int64_t*>(base) = 0;
    CheckMpi(MPI_Win_unlock(0, *window), "MPI_Win_unlock");
  }
  window_ = window;
  group_.Barrier();
#endif
}

SharedCounter::~SharedCounter() {
#ifdef PARALLAX_HAVE_MPI
  if (window_ == nullptr) return;
  auto* window = static_cast<MPI_Win*>(window_);
  group_.Barrier();  // Nobody frees the window while another rank may still add to it.
  MPI_Win_free(window);
  delete window;
#endif
}

int64_t SharedCounter::Next() {
#ifdef PARALLAX_HAVE_MPI
  if (window_ != nullptr) {
    auto* window = static_cast<MPI_Win*>(window_);
    const int64_t one = 1;
    int64_t previous = 0;
    CheckMpi(MPI_Win_lock(MPI_LOCK_SHARED, 0, 0, *window), "MPI_Win_lock");
    CheckMpi(MPI_Fetch_and_op(&one, &previous, MPI_INT64_T, 0, 0, MPI_SUM, *window),
             "MPI_Fetch_and_op");
    CheckMpi(MPI_Win_unlock(0, *window), "MPI_Win_unlock");
    return previous;
  }
#endif
  return local_value_++;
}

}  // namespace parallax
