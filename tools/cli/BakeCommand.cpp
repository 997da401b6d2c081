#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>

#include "CliSupport.h"
#include "Commands.h"
#include "brittle/precompute/BakeManifest.h"
#include "brittle/precompute/BakePipeline.h"
#include "brittle/precompute/FragmentDatabaseBake.h"
#include "brittle/precompute/MaterialLibrary.h"

namespace brittle::cli {
namespace {

struct BakeOptions {
  std::string mesh;
  std::string material;
  std::string manifest;
  std::string name;
  std::string out;
  int64_t tets = 5000;
  double cellSize = 0.0;
  int modes = ModalSettings{}.modeCount;
  bool repair = false;
  double repairVoxel = 0.0;
  bool lumped = false;
  std::string element = "p1";
  bool noFeatures = false;
  double sliverBound = 5.0;
  int meshingRuns = TetMeshSettings{}.meshingRuns;
  double stretch = 1.0;
  double contactSpread = 0.0;
  std::string factorization = "cholmod";
  uint64_t seed = 1;
  bool quiet = false;
  bool json = false;
};

}  // namespace

Runner addBakeCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("bake", "Bake surface meshes into a pack: validate, tet-mesh, FEM, modal basis, stress modes");
  auto o = std::make_shared<BakeOptions>();
  auto* mesh = cmd->add_option("--mesh", o->mesh, "Surface mesh (OFF, OBJ, PLY, STL), closed and outward");
  auto* manifest = cmd->add_option("--manifest", o->manifest, "JSON manifest of several objects (see docs/cli.md)");
  mesh->excludes(manifest);
  cmd->add_option("--material", o->material, "Preset name (" + [] {
    std::string names;
    for (const auto& n : materialPresetNames()) names += (names.empty() ? "" : ", ") + n;
    return names;
  }() + ") or a material JSON file");
  cmd->add_option("--name", o->name, "Object name in the pack (default: mesh file stem)");
  cmd->add_option("--tets", o->tets, "Target number of tetrahedra")->capture_default_str()->check(CLI::Range(int64_t{0}, int64_t{5000000}));
  cmd->add_option("--cell-size", o->cellSize, "Cell size in m (used instead of --tets when given)")->check(CLI::PositiveNumber);
  cmd->add_option("--modes", o->modes, "Number of elastic modes r")->capture_default_str()->check(CLI::Range(1, 2000));
  cmd->add_flag("--repair", o->repair, "Rebuild a watertight surface through an OpenVDB level set first");
  cmd->add_option("--repair-voxel", o->repairVoxel, "Repair voxel size in m (default: longest side / 128)")->check(CLI::PositiveNumber);
  cmd->add_flag("--no-sharp-features", o->noFeatures,
                "Do not protect sharp edges (better element quality on organic or coarse meshes)");
  cmd->add_option("--sliver-bound", o->sliverBound,
                  "Smallest dihedral angle (deg) Mesh_3's optimisers aim for; higher is slower, 0 = best effort")
      ->capture_default_str()->check(CLI::Range(0.0, 30.0));
  cmd->add_option("--meshing-runs", o->meshingRuns,
                  "Mesh_3 runs allowed for the final mesh: when one splits a thin part or makes a degenerate tet, "
                  "the next adjusts (sharp features off, local size, more tets); 1 = no retry")
      ->capture_default_str()->check(CLI::Range(1, 8));
  cmd->add_option("--stretch", o->stretch,
                  "Elements this many times wider than thick across the solid's thinnest axis (flat parts in p2: "
                  "bending needs one element through the thickness, not one as wide as it is thick); 1 = near-regular tets")
      ->capture_default_str()
      ->check(CLI::Validator(  // CLI::Range lets "nan" through
          [](std::string& v) -> std::string {
            char* end = nullptr;
            const double k = std::strtod(v.c_str(), &end);
            return end != v.c_str() && *end == '\0' && isThinStretch(k) ? "" : "must be a number in [1, 16]";
          },
          "[1 - 16]"));
  cmd->add_option("--contact-spread", o->contactSpread,
                  "The object's own floor on the contact load's spread, a fraction of its bounding-box diagonal that its "
                  "mesh resolves; the runtime spreads a hit over the larger of this and its own setting (0: the runtime's alone; "
                  "docs/realtime.md, \"Contact loads\")")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 0.99));
  cmd->add_option("--element", o->element,
                  "Finite element: p1 (4-node tets) or p2 (10-node tets; thin parts, which lock in bending with p1)")
      ->check(CLI::IsMember({"p1", "p2"}))->capture_default_str();
  cmd->add_flag("--lumped-mass", o->lumped, "Use a lumped (diagonal) mass matrix instead of the consistent one");
  cmd->add_option("--factorization", o->factorization, "Sparse factorisation of K - sigma M")
      ->check(CLI::IsMember({"cholmod", "eigen"}))->capture_default_str();
  cmd->add_option("--seed", o->seed, "Seed for meshing and the eigen solver's start vector")->capture_default_str();
  cmd->add_option("--out", o->out, "Output pack (.h5), written atomically")->required();
  cmd->add_flag("--quiet", o->quiet, "No progress display");
  cmd->add_flag("--json", o->json, "Print the inspection of the new pack as JSON");
  cmd->get_option("--cell-size")->excludes(cmd->get_option("--tets"));
  // A manifest carries its own per-object settings: refuse options it would silently override.
  for (const char* perObject : {"--material", "--name", "--tets", "--cell-size", "--modes", "--repair", "--repair-voxel",
                                "--element", "--lumped-mass", "--no-sharp-features", "--sliver-bound", "--meshing-runs", "--stretch", "--contact-spread", "--seed"}) {
    cmd->get_option(perObject)->excludes(manifest);
  }

  return [o, cmd]() -> int {
    // The output's directory must exist (bake creates none); checked first, so that a long bake
    // never ends on a path it cannot write.
    if (const std::filesystem::path dir = std::filesystem::path(o->out).parent_path();
        !dir.empty() && !std::filesystem::is_directory(dir)) {
      return reportError(makeError(ErrorCode::PackIoError, "cannot write pack '" + o->out + "': no directory " + dir.string()));
    }
    std::vector<ObjectBakeSettings> objects;
    if (!o->manifest.empty()) {
      auto loaded = loadBakeManifest(o->manifest);
      if (!loaded) return reportError(loaded.error());
      objects = std::move(loaded).value();
    } else {
      if (o->mesh.empty() || o->material.empty()) {
        std::cerr << "error [invalid_argument]: bake needs --mesh and --material, or --manifest\n" << cmd->help();
        return kExitUsage;
      }
      auto material = resolveMaterial(o->material);
      if (!material) return reportError(material.error());
      ObjectBakeSettings s;
      s.meshPath = o->mesh;
      s.name = o->name;
      s.material = std::move(material).value();
      s.tetMesh.targetTets = o->cellSize > 0.0 ? 0 : o->tets;
      s.tetMesh.cellSizeM = o->cellSize;
      s.tetMesh.seed = o->seed;
      s.tetMesh.detectSharpFeatures = !o->noFeatures;
      s.tetMesh.sliverBoundDeg = o->sliverBound;
      s.tetMesh.meshingRuns = o->meshingRuns;
      s.tetMesh.thinStretch = o->stretch;
      s.contactSpreadFraction = o->contactSpread;
      s.modal.modeCount = o->modes;
      s.modal.seed = o->seed;
      s.repair = o->repair;
      s.repairSettings.voxelSizeM = o->repairVoxel;
      s.fem.lumpedMass = o->lumped;
      s.elementOrder = *parseElementOrder(o->element);
      objects.push_back(std::move(s));
    }
    for (auto& s : objects) s.modal.factorization = o->factorization == "eigen" ? Factorization::EigenLdlt : Factorization::Cholmod;

    std::optional<DatabaseBakeSettings> database;
    if (!o->manifest.empty()) {
      auto section = loadDatabaseManifest(o->manifest);
      if (!section) return reportError(section.error());
      database = std::move(section).value();
    }
    std::vector<ObjectBakeReport> reports;
    Result<Pack> pack = [&]() -> Result<Pack> {
      TerminalProgress progress(o->quiet);
      auto objectsPack = bakePack(objects, &progress, &reports);
      if (!objectsPack || !database) return objectsPack;
      auto db = bakeFragmentDatabase(*database, &progress);
      if (!db) return db.error();
      objectsPack.value().database = std::move(db).value();
      return objectsPack;
    }();
    if (!pack) return reportError(pack.error());
    // What the mesher changed, on stderr so that --json output stays one document.
    for (size_t i = 0; i < reports.size(); ++i) {
      for (const auto& a : reports[i].meshingAdjustments) {
        std::cerr << "adjusted " << a.what << (reports.size() > 1 ? " (" + pack.value().objects[i].name + ")" : "") << ": "
                  << a.why << "\n";
      }
    }
    Pack reread;
    if (int code = writeAndPrintPack(pack.value(), o->out, o->json, &reread); code != kExitOk || o->json) return code;
    for (size_t i = 0; i < reports.size(); ++i) {
      const auto& r = reports[i];
      std::cout << "  check " << reread.objects[i].name << ": tet volume vs surface "
                << 100.0 * r.tetVolumeRelativeError << "%";
      if (objects[i].repair) {
        std::cout << ", repair voxel " << r.repair.voxelSizeM << " m changed the volume by "
                  << 100.0 * r.repair.relativeVolumeChange << "%";
      }
      std::cout << ", " << r.modalStats.operatorApplications << " solves with K - sigma M\n";
    }
    std::cout << "\nwrote " << o->out << "\n";
    return kExitOk;
  };
}

int writeAndPrintPack(const Pack& pack, const std::string& path, bool json, Pack* written) {
  if (Status status = writePack(pack, path); !status) {
    reportError(status.error());
    return kExitPack;  // includes the writer's own checks (InvalidArgument): a pack problem
  }
  auto reread = readPack(path);
  if (!reread) {
    std::error_code ignored;
    std::filesystem::remove(path, ignored);
    reportError(reread.error());
    return kExitPack;
  }
  if (json) {
    std::cout << inspectJson(reread.value()).dump(2) << "\n";
  } else {
    printInspection(reread.value(), std::cout);
  }
  if (written) *written = std::move(reread).value();
  return kExitOk;
}

}  // namespace brittle::cli
