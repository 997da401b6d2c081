// brittle size — the cheapest model that meets a scene's accuracy target (ModelSizing.h): bakes
// the all-maximum pack, measures every mode count of the ladder against the full-FEM reference
// over the scene's impacts, bakes the sized pack and reports what it saves.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>

#include "CliSupport.h"
#include "Commands.h"
#include "brittle/core/AtomicFile.h"
#include "brittle/precompute/BakeManifest.h"
#include "brittle/precompute/ModelSizing.h"
#include "brittle/precompute/RuntimeSettingsFile.h"

namespace brittle::cli {
namespace {

struct SizeOptions {
  std::string manifest, scene, out, sizedManifest, report, keepMaximum, settingsOut;
  std::vector<std::string> elements = {"p1", "p2"};
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
    nlohmann::json elements = nlohmann::json::array();
    for (const auto& e : o.elementTrials) {
      elements.push_back({{"element", elementOrderName(e.elementOrder)}, {"first_frequency_hz", e.firstFrequencyHz},
                          {"frequency_error", e.frequencyError}, {"chosen_modes", e.chosenModes},
                          {"target_met", e.targetMet}, {"impact_values", e.impactValues},
                          {"median_impact_ms", e.medianImpactMs}});
    }
    objects.push_back({{"name", o.object}, {"element", elementOrderName(o.elementOrder)}, {"chosen_modes", o.chosenModes},
                       {"target_met", o.targetMet}, {"worst_error", o.chosenError}, {"impacts", o.impacts},
                       {"reference_s", o.referenceS}, {"trials", trials}, {"element_trials", elements}});
  }
  nlohmann::json debris = nlohmann::json::array();
  for (const auto& d : r.debris) {
    debris.push_back({{"name", d.object}, {"fragments", d.fragments}, {"broke_again", d.brokeAgain},
                      {"smallest_broken_fraction", std::isfinite(d.smallestBrokenFraction) ? nlohmann::json(d.smallestBrokenFraction) : nlohmann::json()},
                      {"debris_volume_fraction", d.debrisVolumeFraction}});
  }
  nlohmann::json search;
  if (r.search) {
    nlohmann::json trials = nlohmann::json::array();
    for (const auto& t : r.search->trials) {
      trials.push_back({{"descriptor", descriptorKindName(t.kind)}, {"precision", t.precision},
                        {"index", describeIndexSettings(t.index)}, {"matched", t.matched},
                        {"median_frequency_error", std::isfinite(t.medianFrequencyError) ? nlohmann::json(t.medianFrequencyError) : nlohmann::json()},
                        {"bytes_compared", t.bytesCompared}, {"median_match_ms", t.medianMatchMs}});
    }
    search = {{"descriptor", descriptorKindName(r.search->kind)}, {"precision", r.search->precision},
              {"index", describeIndexSettings(r.search->index)},
              {"target_met", r.search->targetMet}, {"median_frequency_error", r.search->medianFrequencyError},
              {"median_match_ms", r.search->medianMatchMs}, {"fragments", r.search->fragments}, {"trials", trials},
              // The sized pack's model of the chosen kind is fitted to these when there are ≥ 8 (MatchErrors.h).
              {"match_error_samples", r.search->distanceErrors.size()}};
  }
  nlohmann::json frequencyErrors;
  if (r.frequencyErrors) {
    const FrequencyErrorSizing& f = *r.frequencyErrors;
    nlohmann::json pieces = nlohmann::json::object();
    for (const auto& [name, n] : f.piecesPerObject) pieces[name] = n;
    frequencyErrors = {{"calibrated", f.calibrated}, {"note", f.note}, {"impacts", f.impacts}, {"pieces", pieces},
                       {"bins", {{"ritz", f.ritzBins}, {"checked", f.checkedBins}, {"checked_p2", f.checkedP2Bins}}},
                       {"seconds", f.seconds}};
  }
  return {{"target_peak_stress_error", r.targetError},
          {"target_frequency_error", r.frequencyTargetError},
          {"target_match_frequency_error", r.matchTargetError},
          {"debris", debris},
          {"debris_volume_fraction", r.debrisVolumeFraction},
          {"search", search},
          {"frequency_errors", frequencyErrors},
          {"fragment_sizing_s", r.fragmentSizingS},
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
    std::printf("  %-18s %s, %3d modes, worst error %5.1f %% over %d impacts%s\n", o.object.c_str(),
                elementOrderName(o.elementOrder), o.chosenModes, 100.0 * o.chosenError, o.impacts,
                o.targetMet ? "" : "  (target NOT met: largest count kept)");
    for (const auto& e : o.elementTrials) {
      std::printf("      %s: first mode %.1f Hz (%.2f %% from p2), %d modes, %.3g values read, %.2f ms%s\n",
                  elementOrderName(e.elementOrder), e.firstFrequencyHz, 100.0 * e.frequencyError, e.chosenModes,
                  e.impactValues, e.medianImpactMs, e.targetMet ? "" : "  (a target not met)");
    }
    for (const auto& t : o.trials) {
      std::printf("      %3d modes: %6.1f %%  %7.2f ms\n", t.modes, 100.0 * t.worstError, t.medianImpactMs);
    }
  }
  for (const auto& s : r.skippedObjects) std::printf("  %-18s not used by the scene: not baked\n", s.c_str());
  std::printf("fragments: debris below %.3g of a body's volume (the scene's top-speed impacts, each fragment hit again)\n",
              r.debrisVolumeFraction);
  for (const auto& d : r.debris) {
    std::printf("  %-18s %3d fragments, %3d broke again", d.object.c_str(), d.fragments, d.brokeAgain);
    if (d.brokeAgain > 0) std::printf(", the smallest at %.3g of the body", d.smallestBrokenFraction);
    std::printf(": threshold %.3g\n", d.debrisVolumeFraction);
  }
  if (r.search) {
    std::printf("search: %s, %s, median frequency error %.1f %% (target %.1f %%%s), %.2f ms per match, %d fragments\n",
                descriptorKindName(r.search->kind), describeIndexSettings(r.search->index).c_str(),
                100.0 * r.search->medianFrequencyError, 100.0 * r.matchTargetError,
                r.search->targetMet ? "" : ": NOT met, the most accurate kept", r.search->medianMatchMs, r.search->fragments);
    for (const auto& t : r.search->trials) {
      std::printf("      %-15s %-22s: %6.1f %%  %9.0f bytes compared  %6.2f ms  (%d matched)\n", descriptorKindName(t.kind),
                  describeIndexSettings(t.index).c_str(), 100.0 * t.medianFrequencyError, t.bytesCompared, t.medianMatchMs,
                  t.matched);
    }
  }
  std::printf("database: %s\n", r.refracture ? "kept (fragments break again)" : "dropped (the scene does not refracture)");
  if (r.frequencyErrors) {
    const FrequencyErrorSizing& f = *r.frequencyErrors;
    if (f.calibrated) {
      std::printf("bodies' frequency errors: calibrated on the scene's impacts (%d, %.1f s), pieces:", f.impacts, f.seconds);
      for (const auto& [name, n] : f.piecesPerObject) std::printf(" %s %d", name.c_str(), n);
      std::printf("\n");
    } else {
      std::printf("bodies' frequency errors: NOT calibrated (%s); the pack predicts none\n", f.note.c_str());
    }
  }
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
  cmd->add_option("--scene", o->scene, "Scene requirements (JSON: target, objects, speeds, impactors; see docs/cli.md)")->required();
  cmd->add_option("--out", o->out, "Sized pack (.h5), written atomically")->required();
  cmd->add_option("--target", o->target, "Worst peak-stress error allowed (overrides the scene's)")->check(CLI::Range(1e-6, 0.999));
  cmd->add_option("--ladder", o->settings.modeLadder, "Mode counts tried")->delimiter(',')->capture_default_str()
      ->check(CLI::Range(1, 2000));
  cmd->add_option("--mode-cluster-gap", o->settings.modeClusterGap,
                  "Neighbouring modes closer than this (relative frequency) are one cluster: a count that would split "
                  "one is raised to keep all of it (0: counts as given)")
      ->capture_default_str()->check(CLI::Range(0.0, 0.5));
  cmd->add_option("--points", o->settings.points, "Surface points per impactor and speed")->capture_default_str()
      ->check(CLI::Range(1, 1000));
  cmd->add_option("--reference-steps", o->settings.referenceStepsPerContact, "Newmark steps per contact time")
      ->capture_default_str()->check(CLI::Range(10, 100000));
  cmd->add_option("--repeats", o->settings.timingRepeats, "Impacts timed per count and impact")->capture_default_str()
      ->check(CLI::Range(1, 1000));
  cmd->add_option("--seed", o->settings.seed, "Seed of the impact points")->capture_default_str();
  cmd->add_option("--elements", o->elements,
                  "Element orders tried per object, the cheapest that meets both targets kept (p2 must be among "
                  "several: frequency errors are estimated against it); 'manifest' keeps each object's own")
      ->delimiter(',')->capture_default_str()->check(CLI::IsMember({"p1", "p2", "manifest"}));
  cmd->add_option("--frequency-target", o->settings.frequencyErrorTarget,
                  "First-frequency error allowed when choosing the element order (relative, against p2 on the same tets)")
      ->capture_default_str()->check(CLI::Range(1e-6, 0.999));
  cmd->add_option("--frequency-error-points", o->settings.frequencyErrorPoints,
                  "Surface points per impactor and speed end for the bodies' frequency-error calibration at the scene's "
                  "impacts (0: none; the pack then predicts no body's error)")
      ->capture_default_str()->check(CLI::Range(0, 1000));
  cmd->add_option("--search-precision", o->settings.searchPrecision,
                  "Search precisions tried per descriptor kind: factors on the checks of the index the database stores (a graph's ef, an "
                  "inverted file's lists probed, a kd-forest's checks); 0: the exact search. The cheapest that meets the scene's "
                  "match_frequency_error is stored")
      ->delimiter(',')->capture_default_str()->check(CLI::Range(0.0, 1e6));
  cmd->add_option("--sized-manifest", o->sizedManifest, "Also write the sized pack's bake manifest here");
  cmd->add_option("--report", o->report, "Also write the report as JSON here");
  cmd->add_option("--settings-out", o->settingsOut,
                  "Runtime settings for the scene (descriptor, debris threshold; JSON for play/impact --settings); "
                  "default: the sized pack's name with .settings.json");
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
    for (const std::string& name : o->elements) {
      if (name == "manifest" && o->elements.size() > 1) {
        return reportError(makeError(ErrorCode::InvalidArgument, "--elements: 'manifest' stands alone"));
      }
      if (name != "manifest") o->settings.elementOrders.push_back(*parseElementOrder(name));
    }
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
    FractureSettings chosen;
    chosen.debrisVolumeFraction = report.value().debrisVolumeFraction;
    if (report.value().search) chosen.descriptor = report.value().search->kind;
    const std::string settingsPath =
        o->settingsOut.empty() ? std::filesystem::path(o->out).replace_extension(".settings.json").string() : o->settingsOut;
    if (Status st = writeFileAtomically(settingsPath, runtimeSettingsJson(chosen)); !st) return reportError(st.error());
    if (!o->sizedManifest.empty()) {
      if (Status st = writeSizedManifest(o->manifest, report.value(), o->sizedManifest); !st) return reportError(st.error());
    }
    if (o->json) {
      std::cout << json.dump(2) << "\n";
    } else {
      printReport(report.value());
      std::cout << "\nwrote " << o->out << " and " << settingsPath << "\n";
    }
    return kExitOk;
  };
}

}  // namespace brittle::cli
