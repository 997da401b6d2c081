// bench: the benchmarks that write CSV (tools/bench/), one subcommand each.
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "../bench/ElementBench.h"
#include "../bench/ExactModesBench.h"
#include "../bench/FractureStatsBench.h"
#include "../bench/ImpactBench.h"
#include "../bench/IntegratorBench.h"
#include "../bench/ModeCountBench.h"
#include "../bench/ResolutionBench.h"
#include "../bench/SearchBench.h"
#include "CliSupport.h"
#include "Commands.h"
#include "brittle/precompute/BaseShapes.h"

namespace brittle::cli {
namespace {

// Runs a benchmark that writes one CSV: its directory made first, its error reported, its path printed.
template <class Run>
int writeCsv(const std::filesystem::path& csv, Run run) {
  if (csv.has_parent_path()) std::filesystem::create_directories(csv.parent_path());
  if (Status st = run(); !st) return reportError(st.error());
  std::cout << "wrote " << csv.string() << "\n";
  return kExitOk;
}

// An option whose value `yes`, `no` or "both" sets `out` to {true}, {false} or `both` (each value a
// row set of the bench's CSV).
void addEitherOrBoth(CLI::App* cmd, const char* name, std::vector<bool>& out, const char* yes, const char* no,
                     std::vector<bool> both, const char* help) {
  const std::string y = yes, n = no;
  cmd->add_option_function<std::string>(
         name, [&out, y, n, both](const std::string& v) { out = v == y ? std::vector<bool>{true} : v == n ? std::vector<bool>{false} : both; },
         help)
      ->check(CLI::IsMember({y, n, std::string("both")}));
}

}  // namespace

Runner addBenchCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "bench", "Benchmarks that write CSV (charts: tools/scripts/plot_*.py, all redrawn by tools/run-charts.sh)");
  cmd->require_subcommand(1);
  auto* search = cmd->add_subcommand(
      "search", "Descriptor search: recall@1, query time, build time, memory and physical error per setting");
  auto s = std::make_shared<bench::SearchBenchSettings>();
  auto shapes = std::make_shared<std::string>("assets/shapes/base-shapes.json");
  auto kinds = std::make_shared<std::vector<std::string>>(std::vector<std::string>{"moment", "voxel", "voxel-improved"});
  auto indices = std::make_shared<std::vector<std::string>>(
      std::vector<std::string>{"kd-forest:1:8", "kd-forest:4:32", "kd-forest:4:128", "kd-forest:8:512", "hnsw:16:16",
                               "hnsw:16:16:set", "hnsw:16:64", "hnsw-binary:16:16", "hnsw-binary:16:64", "hnsw-binary:16:64:set", "hnsw-pooled:16:32", "hnsw-pooled:16:64", "hnsw-principal:16:32", "hnsw-principal:16:64", "faiss-hnsw:16:16", "faiss-hnsw:16:64", "ivf:256:4", "ivf:1024:8", "ivf:1024:40", "ivf-binary:1024:32", "faiss-ivf:256:8", "faiss-ivf:256:32",
                               "faiss-binary-flat", "faiss-binary-hnsw:16:64"});
  search->add_option("--shapes", *shapes, "Base shape definitions (JSON)")->capture_default_str();
  search->add_option("--sizes", s->sizes, "Database sizes")->delimiter(',')->capture_default_str();
  search->add_option("--kinds", *kinds, "Descriptor kinds")->delimiter(',')->capture_default_str()
      ->check(CLI::IsMember({"moment", "voxel", "voxel-improved"}));
  auto* voxelSizeLimit = search->add_option("--voxel-size-limit", s->voxelSizeLimit, "Largest database size for the voxel kinds")->capture_default_str();
  search->add_option("--index", *indices, "Index settings: kd-forest:TREES:CHECKS, hnsw:M:EF, hnsw-binary:M:EF, hnsw-pooled:M:EF (the voxel kinds: a graph over 8x8x8 block sums, the ef nearest re-ranked exactly; hnsw-principal:M:EF the same over their 64 principal components; a graph with :set searches a fragment's candidate frames in one walk instead of one by one), ivf:LISTS:PROBES (an inverted file over principal components; the moments' and the improved voxels' default), ivf-binary:LISTS:PROBES (an inverted file over the occupancy bits, their default), autotuned:PRECISION, brute-force; FAISS's "
                     "faiss-hnsw:M:EF, faiss-ivf:LISTS:PROBES, faiss-binary-flat, faiss-binary-hnsw:M:EF (the binary kinds, hnsw-binary and ivf-binary too: "
                     "voxel kind only)")
      ->delimiter(',')->capture_default_str();
  search->add_option("--queries", s->queries, "Query fragments")->capture_default_str()->check(CLI::Range(1, 100000));
  search->add_option("--physics-queries", s->physicsQueries, "Queries with a direct bake as ground truth")
      ->capture_default_str()->check(CLI::Range(0, 10000));
  search->add_option("--physics-tets", s->physicsTets, "Tetrahedra per fragment for the physical error")->capture_default_str();
  search->add_option("--min-query-triangles", s->minQueryTriangles,
                     "Query fragments are refined by midpoint subdivision (same solid) to at least this many triangles")
      ->capture_default_str()
      ->check(CLI::Range(int64_t{0}, int64_t{1} << 20));
  auto* runtimeFraction = search->add_option("--runtime-fraction", s->runtimeFraction,
                     "Share of database entries broken off base shapes by the runtime (a second source)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  search->add_flag("--runtime-queries", s->runtimeQueries,
                   "Query with fragments broken off by the runtime instead of exact cuts");
  auto* voxelResolution = search->add_option("--voxel-resolution", s->voxelResolution, "Voxels per axis")->capture_default_str()->check(CLI::Range(2, 64));
  auto* momentOrder = search->add_option("--moment-order", s->momentOrder, "Highest order of the moment descriptor")->capture_default_str()->check(CLI::Range(2, 10));
  search->add_option("--seed", s->seed, "Seed of the database and the queries")->capture_default_str();
  // A database baked once (10⁵ entries with every descriptor: about 28 min on 2 cores) and searched by many runs.
  search->add_option("--database", s->database,
                     "Search this pack's fragment database (bake-db, e.g. --descriptors-only) instead of baking one; its descriptor settings describe the queries")
      ->check(CLI::ExistingFile)
      ->excludes(voxelResolution)
      ->excludes(momentOrder)
      ->excludes(voxelSizeLimit)
      ->excludes(runtimeFraction);
  search->add_option("--csv", s->searchCsv, "Search results CSV")->capture_default_str();
  search->add_option("--cost-csv", s->descriptorCsv, "Descriptor cost CSV")->capture_default_str();
  search->add_flag("--quiet", s->quiet, "No progress lines");
  auto* impact = cmd->add_subcommand(
      "impact", "Impact latency per stage on glass panes of several sizes and mode counts, pruned and unpruned");
  auto is = std::make_shared<bench::ImpactBenchSettings>();
  impact->add_option("--tets", is->tets, "Target tet counts")->delimiter(',')->capture_default_str();
  impact->add_option("--modes", is->modes, "Mode counts")->delimiter(',')->capture_default_str();
  impact->add_option_function<std::string>(
            "--element", [is](const std::string& name) { is->elementOrder = *parseElementOrder(name); },
            "The slab's element: p1 (default) or p2")
      ->check(CLI::IsMember({"p1", "p2"}));
  impact->add_option("--impacts", is->impacts, "Impacts per setting")->capture_default_str()->check(CLI::Range(1, 100000));
  impact->add_option("--speed", is->speedMps, "Impact speed (m/s)")->capture_default_str();
  impact->add_option("--seed", is->seed, "Seed of the impact points and cracks")->capture_default_str();
  impact->add_option("--csv", is->csv, "Output CSV")->capture_default_str();
  auto pb = std::make_shared<bench::PlacementBenchSettings>();
  auto* place = cmd->add_subcommand("place", "Placing each object of a pack against reading its bytes (its background preparation, and a World destroyed during it)");
  place->add_option("pack", pb->pack, "The pack")->required()->check(CLI::ExistingFile);
  place->add_option("--repeats", pb->repeats, "Fresh worlds per object (medians)")->capture_default_str()->check(CLI::Range(1, 1000));
  place->add_option("--csv", pb->csv, "Output CSV")->capture_default_str();
  impact->add_option("--database", is->databasePack,
                     "A pack whose fragment database the fragments are matched against (none: they stay surfaces)");
  impact->add_flag_callback(
      "--whole-database", [is] { is->databaseReading = EntryReading::Whole; },
      "Read every database entry before the first impact instead of each when it is first matched (as the runtime "
      "commands do): the memory and load time of the whole database, for comparison");
  impact->add_option("--exact-max-tets", is->exactModesMaxTets,
                     "With a database: fragments of at most this many parent tets get their own modes (0: all matched)")
      ->capture_default_str()->check(CLI::NonNegativeNumber);
  impact->add_option("--polynomial-degree", is->polynomialModeDegree,
                     "With a database: matched bodies ring at their fragment's own frequencies from polynomial fields of this degree (0: the entries')")
      ->capture_default_str()->check(CLI::Range(0, 5));
  impact->add_option("--mesh-ratio-max-dof", is->meshRatioMaxDof,
                     "With a database: ... the lowest three corrected by the fragment's own linear-tet mesh up to this many degrees of freedom (0: never)")
      ->capture_default_str()->check(CLI::NonNegativeNumber);
  impact->add_option("--threads", is->threads, "The World's worker threads (0: one per core; 1: each impact on one thread)")
      ->capture_default_str()->check(CLI::NonNegativeNumber);
  addEitherOrBoth(impact, "--pruning", is->pruning, "on", "off", {true, false},
                  "The stress scans timed: on (pruned by the stress bounds, the World's default), off (every element at every "
                  "instant) or both (default)");
  addEitherOrBoth(impact, "--cracks", is->crackEnds, "end", "cross", {false, true},
                  "How cracks meet: cross (they run through each other, the World's default), end (each ends at the first "
                  "crack it meets, CrackSettings::endAtCracks) or both");
  impact->add_flag("--quiet", is->quiet, "No progress lines");
  auto* integrators = cmd->add_subcommand(
      "integrators", "Error and stability of the modal time integrators against the time step (ωh from 0.01 to 100)");
  auto ib = std::make_shared<bench::IntegratorBenchSettings>();
  integrators->add_option("--zeta", ib->dampingRatios, "Damping ratios")->delimiter(',')->capture_default_str();
  integrators->add_option("--pulse-steps", ib->pulseSteps, "Steps over the 100 us pulse")->capture_default_str()->check(CLI::Range(2, 10000));
  integrators->add_option("--points", ib->points, "Values of ωh")->capture_default_str()->check(CLI::Range(2, 1000));
  integrators->add_option("--csv", ib->csv, "Error CSV")->capture_default_str();
  integrators->add_option("--timing-csv", ib->timingCsv, "Timing CSV")->capture_default_str();
  auto* modes = cmd->add_subcommand(
      "modes", "Mode count against peak-stress error (full-FEM reference) and impact time, with and without the static correction");
  auto mb = std::make_shared<bench::ModeCountBenchSettings>();
  modes->add_option("--modes", mb->modes, "Mode counts")->delimiter(',')->capture_default_str();
  modes->add_option("--tets", mb->tets, "Target tet count of the plate")->capture_default_str();
  modes->add_option("--points", mb->points, "Impact points")->capture_default_str()->check(CLI::Range(1, 1000));
  modes->add_option("--speed", mb->speedMps, "Impact speed (m/s)")->capture_default_str();
  modes->add_option("--repeats", mb->repeats, "Impacts timed per setting")->capture_default_str()->check(CLI::Range(1, 1000));
  modes->add_option("--reference-steps", mb->referenceStepsPerContact, "Newmark steps per contact time")
      ->capture_default_str()->check(CLI::Range(10, 100000));
  modes->add_option("--seed", mb->seed, "Seed of the impact points")->capture_default_str();
  modes->add_option("--csv", mb->csv, "Output CSV")->capture_default_str();
  modes->add_flag("--quiet", mb->quiet, "No progress lines");
  auto* resolution = cmd->add_subcommand("resolution", "Tet resolution against frequency error and bake time");
  auto rb = std::make_shared<bench::ResolutionBenchSettings>();
  resolution->add_option("--mesh", rb->mesh, "Surface mesh")->capture_default_str();
  resolution->add_option("--material", rb->material, "Material: preset or JSON file")->capture_default_str();
  resolution->add_option("--tets", rb->tets, "Target tet counts (two or more)")->delimiter(',')->capture_default_str();
  resolution->add_option("--modes", rb->modes, "Elastic modes compared")->capture_default_str()->check(CLI::Range(1, 500));
  resolution->add_option("--csv", rb->csv, "Output CSV")->capture_default_str();
  resolution->add_flag("--quiet", rb->quiet, "No progress lines");
  auto* elements = cmd->add_subcommand(
      "elements", "P1 against P2 tets: first-frequency error against DOF, and impact time against that error");
  auto eb = std::make_shared<bench::ElementBenchSettings>();
  elements->add_option("--cases", eb->cases, "Cases: plate, beam, brick")->delimiter(',')->capture_default_str()
      ->check(CLI::IsMember({"plate", "beam", "brick"}));
  elements->add_option("--p1-tets", eb->p1Tets, "P1 tet targets (default: each case's ladder)")->delimiter(',');
  elements->add_option("--p2-tets", eb->p2Tets, "P2 tet targets (default: each case's ladder)")->delimiter(',');
  elements->add_option("--modes", eb->modes, "Modes baked and used by the impacts")->capture_default_str()->check(CLI::Range(1, 500));
  elements->add_option("--impacts", eb->impacts, "Impacts timed per mesh")->capture_default_str()->check(CLI::Range(1, 1000));
  elements->add_option("--speed", eb->speedMps, "Steel ball speed (m/s)")->capture_default_str();
  elements->add_option("--seed", eb->seed, "Seed of the impact points")->capture_default_str();
  elements->add_option("--brick-mesh", eb->brickMesh, "Surface mesh of the brick case")->capture_default_str();
  elements->add_option("--csv", eb->csv, "Output CSV")->capture_default_str();
  elements->add_flag("--quiet", eb->quiet, "No progress lines");
  auto* fracture = cmd->add_subcommand(
      "fracture", "Fragment count and largest fragment's mass share against impact speed, over many seeds");
  auto fb = std::make_shared<bench::FractureStatsBenchSettings>();
  fracture->add_option("--plate-speeds", fb->plateSpeedsMps, "Speeds of the ball on the glass plate (m/s)")
      ->delimiter(',')->capture_default_str();
  fracture->add_option("--brick-speeds", fb->brickSpeedsMps, "Speeds of the brick dropped on a corner (m/s)")
      ->delimiter(',')->capture_default_str();
  fracture->add_option("--seeds", fb->seeds, "Seeds per speed")->capture_default_str()->check(CLI::Range(1, 100000));
  fracture->add_option("--plate-tets", fb->plateTets, "Target tet count of the plate")->capture_default_str();
  fracture->add_option("--brick-tets", fb->brickTets, "Target tet count of the brick")->capture_default_str();
  fracture->add_option("--modes", fb->modes, "Modes per object")->capture_default_str()->check(CLI::Range(1, 500));
  fracture->add_option("--brick-mesh", fb->brickMesh, "Surface mesh of the brick")->capture_default_str();
  fracture->add_option("--csv", fb->csv, "Output CSV")->capture_default_str();
  fracture->add_flag("--quiet", fb->quiet, "No progress lines");
  auto* exact = cmd->add_subcommand(
      "exact-modes", "A fragment's database match against its own modal analysis at runtime, per fragment size");
  auto xb = std::make_shared<bench::ExactModesBenchSettings>();
  exact->add_option("pack", xb->pack, "A pack with a fragment database")->capture_default_str();
  exact->add_option("--objects", xb->objects, "Objects to break (default: all)")->delimiter(',');
  exact->add_option("--speeds", xb->speedsMps, "Ball speeds (m/s)")->delimiter(',')->capture_default_str();
  exact->add_option("--seeds", xb->seeds, "Seeds per speed (impact point and cracks)")->capture_default_str()->check(CLI::Range(1, 10000));
  exact->add_option("--max-fragments", xb->maxFragmentsPerImpact, "Largest fragments measured per impact")
      ->capture_default_str()->check(CLI::Range(1, 1000));
  exact->add_option("--reference-max-tets", xb->referenceMaxTets,
                    "Largest mesh that gets the reference (P2 tets on the exact path's mesh; with --reference-split, that mesh split 1:8)")
      ->capture_default_str()->check(CLI::NonNegativeNumber);
  exact->add_flag("--reference-split", xb->referenceSplit,
                  "Reference on the exact path's mesh split 1:8 (8x the P2 tets: checks the reference's convergence)");
  exact->add_option("--entries", xb->entryLimits,
                    "Match against the database's first N entries only, for each N (0: all): one row per fragment and N")
      ->delimiter(',')->capture_default_str()->check(CLI::NonNegativeNumber);
  exact->add_option("--exact-modes", xb->exactModes, "Modes of the exact path")->capture_default_str()->check(CLI::Range(1, 500));
  exact->add_option("--repeats", xb->repeats, "Timing repeats (median)")->capture_default_str()->check(CLI::Range(1, 100));
  auto exactDescriptor = std::make_shared<std::string>("moment");
  exact->add_option("--descriptor", *exactDescriptor, "Descriptor kind the fragments are matched with")
      ->check(CLI::IsMember({"moment", "voxel", "voxel-improved"}))->capture_default_str();
  exact->callback([xb, exactDescriptor] { xb->descriptor = parseDescriptorKind(*exactDescriptor).value(); });
  exact->add_option("--csv", xb->csv, "Output CSV")->capture_default_str();
  exact->add_flag("--quiet", xb->quiet, "No progress lines");
  return [s, shapes, kinds, indices, impact, is, place, pb, integrators, ib, modes, mb, resolution, rb, elements, eb, fracture,
          fb, exact, xb]() -> int {
    if (elements->parsed()) return writeCsv(eb->csv, [&] { return bench::runElementBench(*eb); });
    if (exact->parsed()) return writeCsv(xb->csv, [&] { return bench::runExactModesBench(*xb); });
    if (fracture->parsed()) return writeCsv(fb->csv, [&] { return bench::runFractureStatsBench(*fb); });
    if (resolution->parsed()) return writeCsv(rb->csv, [&] { return bench::runResolutionBench(*rb); });
    if (modes->parsed()) return writeCsv(mb->csv, [&] { return bench::runModeCountBench(*mb); });
    if (integrators->parsed()) {
      for (const auto& path : {ib->csv, ib->timingCsv}) {
        if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path());
      }
      for (double z : ib->dampingRatios) {
        if (!(z >= 0.0 && z < 1.0)) return reportError(makeError(ErrorCode::InvalidArgument, "--zeta values must be in [0, 1)"));
      }
      if (Status st = bench::runIntegratorBench(*ib); !st) return reportError(st.error());
      std::cout << "wrote " << ib->csv.string() << " and " << ib->timingCsv.string() << "\n";
      return kExitOk;
    }
    if (place->parsed()) return writeCsv(pb->csv, [&] { return bench::runPlacementBench(*pb); });
    if (impact->parsed()) return writeCsv(is->csv, [&] { return bench::runImpactBench(*is); });
    auto loaded = loadBaseShapes(*shapes);
    if (!loaded) return reportError(loaded.error());
    s->shapes = std::move(loaded).value();
    s->kinds.clear();
    for (const auto& k : *kinds) s->kinds.push_back(parseDescriptorKind(k).value());
    s->indices.clear();
    for (const auto& text : *indices) {
      auto choice = bench::parseIndexChoice(text);
      if (!choice) return reportError(choice.error());
      s->indices.push_back(std::move(choice).value());
    }
    for (const auto& path : {s->searchCsv, s->descriptorCsv}) {
      if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path());
    }
    if (Status st = bench::runSearchBench(*s); !st) return reportError(st.error());
    std::cout << "wrote " << s->searchCsv.string() << " and " << s->descriptorCsv.string() << "\n";
    return kExitOk;
  };
}

}  // namespace brittle::cli
