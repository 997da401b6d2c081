#include "ImpactBench.h"

#include "BenchSupport.h"

#include <algorithm>
#include <cstdio>
#include <chrono>
#include <fstream>
#include <memory>
#include <random>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "brittle/core/Timing.h"
#include "brittle/database/Pack.h"
#include "brittle/precompute/BakePipeline.h"
#include "brittle/precompute/MaterialLibrary.h"
#include "brittle/runtime/World.h"

namespace brittle::bench {
namespace {

// The (pruned, cracks end at cracks) pairs timed, pruning's outer.
std::vector<std::pair<bool, bool>> timedSchemes(const ImpactBenchSettings& s) {
  std::vector<std::pair<bool, bool>> schemes;
  for (bool prune : s.pruning) {
    for (bool ends : s.crackEnds) schemes.emplace_back(prune, ends);
  }
  return schemes;
}

}  // namespace

Status runImpactBench(const ImpactBenchSettings& s) {
  std::ofstream csv(s.csv);
  if (!csv) return makeError(ErrorCode::PackIoError, "cannot write " + s.csv.string());
  csv << "target_tets,tets,modes,prune,stage,impacts,median_ms,p99_ms,broken_fraction,mean_fragments,median_evaluations,element,cracks,mean_cut_elements\n";
  const Material glass = materialPreset("glass").value();
  FragmentDatabase database;
  if (!s.databasePack.empty()) {
    const auto t0 = SteadyClock::now();
    auto source = readPack(s.databasePack, s.databaseReading);
    if (!source) return source.error();
    database = std::move(source.value().database);
    std::printf("database: %zu entries read in %.2f s (%s)\n", database.entries.size(), secondsSince(t0),
                s.databaseReading == EntryReading::OnDemand ? "their arrays on demand" : "whole");
    if (database.empty() || !database.hasPhysics()) {
      return makeError(ErrorCode::InvalidArgument, s.databasePack.string() + " has no fragment database with modal data");
    }
  }
  const int maxModes = *std::max_element(s.modes.begin(), s.modes.end());
  for (int64_t target : s.tets) {
    ObjectBakeSettings b;
    b.name = "pane";
    b.material = glass;
    b.tetMesh.targetTets = target;
    b.modal.modeCount = maxModes;
    b.elementOrder = s.elementOrder;
    auto asset = bakeSurface(boxSurface(0.2, 0.2, 0.05), b);
    if (!asset) return asset.error();
    const int64_t tets = asset.value().tetMesh.tets.rows();
    Pack pack;
    pack.materials.push_back(glass);
    pack.objects.push_back(std::move(asset).value());
    pack.database = database;
    for (int modes : s.modes) {
      for (const auto& [prune, endAtCracks] : timedSchemes(s)) {
        WorldSettings ws;
        ws.seed = s.seed;
        ws.fracture.modeCount = modes;
        ws.fracture.pruneStresses = prune;
        ws.fracture.crack.endAtCracks = endAtCracks;
        // Without a database fragments stay surfaces; with one they become objects, whose bodies
        // are timed apart (the first call that needs each waits for it).
        ws.fracture.matchFragments = !database.empty();
        ws.fracture.exactModesMaxTets = s.exactModesMaxTets;
        ws.fracture.polynomialModeDegree = s.polynomialModeDegree;
        ws.fracture.meshRatioMaxDof = s.meshRatioMaxDof;
        ws.workerThreads = s.threads;
        auto world = World::create(Pack(pack), ws);
        if (!world) return world.error();
        // The object placed once and its K factorised before the clock starts, as a host places its
        // objects when a level loads: the impacts timed below are warm (placement has its own bench).
        if (auto warm = world.value().addObject({.asset = "pane"}); !warm) return warm.error();
        if (Status st = world.value().waitUntilPrepared(); !st) return st.error();
        std::mt19937_64 rng(s.seed);
        std::uniform_real_distribution<double> where(-0.08, 0.08);
        std::vector<std::vector<double>> stage(10);
        std::vector<double> evaluations;
        int broken = 0;
        double fragments = 0.0, cutElements = 0.0;
        ImpactResult result;  // reused, as a host's hot path would
        for (int i = 0; i < s.impacts; ++i) {
          auto id = world.value().addObject({.asset = "pane"});
          if (!id) return id.error();
          ImpactDesc d;
          d.object = id.value();
          const double x = where(rng);
          const double y = where(rng);
          d.pointWorld = Eigen::Vector3d(x, y, 0.025);
          d.normalWorld = Eigen::Vector3d::UnitZ();
          d.speedMps = s.speedMps;
          d.impactorMassKg = 0.1;
          d.impactorRadiusM = 0.02;
          if (Status st = world.value().impact(d, result); !st) return st.error();
          const ImpactResult& r = result;
          const StageTimes& t = r.times;
          const auto b0 = SteadyClock::now();
          for (const FragmentResult& f : r.fragments) {  // makes each new object's modal data
            if (f.object.valid()) (void)world.value().objectAsset(f.object);
          }
          const double bodiesS = secondsSince(b0);
          const double ms[] = {t.contactS, t.modalS, t.stressS, t.propagationS, t.surfacesS, t.matchingS, t.totalS(),
                               t.totalS() - t.surfacesS - t.propagationS, bodiesS, t.totalS() + bodiesS};
          for (size_t k = 0; k < 10; ++k) stage[k].push_back(1e3 * ms[k]);
          evaluations.push_back(static_cast<double>(r.stressEvaluations));
          broken += r.broken ? 1 : 0;
          fragments += static_cast<double>(r.fragments.size());
          cutElements += static_cast<double>(r.fracture.cutElements.size());
          if (world.value().isAlive(id.value())) (void)world.value().removeObject(id.value());
          for (const FragmentResult& f : r.fragments) {
            if (f.object.valid()) (void)world.value().removeObject(f.object);
          }
          // Each impact is timed on an idle world: what the last one left on the workers (its
          // fragments' checks and factorisations) is done first, as it would be between two hits a
          // frame apart or more, instead of sharing the two cores with the next impact's clock.
          if (Status st = world.value().waitUntilPrepared(); !st) return st.error();
        }
        static const char* kStages[] = {"contact", "modal", "stress", "propagation", "surfaces", "matching", "total",
                                        "to_initiation", "bodies", "to_objects"};
        for (size_t k = 0; k < 10; ++k) {
          csv << target << "," << tets << "," << modes << "," << (prune ? 1 : 0) << "," << kStages[k] << "," << s.impacts
              << "," << percentile(stage[k], 0.5) << "," << percentile(stage[k], 0.99) << ","
              << static_cast<double>(broken) / s.impacts << "," << fragments / s.impacts << "," << percentile(evaluations, 0.5)
              << "," << elementOrderName(s.elementOrder) << "," << (endAtCracks ? "end" : "cross") << ","
              << cutElements / s.impacts << "\n";
        }
        if (!s.quiet) {
          std::printf("%6lld tets %3d modes %-9s total median %8.2f ms p99 %8.2f ms (stress %.2f, cracks %.2f, surfaces %.2f, "
                      "matching %.2f); bodies after %.2f ms; %.1f fragments%s\n",
                      static_cast<long long>(tets), modes, prune ? "pruned" : "unpruned", percentile(stage[6], 0.5),
                      percentile(stage[6], 0.99), percentile(stage[2], 0.5), percentile(stage[3], 0.5), percentile(stage[4], 0.5),
                      percentile(stage[5], 0.5), percentile(stage[8], 0.5), fragments / s.impacts,
                      endAtCracks ? ", cracks ending at cracks" : "");
          std::fflush(stdout);
        }
      }
    }
  }
  return Ok{};
}

namespace {

double arrayBytes(const ObjectAsset& a) {
  return 8.0 * static_cast<double>(a.tetMesh.nodes.size() + a.modal.modes.size() + a.stressModes.size()) +
         4.0 * static_cast<double>(a.tetMesh.tets.size());
}

}  // namespace

Status runPlacementBench(const PlacementBenchSettings& s) {
  std::ofstream csv(s.csv);
  if (!csv) return makeError(ErrorCode::PackIoError, "cannot write " + s.csv.string());
  std::vector<double> reads;
  Pack pack;
  for (int r = 0; r < s.repeats; ++r) {
    const auto t0 = SteadyClock::now();
    auto read = readPack(s.pack);
    if (!read) return read.error();
    reads.push_back(secondsSince(t0));
    pack = std::move(read).value();
  }
  double total = 0.0;
  for (const ObjectAsset& a : pack.objects) total += arrayBytes(a);
  const double packReadS = percentile(reads, 0.5);
  csv << "object,tets,read_share_ms,place_ms,place_over_read,background_prepare_ms,destroy_prepared_ms,"
         "destroy_midway_ms,destroy_midway_max_ms,preparation_left_ms\n";
  std::printf("pack read %.1f ms (median of %d)\n", 1e3 * packReadS, s.repeats);
  for (const ObjectAsset& a : pack.objects) {
    std::vector<double> place, prepare, destroyPrepared, destroyMidway;
    auto makeWorld = [&]() -> Result<std::unique_ptr<World>> {
      Pack one;
      one.materials = pack.materials;
      one.objects.push_back(a);
      auto world = World::create(std::move(one), WorldSettings{});
      if (!world) return world.error();
      return std::make_unique<World>(std::move(world).value());
    };
    auto destroy = [](std::unique_ptr<World>& world) {
      const auto t = SteadyClock::now();
      world.reset();
      return secondsSince(t);
    };
    for (int r = 0; r < s.repeats; ++r) {
      auto world = makeWorld();
      if (!world) return world.error();
      const auto t0 = SteadyClock::now();
      auto id = world.value()->addObject({.asset = a.name});
      place.push_back(secondsSince(t0));
      if (!id) return id.error();
      const auto t1 = SteadyClock::now();
      if (Status st = world.value()->waitUntilPrepared(); !st) return st.error();
      prepare.push_back(secondsSince(t1));
      destroyPrepared.push_back(destroy(world.value()));  // freeing what it holds: the floor
    }
    // A World destroyed a quarter, half and three quarters into the preparation: its destructor
    // stops the preparation at its next cancellation point. Before, it waited for the rest of it,
    // the reference (preparation_left_ms: the median preparation less the time waited).
    const double prepareS = percentile(prepare, 0.5);
    double leftS = 0.0;
    for (int r = 0; r < s.repeats; ++r) {
      for (double fraction : {0.25, 0.5, 0.75}) {
        auto world = makeWorld();
        if (!world) return world.error();
        if (auto id = world.value()->addObject({.asset = a.name}); !id) return id.error();
        std::this_thread::sleep_for(std::chrono::duration<double>(fraction * prepareS));
        destroyMidway.push_back(destroy(world.value()));
        leftS += (1.0 - fraction) * prepareS / 3.0 / s.repeats;
      }
    }
    // Without the database, which an object's placement does not read, the pack's bytes are its objects'.
    const double shareS = packReadS * arrayBytes(a) / total;
    const double placeS = percentile(place, 0.5);
    const double midwayMaxS = *std::max_element(destroyMidway.begin(), destroyMidway.end());
    csv << a.name << "," << a.tetMesh.tets.rows() << "," << 1e3 * shareS << "," << 1e3 * placeS << "," << placeS / shareS << ","
        << 1e3 * prepareS << "," << 1e3 * percentile(destroyPrepared, 0.5) << "," << 1e3 * percentile(destroyMidway, 0.5) << ","
        << 1e3 * midwayMaxS << "," << 1e3 * leftS << "\n";
    std::printf("%-16s %6lld tets: place %7.2f ms, its bytes read %7.2f ms (%.2fx); K factorised in the background %7.1f ms\n",
                a.name.c_str(), static_cast<long long>(a.tetMesh.tets.rows()), 1e3 * placeS, 1e3 * shareS, placeS / shareS,
                1e3 * prepareS);
    std::printf("%-16s              destroyed: prepared %6.1f ms, midway %6.1f ms (max %6.1f; the preparation left %7.1f ms)\n",
                "", 1e3 * percentile(destroyPrepared, 0.5), 1e3 * percentile(destroyMidway, 0.5), 1e3 * midwayMaxS, 1e3 * leftS);
  }
  return Ok{};
}

}  // namespace brittle::bench
