#include "Distributed.h"

#include "brittle/core/AtomicFile.h"

#include <cstdlib>
#include <fstream>
#include <iterator>
#include <string_view>
#include <vector>

#ifdef BRITTLE_WITH_MPI
#include <mpi.h>
#endif

namespace brittle::cli {
namespace {

bool launchedByMpirun() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK"}) {
    if (std::getenv(name)) return true;
  }
  return false;
}

[[maybe_unused]] Result<std::vector<char>> readBytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return makeError(ErrorCode::FileNotFound, "cannot open '" + path.string() + "'");
  return std::vector<char>((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

}  // namespace

Result<ProcessGroup> ProcessGroup::join() {
  ProcessGroup group;
  if (!launchedByMpirun()) return group;
#ifdef BRITTLE_WITH_MPI
  int initialised = 0;
  MPI_Initialized(&initialised);
  if (!initialised) MPI_Init(nullptr, nullptr);
  MPI_Comm_rank(MPI_COMM_WORLD, &group.mRank);
  MPI_Comm_size(MPI_COMM_WORLD, &group.mSize);
  group.mJoined = true;
  return group;
#else
  return makeError(ErrorCode::InvalidArgument,
                   "started by mpirun, but this brittle was built without MPI (install libopenmpi-dev and rebuild)");
#endif
}

ProcessGroup::ProcessGroup(ProcessGroup&& other) noexcept
    : mRank(other.mRank), mSize(other.mSize), mJoined(other.mJoined) {
  other.mJoined = false;
}

ProcessGroup::~ProcessGroup() {
#ifdef BRITTLE_WITH_MPI
  if (mJoined) MPI_Finalize();
#endif
}

void ProcessGroup::barrier() const {
#ifdef BRITTLE_WITH_MPI
  if (mJoined) MPI_Barrier(MPI_COMM_WORLD);
#endif
}

bool ProcessGroup::allSucceeded(bool ok) const {
#ifdef BRITTLE_WITH_MPI
  if (mJoined) {
    int mine = ok ? 1 : 0, all = 0;
    MPI_Allreduce(&mine, &all, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
    return all == 1;
  }
#endif
  return ok;
}

Status ProcessGroup::sendToRoot(int from, const std::filesystem::path& path) const {
  if (from == 0 || !mJoined) return Ok{};
#ifdef BRITTLE_WITH_MPI
  // A size first (−1: the sender could not read its file), then the bytes in pieces of ≤ 1 GiB
  // (MPI counts are ints).
  constexpr long long kPiece = 1ll << 30;
  int status = 0;
  if (mRank == from) {
    auto bytes = readBytes(path);
    long long size = bytes ? static_cast<long long>(bytes.value().size()) : -1;
    MPI_Send(&size, 1, MPI_LONG_LONG, 0, 0, MPI_COMM_WORLD);
    for (long long at = 0; at < size; at += kPiece) {
      MPI_Send(bytes.value().data() + at, static_cast<int>(std::min(kPiece, size - at)), MPI_CHAR, 0, 1,
               MPI_COMM_WORLD);
    }
  } else if (mRank == 0) {
    long long size = 0;
    MPI_Recv(&size, 1, MPI_LONG_LONG, from, 0, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    std::vector<char> bytes(static_cast<size_t>(std::max(size, 0ll)));
    for (long long at = 0; at < size; at += kPiece) {
      MPI_Recv(bytes.data() + at, static_cast<int>(std::min(kPiece, size - at)), MPI_CHAR, from, 1, MPI_COMM_WORLD,
               MPI_STATUS_IGNORE);
    }
    status = size < 0 ? 1 : (writeFileAtomically(path, std::string_view(bytes.data(), bytes.size())) ? 0 : 2);
  }
  MPI_Bcast(&status, 1, MPI_INT, 0, MPI_COMM_WORLD);
  if (status == 1) return makeError(ErrorCode::PackIoError, "rank " + std::to_string(from) + " cannot read '" + path.string() + "'");
  if (status == 2) return makeError(ErrorCode::PackIoError, "rank 0 cannot write '" + path.string() + "'");
  return Ok{};
#else
  (void)path;
  return Ok{};
#endif
}

}  // namespace brittle::cli
