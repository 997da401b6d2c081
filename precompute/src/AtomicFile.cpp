#include "brittle/precompute/AtomicFile.h"

#include <unistd.h>

#include <fstream>
#include <string>

namespace brittle {

Status writeFileAtomically(const std::filesystem::path& path, std::string_view bytes) {
  const std::filesystem::path temporary = path.string() + ".tmp-" + std::to_string(::getpid());
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    out.flush();
    if (!out) {
      std::error_code ignored;
      std::filesystem::remove(temporary, ignored);
      return makeError(ErrorCode::PackIoError, "cannot write '" + temporary.string() + "'");
    }
  }
  std::error_code ec;
  std::filesystem::rename(temporary, path, ec);
  if (ec) {
    std::filesystem::remove(temporary, ec);
    return makeError(ErrorCode::PackIoError, "cannot rename '" + temporary.string() + "' to '" + path.string() + "'");
  }
  return Ok{};
}

}  // namespace brittle
