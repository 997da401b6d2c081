// brittle — the command-line tool: bake packs, inspect them, query the database, break objects.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>
#include <map>

#include "Commands.h"
#include "CliSupport.h"
#include "brittle/core/EigenBlocking.h"

int main(int argc, char** argv) {
  brittle::pinEigenBlocking();  // the same packs and fractures on every CPU (EigenBlocking.h)
  CLI::App app{"brittle: bake breakable objects and a fragment shape database offline (tet meshes, modal bases, stress modes, shape descriptors) into HDF5 packs"};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("brittle ") + BRITTLE_VERSION);
  std::map<CLI::App*, brittle::cli::Runner> runners;
  auto add = [&](const char* name, brittle::cli::Runner runner) { runners[app.get_subcommand(name)] = std::move(runner); };
  add("bake", brittle::cli::addBakeCommand(app));
  add("inspect", brittle::cli::addInspectCommand(app));
  add("bake-db", brittle::cli::addBakeDbCommand(app));
  add("query", brittle::cli::addQueryCommand(app));
  add("bench", brittle::cli::addBenchCommand(app));
  add("impact", brittle::cli::addImpactCommand(app));
  add("calibrate", brittle::cli::addCalibrateCommand(app));
  add("calibrate-errors", brittle::cli::addCalibrateErrorsCommand(app));
  add("size", brittle::cli::addSizeCommand(app));
  add("play", brittle::cli::addPlayCommand(app));
  add("view", brittle::cli::addViewCommand(app));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : brittle::cli::kExitUsage;
  }
  try {
    for (auto* sub : app.get_subcommands()) return runners.at(sub)();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error [internal]: %s\n", e.what());
    return brittle::cli::kExitInternal;
  } catch (...) {
    std::fprintf(stderr, "error [internal]: unknown exception\n");
    return brittle::cli::kExitInternal;
  }
  return brittle::cli::kExitUsage;
}
