// CliSupport.h — what every brittle subcommand shares: exit codes, error printing, progress.
#pragma once

#include <string>

#include <CLI/CLI.hpp>

#include "brittle/core/Result.h"
#include "brittle/core/Timing.h"
#include "brittle/precompute/Progress.h"
#include "brittle/runtime/World.h"

namespace brittle::cli {

/// Exit codes (documented in docs/cli.md).
enum ExitCode : int {
  kExitOk = 0,
  kExitInternal = 1,
  kExitUsage = 2,        // CLI11 parse errors
  kExitBadMesh = 3,      // file, format, mesh validity, repair
  kExitBadMaterial = 4,
  kExitSolve = 5,        // meshing, FEM, eigen solve
  kExitPack = 6,         // pack read/write
};

ExitCode exitCodeFor(ErrorCode code);

/// Prints "error [code_name]: message" to stderr and returns the exit code.
int reportError(const Error& error);

/// `--settings FILE` (RuntimeSettingsFile.h) for a command that breaks objects: the file's values
/// replace `fracture`'s, except those the user gave as flags on `cmd` (--modes, --debris,
/// --descriptor, --exact-max-tets, --end-at-cracks, ...), which win: set every flag's value into
/// `fracture` before the call. Errors: those of loadRuntimeSettings.
Status applyRuntimeSettingsFile(const std::string& path, const CLI::App& cmd, FractureSettings& fracture);

/// Progress on stderr: a single rewritten line on a terminal, one line per stage otherwise.
class TerminalProgress final : public ProgressSink {
 public:
  explicit TerminalProgress(bool quiet);
  ~TerminalProgress() override;
  void report(std::string_view stage, double fraction) override;
  void finish();

 private:
  bool mQuiet;
  bool mTty;
  std::string mStage;
  int mPercent = -1;
  SteadyClock::time_point mStart;
};

}  // namespace brittle::cli
