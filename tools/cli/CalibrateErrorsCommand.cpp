// brittle calibrate-errors — how far a matched body's own frequencies are from its fragment's,
// calibrated on runtime fragments of the pack's objects, stored in the pack's database
// (FrequencyErrorCalibration.h; World::frequencyError and `brittle impact` report it).
#include <cmath>
#include <fstream>
#include <iostream>

#include "CliSupport.h"
#include "Commands.h"
#include "brittle/database/Pack.h"
#include "brittle/precompute/FrequencyErrorCalibration.h"
#include "brittle/precompute/SceneRequirements.h"

namespace brittle::cli {
namespace {

struct CalibrateErrorsOptions {
  std::string pack, out, csv, scene;
  FrequencyErrorCalibrationSettings settings;
  bool noP2 = false, json = false, quiet = false;
};

void printModel(const char* what, const MatchErrorModel& m) {
  std::cout << what << ": " << m.samples << " fragments in " << m.distance.size() << " bins\n";
  for (size_t b = 0; b < m.distance.size(); ++b) {
    std::printf("  indicator <= %-9.4g median %6.1f %%  p90 %6.1f %%\n", m.distance[b], 100.0 * m.medianError[b], 100.0 * m.p90Error[b]);
  }
}

}  // namespace

Runner addCalibrateErrorsCommand(CLI::App& app) {
  auto o = std::make_shared<CalibrateErrorsOptions>();
  auto* cmd = app.add_subcommand(
      "calibrate-errors",
      "Calibrate the predicted error of matched bodies' own frequencies (Ritz values, and those checked by the fragment's mesh) "
      "on runtime fragments of the pack's objects, against their solids in quadratic tets, and store it in the pack");
  cmd->add_option("pack", o->pack, "Pack with a fragment database (.h5)")->required()->check(CLI::ExistingFile);
  cmd->add_option("--out", o->out, "Output pack, written atomically (default: the input pack, replaced)");
  cmd->add_option("--objects", o->settings.objects, "Break only these pack objects (default: all)")->delimiter(',');
  cmd->add_option("--speeds", o->settings.speedsMps, "Impact speeds (m/s)")->delimiter(',')->capture_default_str();
  cmd->add_option("--seeds", o->settings.seeds, "Impacts per object and speed (with --scene: surface points per impactor and speed end)")
      ->capture_default_str()->check(CLI::Range(1, 1000));
  cmd->add_option("--scene", o->scene,
                  "Break the objects with a scene's impacts instead (a requirements file, as for size: its objects, impactors and "
                  "both ends of each speed range; --speeds is then not used)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--first-seed", o->settings.firstSeed,
                  "Seed of the first impact (default 1001: bench exact-modes' seeds 1.. stay held back)")
      ->capture_default_str();
  cmd->add_option("--max-fragments", o->settings.maxFragmentsPerImpact, "Fragments per impact, spread over their sizes")
      ->capture_default_str()
      ->check(CLI::Range(1, 1000));
  cmd->add_option("--degree", o->settings.degree, "The runtime's polynomial mode degree")->capture_default_str()->check(CLI::Range(3, 5));
  cmd->add_flag("--no-p2", o->noP2, "Calibrate the checks in linear tets only (the quadratic ones take ~80 ms a piece)");
  cmd->add_option("--check-max-dof", o->settings.checkMaxDof, "Pieces checked up to this many DOF")->capture_default_str();
  cmd->add_option("--reference-max-tets", o->settings.referenceMaxTets, "No truth (the piece skipped) above this many tets")
      ->capture_default_str();
  cmd->add_option("--bins", o->settings.bins.bins, "Bins of each model, at most")->capture_default_str()->check(CLI::Range(1, 64));
  cmd->add_option("--csv", o->csv, "Write every fragment's indicators and errors here");
  cmd->add_flag("--quiet", o->quiet, "No progress display");
  cmd->add_flag("--json", o->json, "Print the inspection of the new pack as JSON");
  return [o]() -> int {
    auto pack = readPack(o->pack);
    if (!pack) return reportError(pack.error());
    if (pack.value().database.empty() || !pack.value().database.hasPhysics()) {
      return reportError(makeError(ErrorCode::InvalidArgument, "calibrate-errors: the pack has no fragment database with physics"));
    }
    o->settings.p2Checks = !o->noP2;
    if (!o->scene.empty()) {
      auto scene = loadSceneRequirements(o->scene);
      if (!scene) return reportError(scene.error());
      o->settings.scene = std::move(scene.value().objects);
    }
    Result<FrequencyErrorCalibration> calibrated = makeError(ErrorCode::Cancelled, "not run");
    {
      TerminalProgress progress(o->quiet);
      calibrated = calibrateFrequencyErrors(pack.value(), o->settings, &progress);
    }
    if (!calibrated) return reportError(calibrated.error());
    const FrequencyErrorCalibration& c = calibrated.value();
    if (!o->csv.empty()) {
      std::ofstream csv(o->csv);
      csv << "object,speed_mps,seed,fragment,check_dof,truth_f1_hz,ritz_indicator,ritz_freq_err,check_indicator,check_freq_err,"
             "check_p2_indicator,check_p2_freq_err\n";
      csv.precision(9);
      for (const FrequencyErrorSample& x : c.samples) {
        csv << x.object << "," << x.speedMps << "," << x.seed << "," << x.fragment << "," << x.checkDof << "," << x.truthF1Hz << ","
            << x.ritzIndicator << "," << x.ritzError << "," << x.checkIndicator << "," << x.checkError << "," << x.checkP2Indicator
            << "," << x.checkP2Error << "\n";
      }
      if (!csv) return reportError(makeError(ErrorCode::PackIoError, "cannot write " + o->csv));
    }
    if (!o->json) {
      // Pieces per object: an object no impact broke into a measured piece is not in the models.
      std::cout << "pieces per object:";
      for (const auto& [name, n] : c.piecesPerObject)
        std::cout << " " << name << " " << n << (n == 0 ? " (none broke into a piece with a truth: faster impacts?)" : "");
      std::cout << " (" << c.impacts << " impacts)\n";
      printModel("Ritz values against their convergence from two degrees below", c.models.ritz);
      if (!c.models.checked.empty()) printModel("checked values (linear tets) against the mesh's gain", c.models.checked);
      if (!c.models.checkedP2.empty()) printModel("checked values (quadratic tets) against the mesh's gain", c.models.checkedP2);
    }
    pack.value().database.frequencyErrors = c.models;
    return writeAndPrintPack(pack.value(), o->out.empty() ? o->pack : o->out, o->json);
  };
}

}  // namespace brittle::cli
