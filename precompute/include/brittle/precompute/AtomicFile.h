// AtomicFile.h — writing a small file whole or not at all.
#pragma once

#include <filesystem>
#include <string_view>

#include "brittle/core/Result.h"

namespace brittle {

/// Writes `bytes` to a temporary file beside `path` (named after the process id), then renames it
/// over `path`: a reader sees the previous file or the new one, never a part. On failure the
/// temporary is removed and `path` is untouched.
/// Error: PackIoError naming the file that could not be written or renamed.
Status writeFileAtomically(const std::filesystem::path& path, std::string_view bytes);

}  // namespace brittle
