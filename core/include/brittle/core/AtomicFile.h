// AtomicFile.h — writing a file whole or not at all (packs, manifests, settings, reports).
//
// The content goes to a temporary file beside the target, "<name>.tmp-<host>-<pid>-<n>", which is
// synced to disk and then renamed over the target: a reader sees the previous file or the new
// one, never a part, also after a crash. The host and pid keep two writers apart (also on a shared
// file system), the counter two threads of one process. POSIX only (fsync, rename).
#pragma once

#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>

#include "brittle/core/Result.h"

namespace brittle {

namespace atomic_file_detail {

inline std::string hostName() {
  char name[256] = {};
  if (::gethostname(name, sizeof name - 1) != 0) return "host";
  std::string out(name);
  std::replace(out.begin(), out.end(), '-', '_');  // '-' separates the fields of the name
  return out;
}

inline std::string temporaryPrefix(const std::filesystem::path& target) {
  return target.filename().string() + ".tmp-" + hostName() + "-";
}

inline std::filesystem::path temporaryPathFor(const std::filesystem::path& target) {
  static std::atomic<unsigned> counter{0};
  return target.parent_path() /
         (temporaryPrefix(target) + std::to_string(::getpid()) + "-" + std::to_string(counter++));
}

// A writer killed between creating its temporary file and the rename (SIGKILL, power loss)
// leaves the file behind. Remove those of this target whose writer, on this host, is gone.
// Best effort: a file that cannot be removed stays.
inline void removeStaleTemporaries(const std::filesystem::path& target) {
  namespace fs = std::filesystem;
  const std::string prefix = temporaryPrefix(target);
  std::error_code ec;
  const fs::path dir = target.parent_path().empty() ? fs::path(".") : target.parent_path();
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.rfind(prefix, 0) != 0) continue;
    const std::string rest = name.substr(prefix.size());  // "<pid>-<n>"
    const auto dash = rest.find('-');
    if (dash == 0 || dash == std::string::npos || rest.find_first_not_of("0123456789-") != std::string::npos) continue;
    const long pid = std::strtol(rest.substr(0, dash).c_str(), nullptr, 10);
    if (pid <= 0 || pid == ::getpid()) continue;
    if (::kill(static_cast<pid_t>(pid), 0) == 0 || errno != ESRCH) continue;  // alive, or not ours to judge
    std::error_code ignored;
    fs::remove(it->path(), ignored);
  }
}

// The rename is only atomic with respect to a crash if the new file's data reached the disk
// first; otherwise the rename could survive a power loss while the data does not.
inline Status syncToDisk(const std::filesystem::path& file) {
  const int fd = ::open(file.c_str(), O_RDONLY);
  if (fd < 0) {
    return makeError(ErrorCode::PackIoError, "cannot reopen '" + file.string() + "' to sync it: " + std::strerror(errno));
  }
  const int rc = ::fsync(fd);
  const int savedErrno = errno;
  ::close(fd);
  if (rc != 0) {
    return makeError(ErrorCode::PackIoError, "cannot sync '" + file.string() + "' to disk: " + std::strerror(savedErrno));
  }
  return Ok{};
}

// Makes the rename itself durable. Best effort: some file systems refuse fsync on a directory,
// and by then the file is already whole on disk.
inline void syncDirectory(const std::filesystem::path& dir) {
  const int fd = ::open(dir.empty() ? "." : dir.c_str(), O_RDONLY | O_DIRECTORY);
  if (fd < 0) return;
  (void)::fsync(fd);
  ::close(fd);
}

// Removes the temporary file on every way out but a successful rename, exceptions included.
class TemporaryFile {
 public:
  explicit TemporaryFile(std::filesystem::path path) : mPath(std::move(path)) {}
  TemporaryFile(const TemporaryFile&) = delete;
  TemporaryFile& operator=(const TemporaryFile&) = delete;
  ~TemporaryFile() {
    if (mPath.empty()) return;
    std::error_code ignored;
    std::filesystem::remove(mPath, ignored);
  }
  const std::filesystem::path& path() const { return mPath; }
  void release() { mPath.clear(); }

 private:
  std::filesystem::path mPath;
};

}  // namespace atomic_file_detail

/// Writes `path` whole or not at all: first removes temporaries of `path` left by writers that
/// died on this host, then calls `write(temporary)`, which must create and fill the file at
/// `temporary` (beside `path`) and close it; then syncs it, renames it over `path` and syncs the
/// directory. On any failure, or if `write` throws, the temporary is removed and `path` is
/// untouched. `write` takes the temporary path and returns Status.
/// Errors: the error `write` returned, or PackIoError naming the file that could not be synced or
/// renamed.
template <typename WriteTo>
Status writeAtomically(const std::filesystem::path& path, WriteTo&& write) {
  namespace detail = atomic_file_detail;
  if (!path.has_filename()) return makeError(ErrorCode::PackIoError, "'" + path.string() + "' is not a file name");
  detail::removeStaleTemporaries(path);
  detail::TemporaryFile temporary(detail::temporaryPathFor(path));
  if (Status written = std::forward<WriteTo>(write)(temporary.path()); !written) return written.error();
  if (Status synced = detail::syncToDisk(temporary.path()); !synced) return synced.error();
  std::error_code ec;
  std::filesystem::rename(temporary.path(), path, ec);
  if (ec) {
    return makeError(ErrorCode::PackIoError,
                     "cannot rename '" + temporary.path().string() + "' to '" + path.string() + "': " + ec.message());
  }
  temporary.release();
  detail::syncDirectory(path.parent_path());
  return Ok{};
}

/// Writes `bytes` to `path` whole or not at all (writeAtomically).
/// Errors: PackIoError naming the file that could not be written, synced or renamed.
inline Status writeFileAtomically(const std::filesystem::path& path, std::string_view bytes) {
  return writeAtomically(path, [&](const std::filesystem::path& temporary) -> Status {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    out.close();
    if (!out) return makeError(ErrorCode::PackIoError, "cannot write '" + temporary.string() + "'");
    return Ok{};
  });
}

}  // namespace brittle
