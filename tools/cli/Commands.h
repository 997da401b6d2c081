// Commands.h — the brittle subcommands. Each registers its options on the app and returns a
// function to run after parsing; logic lives in the libraries, not here.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>

namespace brittle::cli {

using Runner = std::function<int()>;

Runner addBakeCommand(CLI::App& app);
Runner addInspectCommand(CLI::App& app);

}  // namespace brittle::cli

#include <nlohmann/json.hpp>
#include <ostream>

#include "brittle/database/Pack.h"

namespace brittle::cli {

/// The stable JSON document of `brittle inspect --json` (documented in the README).
nlohmann::json inspectJson(const Pack& pack);

/// The human-readable inspection.
void printInspection(const Pack& pack, std::ostream& out);

}  // namespace brittle::cli
