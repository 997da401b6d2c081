// brittle calibrate — fit a material's E, ν, density and Rayleigh damping to measurements of a
// real object (natural frequencies, decay rates, mass), and write it as a material file.
#include <cmath>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <nlohmann/json.hpp>

#include "CliSupport.h"
#include "Commands.h"
#include "brittle/core/JsonChecks.h"
#include "brittle/database/Pack.h"
#include "brittle/precompute/Calibration.h"
#include "brittle/precompute/MaterialLibrary.h"

namespace brittle::cli {
namespace {

struct CalibrateOptions {
  std::string pack, object, material, measurements, out;
  std::vector<double> frequencies, decayRates;
  double mass = 0.0, poissonMin = CalibrationSettings{}.poissonMin, poissonMax = CalibrationSettings{}.poissonMax;
  bool fixedPoisson = false, json = false, quiet = false;
  uint64_t seed = 1;
};

// {"frequencies_hz": [...], "decay_rates_per_s": [...], "mass_kg": m}; the last two optional.
Result<CalibrationMeasurements> readMeasurements(const std::string& path) {
  std::ifstream in(path);
  if (!in) return makeError(ErrorCode::FileNotFound, "measurements file not found: " + path);
  auto bad = [&](const std::string& what) { return parseError("measurements " + path, what); };
  nlohmann::json doc;
  try {
    doc = nlohmann::json::parse(in);
  } catch (const std::exception& e) {
    return bad(e.what());
  }
  if (!doc.is_object()) return bad("the top level must be an object");
  CalibrationMeasurements m;
  for (const auto& [key, value] : doc.items()) {
    if (key == "frequencies_hz" || key == "decay_rates_per_s") {
      if (!value.is_array()) return bad("\"" + key + "\" must be an array of numbers");
      auto& target = key == "frequencies_hz" ? m.frequenciesHz : m.decayRatesPerS;
      for (const auto& v : value) {
        if (!v.is_number()) return bad("\"" + key + "\" must be an array of numbers");
        target.push_back(v.get<double>());
      }
    } else if (key == "mass_kg") {
      if (!value.is_number()) return bad("\"mass_kg\" must be a number");
      m.massKg = value.get<double>();
    } else {
      return bad(unknownKeyMessage(key) + " (frequencies_hz, decay_rates_per_s, mass_kg)");
    }
  }
  return m;
}

nlohmann::json numberOrNull(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }

}  // namespace

Runner addCalibrateCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("calibrate",
                                 "Fit E, Poisson ratio, density and Rayleigh damping to measured natural frequencies, "
                                 "decay rates and mass of a real object (Ceres); write the material file");
  auto o = std::make_shared<CalibrateOptions>();
  cmd->add_option("pack", o->pack, "Pack holding the object's tet mesh (bake the object first)")->required();
  cmd->add_option("--object", o->object, "Object name in the pack")->required();
  cmd->add_option("--material", o->material, "Starting material: preset or JSON file (default: the object's own)");
  auto* freq = cmd->add_option("--frequencies", o->frequencies, "Measured natural frequencies (Hz) of the lowest elastic modes, ascending")
                   ->delimiter(',');
  cmd->add_option("--decay-rates", o->decayRates, "Measured amplitude decay rate (1/s) of each of those modes")->delimiter(',');
  cmd->add_option("--mass", o->mass, "Measured mass (kg): sets the density")->check(CLI::NonNegativeNumber);
  auto* file = cmd->add_option("--measurements", o->measurements,
                               "JSON file {\"frequencies_hz\": [...], \"decay_rates_per_s\": [...], \"mass_kg\": m}");
  file->excludes(freq);
  cmd->add_flag("--fixed-poisson", o->fixedPoisson, "Keep the starting Poisson ratio; fit E alone (one frequency suffices)");
  cmd->add_option("--poisson-min", o->poissonMin, "Lower bound on the Poisson ratio")->capture_default_str();
  cmd->add_option("--poisson-max", o->poissonMax, "Upper bound on the Poisson ratio")->capture_default_str();
  cmd->add_option("--seed", o->seed, "Seed of the modal solver's starting vector")->capture_default_str();
  cmd->add_option("--out", o->out, "Write the calibrated material here (JSON; bake with --material FILE)");
  cmd->add_flag("--json", o->json, "Print the result as JSON");
  cmd->add_flag("--quiet", o->quiet, "No progress line");

