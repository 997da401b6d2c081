// Commands.h — the brittle subcommands. Each registers its options on the app and returns a
// function to run after parsing; logic lives in the libraries, not here.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>

namespace brittle::cli {

using Runner = std::function<int()>;

Runner addBakeCommand(CLI::App& app);
Runner addInspectCommand(CLI::App& app);
Runner addBakeDbCommand(CLI::App& app);
Runner addQueryCommand(CLI::App& app);
Runner addBenchCommand(CLI::App& app);
Runner addImpactCommand(CLI::App& app);
Runner addCalibrateCommand(CLI::App& app);
Runner addCalibrateErrorsCommand(CLI::App& app);
Runner addSizeCommand(CLI::App& app);
Runner addPlayCommand(CLI::App& app);
Runner addViewCommand(CLI::App& app);

}  // namespace brittle::cli

#include <nlohmann/json.hpp>
#include <ostream>

#include "brittle/database/Pack.h"

namespace brittle::cli {

/// The stable JSON document of `brittle inspect --json` (documented in docs/cli.md).
nlohmann::json inspectJson(const Pack& pack);

/// The human-readable inspection.
void printInspection(const Pack& pack, std::ostream& out);

/// Writes pack atomically, reads it back (what is printed is what is on disk; a pack the reader
/// rejects is removed) and prints its inspection, JSON or text. Returns the exit code; on success
/// *written (when given) receives the pack as read back.
int writeAndPrintPack(const Pack& pack, const std::string& path, bool json, Pack* written = nullptr);

}  // namespace brittle::cli
