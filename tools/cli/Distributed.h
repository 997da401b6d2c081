// Distributed.h — the process group of a bake launched with mpirun (OpenMPI). Without MPI in the
// build, or when brittle is not started by mpirun, the group is this process alone.
//
// What the distributed bake needs and nothing more: rank and size, a barrier, an all-ranks
// agreement on success, and moving whole files (checkpoint chunks) to rank 0, so the ranks need
// not share a file system.
#pragma once

#include <filesystem>
#include <string>

#include "brittle/core/Result.h"

namespace brittle::cli {

class ProcessGroup {
 public:
  /// Joins the MPI job when launched by mpirun (its environment variables are set); otherwise a
  /// group of one. Error: InvalidArgument when launched by mpirun but built without MPI.
  static Result<ProcessGroup> join();
  ProcessGroup(ProcessGroup&& other) noexcept;
  ProcessGroup& operator=(ProcessGroup&&) = delete;
  ~ProcessGroup();  ///< leaves the MPI job (MPI_Finalize) if it joined one

  int rank() const { return mRank; }
  int size() const { return mSize; }
  bool distributed() const { return mJoined; }

  void barrier() const;
  /// true on every rank iff ok on every rank.
  bool allSucceeded(bool ok) const;
  /// Rank `from` sends the file at `path` (its own) to rank 0, which writes it atomically at
  /// `path` (its own). Both must call it. Rank 0 returns the receipt's status on every rank.
  Status sendToRoot(int from, const std::filesystem::path& path) const;

 private:
  ProcessGroup() = default;
  int mRank = 0;
  int mSize = 1;
  bool mJoined = false;
};

}  // namespace brittle::cli