  return [o]() -> int {
    CalibrationMeasurements measured;
    if (!o->measurements.empty()) {
      auto read = readMeasurements(o->measurements);
      if (!read) return reportError(read.error());
      measured = std::move(read).value();
    } else {
      measured.frequenciesHz = o->frequencies;
      measured.decayRatesPerS = o->decayRates;
      measured.massKg = o->mass;
    }
    if (!o->decayRates.empty()) measured.decayRatesPerS = o->decayRates;
    if (o->mass > 0.0) measured.massKg = o->mass;
    if (measured.frequenciesHz.empty()) {
      return reportError(makeError(ErrorCode::InvalidArgument, "give --frequencies or --measurements"));
    }
    auto pack = readPack(o->pack);
    if (!pack) return reportError(pack.error());
    const ObjectAsset* object = nullptr;
    for (const ObjectAsset& a : pack.value().objects) {
      if (a.name == o->object) object = &a;
    }
    if (!object) return reportError(makeError(ErrorCode::InvalidArgument, "no object '" + o->object + "' in " + o->pack));
    Material base;
    if (o->material.empty()) {
      bool found = false;
      for (const Material& m : pack.value().materials) {
        if (m.name == object->materialName) base = m, found = true;
      }
      if (!found) return reportError(makeError(ErrorCode::UnknownMaterial, "the pack lacks material '" + object->materialName + "'"));
    } else {
      auto resolved = resolveMaterial(o->material);
      if (!resolved) return reportError(resolved.error());
      base = std::move(resolved).value();
    }
    CalibrationSettings settings;
    settings.fitPoissonRatio = !o->fixedPoisson;
    settings.poissonMin = o->poissonMin;
    settings.poissonMax = o->poissonMax;
    settings.seed = o->seed;
    settings.elementOrder = object->elementOrder;  // the model the pack runs, not a default
    settings.lumpedMass = object->bake.lumpedMass;
    TerminalProgress progress(o->quiet || o->json);
    auto fit = calibrateMaterial(object->tetMesh, base, measured, settings, &progress);
    progress.finish();
    if (!fit) return reportError(fit.error());
    const CalibrationResult& r = fit.value();
    if (!o->out.empty()) {
      Material named = r.material;
      named.name = base.name + "-calibrated";
      if (Status saved = saveMaterialFile(named, o->out); !saved) return reportError(saved.error());
    }

    nlohmann::json doc;
    doc["object"] = o->object;
    doc["base_material"] = base.name;
    doc["element"] = elementOrderName(object->elementOrder);
    doc["youngs_modulus_pa"] = r.material.youngsModulusPa;
    doc["youngs_modulus_std_pa"] = numberOrNull(r.youngsModulusStdPa);
    doc["poisson_ratio"] = r.material.poissonRatio;
    doc["poisson_ratio_std"] = numberOrNull(r.poissonRatioStd);
    doc["poisson_at_bound"] = r.poissonAtBound;
    doc["density_kg_per_m3"] = r.material.densityKgPerM3;
    doc["rayleigh_alpha_per_s"] = r.material.rayleighAlphaPerS;
    doc["rayleigh_alpha_std_per_s"] = numberOrNull(r.alphaStdPerS);
    doc["rayleigh_beta_s"] = r.material.rayleighBetaS;
    doc["rayleigh_beta_std_s"] = numberOrNull(r.betaStdS);
    doc["frequencies"] = nlohmann::json::array();
    for (size_t i = 0; i < measured.frequenciesHz.size(); ++i) {
      nlohmann::json row = {{"measured_hz", measured.frequenciesHz[i]}, {"model_hz", r.modelFrequenciesHz[i]},
                            {"error", r.frequencyErrors[i]}};
      if (!r.modelDecayRatesPerS.empty()) {
        row["measured_decay_per_s"] = measured.decayRatesPerS[i];
        row["model_decay_per_s"] = r.modelDecayRatesPerS[i];
      }
      doc["frequencies"].push_back(row);
    }
    doc["rms_frequency_error"] = r.rmsFrequencyError;
    doc["rms_decay_rate_error"] = r.rmsDecayRateError;
    doc["iterations"] = r.iterations;
    doc["modal_solves"] = r.modalSolves;
    doc["seconds"] = r.seconds;
    if (!o->out.empty()) doc["material_file"] = o->out;
    if (o->json) {
      std::cout << doc.dump(2) << "\n";
      return kExitOk;
    }
    std::cout << std::setprecision(4) << o->object << " calibrated from " << measured.frequenciesHz.size()
              << " frequencies (base " << base.name << ", " << elementOrderName(object->elementOrder)
              << " tets): E = " << r.material.youngsModulusPa / 1e9 << " GPa ± "
              << r.youngsModulusStdPa / 1e9 << ", nu = " << r.material.poissonRatio << " ± " << r.poissonRatioStd
              << (r.poissonAtBound ? " (at its bound)" : "") << ", density = " << r.material.densityKgPerM3 << " kg/m3\n";
    if (!r.modelDecayRatesPerS.empty()) {
      std::cout << "  damping: alpha = " << r.material.rayleighAlphaPerS << " 1/s ± " << r.alphaStdPerS
                << ", beta = " << r.material.rayleighBetaS << " s ± " << r.betaStdS << "\n";
    }
    std::cout << "  mode  measured Hz    model Hz    error\n";
    for (size_t i = 0; i < measured.frequenciesHz.size(); ++i) {
      std::cout << "  " << std::setw(4) << i << std::setw(13) << measured.frequenciesHz[i] << std::setw(12)
                << r.modelFrequenciesHz[i] << std::setw(9) << std::showpos << 100.0 * r.frequencyErrors[i]
                << std::noshowpos << " %\n";
    }
    std::cout << "  rms frequency error " << 100.0 * r.rmsFrequencyError << " %, " << r.iterations << " iterations, "
              << r.modalSolves << " modal solves, " << r.seconds << " s\n";
    if (!o->out.empty()) std::cout << "  material written to " << o->out << "\n";
    return kExitOk;
  };
}

}  // namespace brittle::cli
