// brittle size — the cheapest model that meets a scene's accuracy target (ModelSizing.h): bakes
// the all-maximum pack, measures every mode count of the ladder against the full-FEM reference
// over the scene's impacts, bakes the sized pack and reports what it saves.
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>

#include "CliSupport.h"
#include "Commands.h"
#include "brittle/precompute/AtomicFile.h"
#include "brittle/precompute/ModelSizing.h"

namespace brittle::cli {
namespace {

struct SizeOptions {
  std::string manifest, scene, out, sizedManifest, report, keepMaximum;
  double target = 0.0;
  ModelSizingSettings settings;
  bool quiet = false, json = false;
};

nlohmann::json reportJson(const SceneSizingReport& r) {
  nlohmann::json objects = nlohmann::json::array();
  for (const auto& o : r.objects) {
    nlohmann::json trials = nlohmann::json::array();
    for (const auto& t : o.trials) {
      trials.push_back({{"modes", t.modes}, {"worst_error", t.worstError}, {"median_impact_ms", t.medianImpactMs}});
    }
    objects.push_back({{"name", o.object}, {"chosen_modes", o.chosenModes}, {"target_met", o.targetMet},
                       {"worst_error", o.chosenError}, {"impacts", o.impacts}, {"reference_s", o.referenceS},
                       {"trials", trials}});
  }
  return {{"target_peak_stress_error", r.targetError},
          {"refracture", r.refracture},
          {"all_met", r.allMet()},
          {"objects", objects},
          {"skipped_objects", r.skippedObjects},
          {"maximum", {{"bake_s", r.maximumBakeS}, {"pack_bytes", r.maximumPackBytes}, {"impact_ms", r.maximumImpactMs}}},
          {"sized", {{"bake_s", r.sizedBakeS}, {"pack_bytes", r.sizedPackBytes}, {"impact_ms", r.sizedImpactMs}}},
          {"database_bake_s", r.databaseBakeS}};
}

void printReport(const SceneSizingReport& r) {
  std::printf("target: worst peak-stress error <= %.1f %% against the full-FEM reference\n", 100.0 * r.targetError);
  for (const auto& o : r.objects) {
    std::printf("  %-18s %3d modes, worst error %5.1f %% over %d impacts%s\n", o.object.c_str(), o.chosenModes,
                100.0 * o.chosenError, o.impacts, o.targetMet ? "" : "  (target NOT met: largest count kept)");
    for (const auto& t : o.trials) {
      std::printf("      %3d modes: %6.1f %%  %7.2f ms\n", t.modes, 100.0 * t.worstError, t.medianImpactMs);
    }
  }
  for (const auto& s : r.skippedObjects) std::printf("  %-18s not used by the scene: not baked\n", s.c_str());
  std::printf("database: %s\n", r.refracture ? "kept (fragments break again)" : "dropped (the scene does not refracture)");
  auto ratio = [](double a, double b) { return b > 0.0 ? a / b : 0.0; };
  std::printf("%-12s %14s %14s %8s\n", "", "all-maximum", "sized", "ratio");
  std::printf("%-12s %12.1f s %12.1f s %8.2f\n", "bake", r.maximumBakeS, r.sizedBakeS, ratio(r.sizedBakeS, r.maximumBakeS));
  std::printf("%-12s %11.2f MB %11.2f MB %8.2f\n", "pack", 1e-6 * static_cast<double>(r.maximumPackBytes),
              1e-6 * static_cast<double>(r.sizedPackBytes),
              ratio(static_cast<double>(r.sizedPackBytes), static_cast<double>(r.maximumPackBytes)));
  std::printf("%-12s %11.2f ms %11.2f ms %8.2f\n", "impacts", r.maximumImpactMs, r.sizedImpactMs,
              ratio(r.sizedImpactMs, r.maximumImpactMs));
}

}  // namespace

Runner addSizeCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "size", "Bake the cheapest pack that meets a scene's accuracy target: modes per object from the full-FEM "
              "reference, only the objects the scene uses, the database only if it refractures");
  auto o = std::make_shared<SizeOptions>();
  cmd->add_option("--manifest", o->manifest, "Bake manifest (JSON, as for bake --manifest)")->required();
  cmd->add_option("--scene", o->scene, "Scene requirements (JSON: target, objects, speeds, impactors; see README)")->required();
  cmd->add_option("--out", o->out, "Sized pack (.h5), written atomically")->required();
  cmd->add_option("--target", o->target, "Worst peak-stress error allowed (overrides the scene's)")->check(CLI::Range(1e-6, 0.999));
  cmd->add_option("--ladder", o->settings.modeLadder, "Mode counts tried")->delimiter(',')->capture_default_str()
      ->check(CLI::Range(1, 2000));
  cmd->add_option("--points", o->settings.points, "Surface points per impactor and speed")->capture_default_str()
      ->check(CLI::Range(1, 1000));
  cmd->add_option("--reference-steps", o->settings.referenceStepsPerContact, "Newmark steps per contact time")
      ->capture_default_str()->check(CLI::Range(10, 100000));
  cmd->add_option("--repeats", o->settings.timingRepeats, "Impacts timed per count and impact")->capture_default_str()
      ->check(CLI::Range(1, 1000));
  cmd->add_option("--seed", o->settings.seed, "Seed of the impact points")->capture_default_str();
  cmd->add_option("--sized-manifest", o->sizedManifest, "Also write the sized pack's bake manifest here");
  cmd->add_option("--report", o->report, "Also write the report as JSON here");
  cmd->add_option("--keep-maximum", o->keepMaximum, "Keep the all-maximum pack here (default: measured, then removed)");
  cmd->add_flag("--quiet", o->quiet, "No progress display");
  cmd->add_flag("--json", o->json, "Print the report as JSON");
  return [o]() -> int {
    auto objects = loadBakeManifest(o->manifest);
    if (!objects) return reportError(objects.error());
    auto database = loadDatabaseManifest(o->manifest);
    if (!database) return reportError(database.error());
    auto requirements = loadSceneRequirements(o->scene);
    if (!requirements) return reportError(requirements.error());
    if (o->target > 0.0) requirements.value().peakStressError = o->target;
    Result<SceneSizingReport> report = [&] {
      TerminalProgress progress(o->quiet);
      return sizeScene(objects.value(), database.value(), requirements.value(), {o->out, o->keepMaximum}, o->settings,
                       &progress);
    }();
    if (!report) return reportError(report.error());
    const nlohmann::json json = reportJson(report.value());
    if (!o->report.empty()) {
      if (Status st = writeFileAtomically(o->report, json.dump(2) + "\n"); !st) return reportError(st.error());
    }
    if (!o->sizedManifest.empty()) {
      if (Status st = writeSizedManifest(o->manifest, report.value(), o->sizedManifest); !st) return reportError(st.error());
    }
    if (o->json) {
      std::cout << json.dump(2) << "\n";
    } else {
      printReport(report.value());
      std::cout << "\nwrote " << o->out << "\n";
    }
    return kExitOk;
  };
}

}  // namespace brittle::cli
