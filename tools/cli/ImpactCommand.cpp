// brittle impact — load a pack, place one object, report one impact, print and write the fragments.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>

#include "../bench/BenchSupport.h"
#include "CliSupport.h"
#include "Commands.h"
#include "brittle/database/Pack.h"
#include "brittle/precompute/MaterialLibrary.h"
#include "brittle/precompute/MeshIO.h"
#include "brittle/runtime/Fingerprint.h"
#include "brittle/runtime/World.h"

namespace brittle::cli {
namespace {

struct ImpactOptions {
  std::string pack, object, impactorMaterial = "steel", out, descriptor = "moment";
  std::vector<double> point, normal;
  double speed = 0.0, impactorMass = 0.1, impactorRadius = 0.02, impulse = 0.0, bodyRadius = 0.0;
  uint64_t seed = 1;
  int modes = 0, repeat = 1;
  int exactMaxTets = FractureSettings{}.exactModesMaxTets;
  int exactMaxDof = FractureSettings{}.exactModesMaxDof;
  double matchErrorTarget = FractureSettings{}.matchErrorTarget;
  int polynomialDegree = FractureSettings{}.polynomialModeDegree;
  int meshRatioMaxDof = FractureSettings{}.meshRatioMaxDof;
  std::string meshRatioElement = elementOrderName(FractureSettings{}.meshRatioElement);
  std::string runtimeSettings;
  double crackBlend = CrackSettings{}.directionBlend, crackNoise = CrackSettings{}.noiseRad;
  double contactSpread = FractureSettings{}.contactSpreadFraction;
  double debris = 0.01, propagationRatio = CrackSettings{}.propagationStressRatio;
  int pulseSteps = FractureSettings{}.pulseSteps, ringDownSteps = FractureSettings{}.ringDownSteps;
  bool noCorrection = false;
  int maxCracks = CrackSettings{}.maxCracks, minFragmentNodes = CrackSettings{}.minFragmentNodes;
  bool noPrune = false, noMatch = false, json = false, reportUncorrected = false, endAtCracks = false;
};

nlohmann::json vec(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

}  // namespace

Runner addImpactCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("impact", "Break an object of a pack with one impact; print and write the fragments");
  auto o = std::make_shared<ImpactOptions>();
  cmd->add_option("pack", o->pack, "Pack (.h5)")->required();
  cmd->add_option("--object", o->object, "Object name in the pack")->required();
  cmd->add_option("--point", o->point, "Contact point x,y,z in the object's frame (m)")->delimiter(',')->expected(3)->required();
  cmd->add_option("--normal", o->normal, "Outward surface normal at the point x,y,z")->delimiter(',')->expected(3)->required();
  cmd->add_option("--speed", o->speed, "Normal approach speed (m/s)")->required();
  cmd->add_option("--impactor-mass", o->impactorMass, "Impactor mass (kg); inf for the ground")->capture_default_str();
  cmd->add_option("--impactor-radius", o->impactorRadius, "Impactor radius (m); inf for flat")->capture_default_str();
  cmd->add_option("--impactor-material", o->impactorMaterial, "Impactor material: preset name or JSON file")->capture_default_str();
  cmd->add_option("--impulse", o->impulse, "Impulse the host resolved (N s); default (1 + e) m* v")->capture_default_str();
  cmd->add_option("--body-radius", o->bodyRadius, "Local radius of curvature (m); 0: estimated from the surface")->capture_default_str();
  cmd->add_option("--modes", o->modes, "Modes used (0: all stored)")->capture_default_str()->check(CLI::NonNegativeNumber);
  cmd->add_option("--settings", o->runtimeSettings, "Runtime settings (JSON, as brittle size writes them); flags given here win");
  cmd->add_option("--exact-max-tets", o->exactMaxTets,
                  "Fragments of at most this many tets get their own modal analysis instead of a database match (0: never)")
      ->capture_default_str()->check(CLI::NonNegativeNumber);
  cmd->add_option("--exact-max-dof", o->exactMaxDof,
                  "... and whose own model has at most this many degrees of freedom (0: no limit)")
      ->capture_default_str()->check(CLI::NonNegativeNumber);
  cmd->add_option("--match-error-target", o->matchErrorTarget,
                  "A fragment small enough for the exact path takes its database match instead when the match's "
                  "predicted frequency error (90th percentile) is within this (0: size alone decides)")
      ->capture_default_str()->check(CLI::NonNegativeNumber);
  cmd->add_option("--polynomial-degree", o->polynomialDegree,
                  "A matched fragment's body rings at the fragment's own frequencies, by Rayleigh–Ritz over polynomial "
                  "fields of this degree from its volume moments (0: the database entry's own modes)")
      ->capture_default_str()->check(CLI::Range(0, 5));
  cmd->add_option("--mesh-ratio-max-dof", o->meshRatioMaxDof,
                  "... and the lowest three of those are corrected by the fragment's own linear-tet mesh when it has at most "
                  "this many degrees of freedom: finds the hinges and flaps no polynomial follows, ~6 ms a piece on the workers (0: never)")
      ->capture_default_str()->check(CLI::NonNegativeNumber);
  cmd->add_option("--mesh-ratio-element", o->meshRatioElement,
                  "... in linear (p1) or quadratic (p2) tets: p2 removes the linear tets' locking from the check, ~10x the cost")
      ->capture_default_str()->check(CLI::IsMember({"p1", "p2"}));
  cmd->add_option("--contact-spread", o->contactSpread,
                  "Spread the contact load over at least this fraction of the object's bounding-box diagonal, or the "
                  "object's own where its pack gives a larger one (0: the mesh's nearest ring only; see docs/realtime.md, \"Contact loads\")")
      ->capture_default_str()->check(CLI::Range(0.0, 0.99));
  cmd->add_option("--debris", o->debris, "Fragments below this volume fraction are rigid debris")->capture_default_str()->check(CLI::Range(0.0, 0.99));
  cmd->add_option("--descriptor", o->descriptor, "Descriptor used to match fragments")
      ->check(CLI::IsMember({"moment", "voxel", "voxel-improved"}))->capture_default_str();
  cmd->add_option("--propagation-ratio", o->propagationRatio, "A crack advances where the normal stress ≥ ratio × σ_t")->capture_default_str();
  cmd->add_option("--max-cracks", o->maxCracks, "Cracks started at most")->capture_default_str()->check(CLI::NonNegativeNumber);
  cmd->add_option("--min-fragment-nodes", o->minFragmentNodes, "Smaller fragments are merged into a neighbour")->capture_default_str()->check(CLI::NonNegativeNumber);
  cmd->add_option("--crack-blend", o->crackBlend, "Weight of a crack's starting plane against the local principal direction")->capture_default_str()->check(CLI::Range(0.0, 1.0));
  cmd->add_option("--crack-noise", o->crackNoise, "Seeded turn of the crack plane per element (rad)")->capture_default_str()->check(CLI::NonNegativeNumber);
  cmd->add_flag("--end-at-cracks", o->endAtCracks,
                "A crack ends where it meets another crack's surface (a T-junction) instead of crossing it");
  cmd->add_option("--pulse-steps", o->pulseSteps, "Stress-evaluation instants during the contact")->capture_default_str()->check(CLI::Range(2, 100000));
  cmd->add_option("--ring-down-steps", o->ringDownSteps, "Instants in the window after the contact")->capture_default_str()->check(CLI::Range(0, 100000));
  cmd->add_flag("--no-static-correction", o->noCorrection, "Truncated modes only (no mode-acceleration correction)");
  cmd->add_flag("--report-uncorrected", o->reportUncorrected,
               "Also scan the truncated modes alone, for peak_without_correction_pa (a second scan, which "
               "prunes poorly: ~50 ms on the default plate)");
  cmd->add_flag("--no-prune", o->noPrune, "Evaluate every element stress (the reference for pruning)");
  cmd->add_flag("--no-match", o->noMatch, "Do not match fragments to the database");
  cmd->add_option("--seed", o->seed, "Seed of the crack noise")->capture_default_str();
  cmd->add_option("--out", o->out, "Directory for the fragment meshes (fragment-NN.off)");
  cmd->add_flag("--json", o->json, "Print the result as JSON");
  cmd->add_option("--repeat", o->repeat,
                  "Repeat the impact on fresh instances of the object in the same world and report the "
                  "median stage times of the repeats (warm: no first-impact factorisation, each repeat after the "
                  "world's background work); the peak must "
                  "be the first's, the cracks follow each impact's own seed")
      ->capture_default_str()->check(CLI::Range(1, 10000));

