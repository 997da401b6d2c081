// FuzzSupport.h — what every fuzz target shares: a scratch directory for the readers that take a
// path, and the check that a reader's error is one of the codes its header documents.
#pragma once

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <string>
#include <string_view>
#include <system_error>

#include "brittle/core/Result.h"

namespace brittle::fuzz {

/// A directory of this process under the system temp directory, made on first use and removed
/// at exit. Its files are overwritten by every input, so the disk use stays constant.
inline const std::filesystem::path& scratchDir() {
  struct Dir {
    std::filesystem::path path;
    Dir() {
      path = std::filesystem::temp_directory_path() / ("brittle-fuzz-" + std::to_string(getpid()));
      std::filesystem::create_directories(path);
    }
    ~Dir() {
      std::error_code ec;
      std::filesystem::remove_all(path, ec);
    }
  };
  static const Dir dir;
  return dir.path;
}

/// Writes bytes to a file in scratchDir() and returns its path.
inline std::filesystem::path writeScratchFile(const std::string& name, const uint8_t* data, size_t size) {
  const std::filesystem::path path = scratchDir() / name;
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  if (!out) {
    std::fprintf(stderr, "fuzz: cannot write %s\n", path.c_str());
    std::abort();
  }
  return path;
}

inline std::filesystem::path writeScratchFile(const std::string& name, std::string_view text) {
  return writeScratchFile(name, reinterpret_cast<const uint8_t*>(text.data()), text.size());
}

/// Writes "custom.json", a valid material file, into scratchDir(): the readers that name material
/// files relative to their own file (manifests, scene requirements) can then reach that branch.
inline void writeCustomMaterialFile() {
  writeScratchFile("custom.json", R"({"name": "custom", "youngs_modulus_pa": 7.2e10, "poisson_ratio": 0.22,
  "density_kg_per_m3": 2500, "tensile_strength_pa": 5e7, "fracture_energy_j_per_m2": 7.4,
  "rayleigh_alpha_per_s": 0, "rayleigh_beta_s": 1.6e-7, "restitution": 0.5, "source": "fuzz fixture"})");
}

/// A finding, not a rejection: prints why and aborts, so that libFuzzer keeps the input.
[[noreturn]] inline void finding(const std::string& what) {
  std::fprintf(stderr, "fuzz finding: %s\n", what.c_str());
  std::abort();
}

/// A reader may refuse any input, but only with one of the codes its header lists and with a
/// message that says something.
template <typename T>
void expectDocumentedError(const Result<T>& result, std::initializer_list<ErrorCode> documented) {
  if (result.ok()) return;
  const Error& e = result.error();
  for (ErrorCode code : documented) {
    if (e.code == code) {
      if (e.message.empty()) finding(std::string(errorCodeName(code)) + " with an empty message");
      return;
    }
  }
  finding("undocumented error code " + std::string(errorCodeName(e.code)) + ": " + e.message);
}

}  // namespace brittle::fuzz