  return [o, cmd]() -> int {
    auto pack = readPack(o->pack, EntryReading::OnDemand);  // a World reads entries as it matches them
    if (!pack) return reportError(pack.error());
    auto impactor = resolveMaterial(o->impactorMaterial);
    if (!impactor) return reportError(impactor.error());
    WorldSettings settings;
    settings.seed = o->seed;
    settings.fracture.modeCount = o->modes;
    settings.fracture.pruneStresses = !o->noPrune;
    settings.fracture.pulseSteps = o->pulseSteps;
    settings.fracture.ringDownSteps = o->ringDownSteps;
    settings.fracture.staticCorrection = !o->noCorrection;
    settings.fracture.reportUncorrectedPeak = o->reportUncorrected;
    settings.fracture.matchFragments = !o->noMatch;
    settings.fracture.debrisVolumeFraction = o->debris;
    settings.fracture.contactSpreadFraction = o->contactSpread;
    settings.fracture.exactModesMaxTets = o->exactMaxTets;
    settings.fracture.exactModesMaxDof = o->exactMaxDof;
    settings.fracture.matchErrorTarget = o->matchErrorTarget;
    settings.fracture.polynomialModeDegree = o->polynomialDegree;
    settings.fracture.meshRatioMaxDof = o->meshRatioMaxDof;
    settings.fracture.meshRatioElement = *parseElementOrder(o->meshRatioElement);
    settings.fracture.descriptor = parseDescriptorKind(o->descriptor).value();
    settings.fracture.crack.endAtCracks = o->endAtCracks;
    if (!o->runtimeSettings.empty()) {
      if (Status st = applyRuntimeSettingsFile(o->runtimeSettings, *cmd, settings.fracture); !st) return reportError(st.error());
    }
    settings.fracture.crack.propagationStressRatio = o->propagationRatio;
    settings.fracture.crack.maxCracks = o->maxCracks;
    settings.fracture.crack.directionBlend = o->crackBlend;
    settings.fracture.crack.noiseRad = o->crackNoise;
    settings.fracture.crack.minFragmentNodes = o->minFragmentNodes;
    auto world = World::create(std::move(pack).value(), settings);
    if (!world) return reportError(world.error());
    auto id = world.value().addObject({.asset = o->object});
    if (!id) return reportError(id.error());
    // The object's tet mesh, for where the peak is: copied now, as a broken object is removed.
    auto asset = world.value().objectAsset(id.value());
    if (!asset) return reportError(asset.error());
    const TetMesh tets = asset.value()->tetMesh;
    ImpactDesc d;
    d.object = id.value();
    d.pointWorld = Eigen::Vector3d(o->point[0], o->point[1], o->point[2]);
    d.normalWorld = Eigen::Vector3d(o->normal[0], o->normal[1], o->normal[2]);
    if (d.normalWorld.norm() > 0.0) d.normalWorld.normalize();
    d.speedMps = o->speed;
    d.impactorMassKg = o->impactorMass;
    d.impactorRadiusM = o->impactorRadius;
    d.impactorYoungsModulusPa = impactor.value().youngsModulusPa;
    d.impactorPoissonRatio = impactor.value().poissonRatio;
    d.impulseNs = o->impulse;
    d.bodyRadiusM = o->bodyRadius;
    auto result = world.value().impact(d);
    if (!result) return reportError(result.error());
    const ImpactResult& r = result.value();
    // Repeats: the same impact on a fresh instance (the body, its factorised K and bounds are the
    // pack object's, made once); their median stage times are the warm cost of the impact. The
    // World gives each impact its own crack seed, so the cracks differ; the peak must not.
    std::vector<StageTimes> warm;
    for (int i = 1; i < o->repeat; ++i) {
      // The last impact's new bodies are made on the World's workers: let them finish first, so
      // that the repeat has the cores to itself.
      if (Status st = world.value().waitUntilPrepared(); !st) return reportError(st.error());
      auto again = world.value().addObject({.asset = o->object});
      if (!again) return reportError(again.error());
      d.object = again.value();
      auto repeated = world.value().impact(d);
      if (!repeated) return reportError(repeated.error());
      if (repeated.value().peakPrincipalStressPa != r.peakPrincipalStressPa || repeated.value().peakElement != r.peakElement ||
          repeated.value().peakTimeS != r.peakTimeS) {
        std::cerr << "error: impact --repeat: repeat " << i << " found another peak than the first impact\n";
        return kExitInternal;
      }
      warm.push_back(repeated.value().times);
      // Leave the world as it was: the repeat's object, or its fragments (maxObjects).
      if (!repeated.value().broken) {
        if (Status st = world.value().removeObject(d.object); !st) return reportError(st.error());
      }
      for (const FragmentResult& f : repeated.value().fragments) {
        if (!f.object.valid()) continue;
        if (Status st = world.value().removeObject(f.object); !st) return reportError(st.error());
      }
    }
    auto warmMedian = [&](double StageTimes::*stage) {
      std::vector<double> v;
      for (const StageTimes& t : warm) v.push_back(t.*stage);
      return bench::percentile(v, 0.5);
    };
    auto warmTotal = [&] {
      std::vector<double> v;
      for (const StageTimes& t : warm) v.push_back(t.totalS());
      return bench::percentile(v, 0.5);
    };

    if (!o->out.empty()) {
      std::error_code ec;
      std::filesystem::create_directories(o->out, ec);
      for (size_t i = 0; i < r.fragments.size(); ++i) {
        char name[48];
        std::snprintf(name, sizeof name, "fragment-%02zu.off", i);
        if (Status st = writeSurfaceMesh(r.fragments[i].surface, std::filesystem::path(o->out) / name); !st) {
          return reportError(st.error());
        }
      }
    }
    nlohmann::json doc;
    doc["object"] = o->object;
    doc["broken"] = r.broken;
    doc["contact"] = {{"effective_mass_kg", r.contact.effectiveMassKg}, {"effective_radius_m", r.contact.effectiveRadiusM},
                      {"effective_modulus_pa", r.contact.effectiveModulusPa}, {"duration_s", r.contact.durationS},
                      {"hertz_peak_force_n", r.contact.hertzPeakForceN}, {"pulse_peak_force_n", r.contact.pulseAmplitudeN},
                      {"impulse_ns", r.contact.impulseNs}, {"patch_radius_m", r.contact.patchRadiusM},
                      {"load_radius_m", r.loadRadiusM},
                      {"body_radius_m", std::isfinite(r.bodyRadiusM) ? nlohmann::json(r.bodyRadiusM) : nlohmann::json("inf")}};
    doc["peak_principal_stress_pa"] = r.peakPrincipalStressPa;
    doc["peak_without_correction_pa"] = r.peakWithoutCorrectionPa;
    doc["peak_time_s"] = r.peakTimeS;
    doc["peak_element"] = r.peakElement;
    if (r.peakElement >= 0 && r.peakElement < tets.tets.rows()) {
      Eigen::Vector3d c = Eigen::Vector3d::Zero();
      for (int k = 0; k < 4; ++k) c += 0.25 * tets.nodes.row(tets.tets(r.peakElement, k)).transpose();
      doc["peak_element_centroid_m"] = {c.x(), c.y(), c.z()};
    } else {
      doc["peak_element_centroid_m"] = nullptr;
    }
    doc["modes_used"] = r.modesUsed;
    doc["stress_evaluations"] = r.stressEvaluations;
    doc["cracks"] = {{"count", r.fracture.crackCount}, {"cut_elements", r.fracture.cutElements.size()},
                     {"area_m2", r.fracture.crackAreaM2}, {"energy_budget_j", r.fracture.energyBudgetJ},
                     {"energy_spent_j", r.fracture.energySpentJ}, {"arrested_by_energy", r.fracture.arrestedByEnergy}};
    doc["fragments"] = nlohmann::json::array();
    // A new object's first frequency (Hz): the exact path's own, or a matched body's, which rings at
    // the fragment's own frequencies with polynomialModeDegree > 0. Asking for it makes the body
    // now (it is made on the workers otherwise), after the timed impact. NaN without an object.
    auto firstHz = [&](const FragmentResult& f) {
      if (!f.object.valid()) return std::numeric_limits<double>::quiet_NaN();
      auto made = world.value().objectAsset(f.object);
      return made && made.value()->modal.frequenciesHz.size() > 0 ? made.value()->modal.frequenciesHz[0]
                                                                  : std::numeric_limits<double>::quiet_NaN();
    };
    // Where a new object's frequencies come from and their predicted error (World::frequencyError;
    // the pack's calibration, brittle calibrate-errors). Asks for the body as firstHz does.
    auto bodyError = [&](const FragmentResult& f) {
      if (!f.object.valid()) return FrequencyErrorPrediction{};
      auto p = world.value().frequencyError(f.object);
      return p ? p.value() : FrequencyErrorPrediction{};  // a body that failed: no prediction
    };
    std::map<std::string, int> paths;
    for (FragmentPath p : {FragmentPath::Debris, FragmentPath::ExactModes, FragmentPath::Matched, FragmentPath::SurfaceOnly})
      paths[std::string(fragmentPathName(p))] = 0;
    for (const FragmentResult& f : r.fragments) {
      ++paths[std::string(fragmentPathName(f.path))];
      auto orNull = [](double x) { return std::isnan(x) ? nlohmann::json() : nlohmann::json(x); };
      doc["fragments"].push_back({{"volume_m3", f.massProperties.volumeM3}, {"mass_kg", f.massProperties.massKg},
                                  {"center_of_mass_m", vec(f.massProperties.centerOfMassM)},
                                  {"triangles", f.surface.faces.rows()}, {"debris", f.debris},
                                  {"matched_entry", f.matchedEntry}, {"match_distance", f.matchDistance},
                                  {"exact_modes", f.exactModes}, {"path", fragmentPathName(f.path)},
                                  {"predicted_match_error", orNull(f.predictedMatchError)},
                                  {"predicted_match_error_p90", orNull(f.predictedMatchErrorP90)},
                                  {"frequency_hz", orNull(firstHz(f))}, {"reason", f.reason}});
      if (f.object.valid()) {
        const FrequencyErrorPrediction b = bodyError(f);
        doc["fragments"].back()["frequency_source"] = frequencySourceName(b.source);
        doc["fragments"].back()["frequency_indicator"] = orNull(b.indicator);
        doc["fragments"].back()["predicted_frequency_error"] = orNull(b.median);
        doc["fragments"].back()["predicted_frequency_error_p90"] = orNull(b.p90);
      }
    }
    doc["fragment_paths"] = paths;
    doc["fingerprint"] = fingerprintHex(fingerprint(r));  // every computed value; times aside
    doc["times_s"] = {{"contact", r.times.contactS}, {"prepare", r.times.prepareS}, {"modal", r.times.modalS}, {"stress", r.times.stressS},
                      {"propagation", r.times.propagationS}, {"surfaces", r.times.surfacesS},
                      {"matching", r.times.matchingS}, {"total", r.times.totalS()}};
    if (!warm.empty()) {
      doc["warm_times_s"] = {{"repeats", warm.size()}, {"contact", warmMedian(&StageTimes::contactS)},
                             {"modal", warmMedian(&StageTimes::modalS)}, {"stress", warmMedian(&StageTimes::stressS)},
                             {"propagation", warmMedian(&StageTimes::propagationS)},
                             {"surfaces", warmMedian(&StageTimes::surfacesS)},
                             {"matching", warmMedian(&StageTimes::matchingS)}, {"total", warmTotal()}};
    }
    if (o->json) {
      std::cout << doc.dump(2) << "\n";
      return kExitOk;
    }
    std::cout << std::setprecision(4) << o->object << " hit at " << o->speed << " m/s: contact " << 1e6 * r.contact.durationS
              << " us, peak force " << r.contact.pulseAmplitudeN << " N; peak principal stress "
              << r.peakPrincipalStressPa / 1e6 << " MPa (" << r.modesUsed << " modes)\n";
    if (!r.broken) {
      std::cout << "  not broken" << (r.fracture.crackCount > 0 ? " (cracked, not separated)" : "") << "\n";
    } else {
      std::cout << "  " << r.fracture.crackCount << " cracks, " << r.fracture.cutElements.size() << " elements cut, "
                << r.fracture.crackAreaM2 * 1e4 << " cm2, energy " << r.fracture.energySpentJ << " / "
                << r.fracture.energyBudgetJ << " J\n";
      for (size_t i = 0; i < r.fragments.size(); ++i) {
        const FragmentResult& f = r.fragments[i];
        std::cout << "  fragment " << std::setw(2) << i << "  " << std::setw(10) << f.massProperties.volumeM3 * 1e6
                  << " cm3  " << std::setw(10) << f.massProperties.massKg * 1e3 << " g  ";
        if (f.debris) std::cout << "debris";
        else if (f.exactModes) std::cout << "own modes (exact path), f1 " << firstHz(f) << " Hz";
        else if (f.matchedEntry >= 0) {
          std::cout << "entry " << f.matchedEntry << " (distance " << f.matchDistance;
          if (!std::isnan(f.predictedMatchErrorP90))
            std::cout << "; the entry's frequencies predicted " << std::lround(100 * f.predictedMatchError) << " % off, p90 "
                      << std::lround(100 * f.predictedMatchErrorP90) << " %";
          std::cout << "), f1 " << firstHz(f) << " Hz";
          const FrequencyErrorPrediction b = bodyError(f);
          const char* source = "unknown (the body failed)";
          switch (b.source) {
            case FrequencySource::Entry: source = "the entry's"; break;
            case FrequencySource::Ritz: source = "the fragment's own, polynomial Ritz"; break;
            case FrequencySource::Checked: source = "the fragment's own, checked on its mesh"; break;
            case FrequencySource::CheckedP2: source = "the fragment's own, checked on its mesh in P2 tets"; break;
            case FrequencySource::Own: break;  // a matched body is never its own: bodyError's fallback
          }
          std::cout << " (" << source;
          if (!std::isnan(b.p90) && b.source != FrequencySource::Entry)
            std::cout << "; predicted error " << std::lround(100 * b.median) << " %, p90 " << std::lround(100 * b.p90) << " %";
          std::cout << ")";
        }
        else std::cout << "unmatched: " << f.reason;
        std::cout << "\n";
      }
    }
    std::cout << "  times (ms): contact " << 1e3 * r.times.contactS << ", first-impact factorisation "
              << 1e3 * r.times.prepareS << ", modal " << 1e3 * r.times.modalS << ", stress "
              << 1e3 * r.times.stressS << ", propagation " << 1e3 * r.times.propagationS << ", surfaces "
              << 1e3 * r.times.surfacesS << ", matching " << 1e3 * r.times.matchingS << ", total "
              << 1e3 * r.times.totalS() << "\n";
    if (!warm.empty()) {
      std::cout << "  warm times (ms, median of " << warm.size() << " repeats): contact " << 1e3 * warmMedian(&StageTimes::contactS)
                << ", modal " << 1e3 * warmMedian(&StageTimes::modalS) << ", stress " << 1e3 * warmMedian(&StageTimes::stressS)
                << ", propagation " << 1e3 * warmMedian(&StageTimes::propagationS) << ", surfaces "
                << 1e3 * warmMedian(&StageTimes::surfacesS) << ", matching " << 1e3 * warmMedian(&StageTimes::matchingS)
                << ", total " << 1e3 * warmTotal() << " (the same peak; cracks from each impact's own seed)\n";
    }
    std::cout << "  fingerprint " << fingerprintHex(fingerprint(r)) << " (every computed value; equal means bit-identical)\n";
    return kExitOk;
  };
}

}  // namespace brittle::cli
