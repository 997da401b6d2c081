#include "brittle/precompute/MaterialLibrary.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <numbers>
#include <system_error>

#include <nlohmann/json.hpp>

#include "brittle/core/AtomicFile.h"
#include "brittle/core/JsonChecks.h"

namespace brittle {
namespace {

// Damping convention for every preset. The references tabulate a loss factor η (nearly
// frequency-independent for these solids), not Rayleigh coefficients. Modal damping is ζ = η/2; we put
// all of it on the stiffness term at f_ref = 1 kHz (α = 0), so ζ(ω) = βω/2 and ζ(2π f_ref) = η/2
// ⇒ β = η / (2π f_ref). Lower modes then get proportionally less damping, which is conservative
// for crack initiation (less ring-down loss).
constexpr double kDampingReferenceHz = 1000.0;

constexpr double betaFromLossFactor(double lossFactor) {
  return lossFactor / (2.0 * std::numbers::pi * kDampingReferenceHz);
}

// Soda-lime-silica float glass (a window pane).
Material makeGlass() {
  Material m;
  m.name = "glass";
  m.youngsModulusPa = 70.0e9;     // EN 572-1:2012 (soda lime silicate glass, basic products)
  m.poissonRatio = 0.2;           // EN 572-1:2012
  m.densityKgPerM3 = 2500.0;      // EN 572-1:2012
  m.tensileStrengthPa = 45.0e6;   // EN 572-1:2012, characteristic bending strength of annealed glass
  // K_Ic ≈ 0.75 MPa·√m: Wiederhorn, "Fracture surface energy of glass", J. Am. Ceram. Soc.
  // 52(2):99–105, 1969 (γ ≈ 3.8–3.9 J/m² for soda-lime glass, i.e. G_c = 2γ ≈ 7.6–7.8 J/m²).
  constexpr double kToughnessPaSqrtM = 0.75e6;
  m.fractureEnergyJPerM2 = fractureEnergyFromToughness(kToughnessPaSqrtM, m.youngsModulusPa, m.poissonRatio);
  m.rayleighAlphaPerS = 0.0;
  m.rayleighBetaS = betaFromLossFactor(1.0e-3);  // η ≈ 1e-3 for glass, Cremer, Heckl & Petersson 2005
  m.restitution = 0.5;            // assumed: no standard reference value exists
  m.source =
      "E = 70 GPa, nu = 0.2, rho = 2500 kg/m3, sigma_t = 45 MPa (characteristic bending strength of "
      "annealed float glass): EN 572-1:2012 Glass in building - Basic soda lime silicate glass "
      "products - Part 1. K_Ic = 0.75 MPa*sqrt(m), converted to G_c = K^2(1-nu^2)/E: consistent with "
      "the fracture surface energy of soda-lime glass, S. M. Wiederhorn, J. Am. Ceram. Soc. 52(2) "
      "99-105 (1969). Loss factor eta = 1e-3 (order tabulated for glass in Cremer, Heckl & "
      "Petersson, Structure-Borne Sound, 3rd ed., Springer 2005), alpha = 0, beta = eta/(2 pi 1 kHz). "
      "Restitution 0.5: assumed.";
  return m;
}

// Triaxial (clay–quartz–feldspar) porcelain, e.g. tableware or a vase.
Material makePorcelain() {
  Material m;
  m.name = "porcelain";
  // Typical of the triaxial porcelains reviewed by Carty & Senapati, "Porcelain — raw materials,
  // processing, phase evolution, and mechanical behavior", J. Am. Ceram. Soc. 81(1):3–20, 1998.
  m.youngsModulusPa = 70.0e9;
  m.poissonRatio = 0.22;
  m.densityKgPerM3 = 2400.0;
  m.tensileStrengthPa = 70.0e6;   // modulus of rupture (flexural), same review
  // Typical triaxial-porcelain toughness, approximate: porcelains vary with quartz content and
  // porosity.
  constexpr double kToughnessPaSqrtM = 1.2e6;
  m.fractureEnergyJPerM2 = fractureEnergyFromToughness(kToughnessPaSqrtM, m.youngsModulusPa, m.poissonRatio);
  m.rayleighAlphaPerS = 0.0;
  m.rayleighBetaS = betaFromLossFactor(1.0e-3);  // assumed equal to glass (no tabulated value)
  m.restitution = 0.5;            // assumed
  m.source =
      "E = 70 GPa, nu = 0.22, rho = 2400 kg/m3, sigma_t = 70 MPa (modulus of rupture): typical "
      "values for triaxial porcelain as reviewed by W. M. Carty & U. Senapati, J. Am. Ceram. Soc. "
      "81(1) 3-20 (1998). K_Ic = 1.2 MPa*sqrt(m) (converted to G_c = K^2(1-nu^2)/E): typical "
      "triaxial-porcelain value, approximate. Porcelains vary widely. Loss factor eta = 1e-3: assumed equal to glass (Cremer, Heckl & "
      "Petersson, Structure-Borne Sound, 3rd ed., Springer 2005, has no porcelain entry), alpha = 0, "
      "beta = eta/(2 pi 1 kHz). Restitution 0.5: assumed.";
  return m;
}

// Dense sintered alpha-alumina (technical ceramic).
Material makeCeramic() {
  Material m;
  m.name = "ceramic";
  // Munro, "Evaluated material properties for a sintered α-alumina", J. Am. Ceram. Soc.
  // 80(8):1919–1928, 1997 (room-temperature values).
  m.youngsModulusPa = 416.0e9;
  m.poissonRatio = 0.231;
  m.densityKgPerM3 = 3984.0;
  m.tensileStrengthPa = 380.0e6;  // flexural (4-point) strength, Munro 1997
  constexpr double kToughnessPaSqrtM = 3.5e6;  // Munro 1997
  m.fractureEnergyJPerM2 = fractureEnergyFromToughness(kToughnessPaSqrtM, m.youngsModulusPa, m.poissonRatio);
  m.rayleighAlphaPerS = 0.0;
  m.rayleighBetaS = betaFromLossFactor(1.0e-3);  // assumed equal to glass (no tabulated value)
  m.restitution = 0.6;            // assumed
  m.source =
      "Sintered alpha-alumina: E = 416 GPa, nu = 0.231, rho = 3984 kg/m3, sigma_t = 380 MPa "
      "(flexural strength), K_Ic = 3.5 MPa*sqrt(m) (converted to G_c = K^2(1-nu^2)/E): R. G. Munro, "
      "Evaluated material properties for a sintered alpha-alumina, J. Am. Ceram. Soc. 80(8) "
      "1919-1928 (1997). Loss factor eta = 1e-3: assumed equal to glass (Cremer, Heckl & Petersson, "
      "Structure-Borne Sound, 3rd ed., Springer 2005), alpha = 0, beta = eta/(2 pi 1 kHz). "
      "Restitution 0.6: assumed.";
  return m;
}

// Normal-weight concrete of strength class C30/37.
Material makeConcrete() {
  Material m;
  m.name = "concrete";
  m.youngsModulusPa = 33.0e9;     // E_cm, EN 1992-1-1:2004 Table 3.1, C30/37
  m.poissonRatio = 0.2;           // EN 1992-1-1:2004 §3.1.3(4), uncracked concrete
  m.densityKgPerM3 = 2400.0;      // EN 1991-1-1:2002 Table A.1, 24 kN/m³ plain normal-weight concrete
  m.tensileStrengthPa = 2.9e6;    // f_ctm, EN 1992-1-1:2004 Table 3.1, C30/37
  // fib Model Code 2010 eq. 5.1-9: G_F = 73 f_cm^0.18 (N/m, f_cm in MPa), f_cm = 38 MPa for C30/37
  // (EN 1992-1-1 Table 3.1). Concrete's fracture energy is given directly, not as a toughness.
  constexpr double kMeanCompressiveStrengthMPa = 38.0;
  m.fractureEnergyJPerM2 = 73.0 * std::pow(kMeanCompressiveStrengthMPa, 0.18);
  m.rayleighAlphaPerS = 0.0;
  m.rayleighBetaS = betaFromLossFactor(6.0e-3);  // η of heavy concrete, Cremer, Heckl & Petersson
  m.restitution = 0.3;            // assumed
  m.source =
      "C30/37: E_cm = 33 GPa, f_ctm = 2.9 MPa, f_cm = 38 MPa: EN 1992-1-1:2004 Table 3.1; nu = 0.2: "
      "EN 1992-1-1:2004 3.1.3(4); rho = 2400 kg/m3 (24 kN/m3): EN 1991-1-1:2002 Table A.1. "
      "G_F = 73 f_cm^0.18 = 140 J/m2: fib Model Code for Concrete Structures 2010, eq. 5.1-9. "
      "Loss factor eta = 6e-3 (order tabulated for concrete in Cremer, Heckl & Petersson, "
      "Structure-Borne Sound, 3rd ed., Springer 2005), alpha = 0, beta = eta/(2 pi 1 kHz). "
      "Restitution 0.3: assumed.";
  return m;
}

// Granite (building stone, a thrown rock).
Material makeStone() {
  Material m;
  m.name = "stone";
  // Typical granite: Goodman, Introduction to Rock Mechanics, 2nd ed., Wiley 1989.
  m.youngsModulusPa = 60.0e9;
  m.poissonRatio = 0.25;
  m.densityKgPerM3 = 2650.0;
  m.tensileStrengthPa = 10.0e6;
  // Within the range of granite toughnesses compiled by Atkinson & Meredith in Atkinson (ed.),
  // Fracture Mechanics of Rock, Academic Press 1987.
  constexpr double kToughnessPaSqrtM = 1.5e6;
  m.fractureEnergyJPerM2 = fractureEnergyFromToughness(kToughnessPaSqrtM, m.youngsModulusPa, m.poissonRatio);
  m.rayleighAlphaPerS = 0.0;
  m.rayleighBetaS = betaFromLossFactor(6.0e-3);  // assumed equal to concrete (no tabulated value)
  m.restitution = 0.4;            // assumed
  m.source =
      "Granite: E = 60 GPa, nu = 0.25, rho = 2650 kg/m3, sigma_t = 10 MPa: typical granite values, "
      "R. E. Goodman, Introduction to Rock Mechanics, 2nd ed., Wiley 1989. K_Ic = 1.5 MPa*sqrt(m) "
      "(converted to G_c = K^2(1-nu^2)/E): within the granite range compiled by B. K. Atkinson & "
      "P. G. Meredith in B. K. Atkinson (ed.), Fracture Mechanics of Rock, Academic Press 1987. "
      "Loss factor eta = 6e-3: assumed equal to concrete (Cremer, Heckl & Petersson, "
      "Structure-Borne Sound, 3rd ed., Springer 2005), alpha = 0, beta = eta/(2 pi 1 kHz). "
      "Restitution 0.4: assumed.";
  return m;
}

// Structural steel S355, used as an impactor (a steel ball); it never fractures in brittle's model.
Material makeSteel() {
  Material m;
  m.name = "steel";
  m.youngsModulusPa = 210.0e9;    // EN 1993-1-1:2005 §3.2.6
  m.poissonRatio = 0.3;           // EN 1993-1-1:2005 §3.2.6
  m.densityKgPerM3 = 7850.0;      // EN 1991-1-1:2002 Table A.4 (77–78.5 kN/m³)
  m.tensileStrengthPa = 510.0e6;  // f_u of S355 (t ≤ 40 mm), EN 1993-1-1:2005 Table 3.1
  // Placeholder order of magnitude for a tough steel; validateMaterial needs G_c > 0, and the
  // impactor's G_c is never used by crack propagation.
  constexpr double kToughnessPaSqrtM = 100.0e6;
  m.fractureEnergyJPerM2 = fractureEnergyFromToughness(kToughnessPaSqrtM, m.youngsModulusPa, m.poissonRatio);
  m.rayleighAlphaPerS = 0.0;
  m.rayleighBetaS = betaFromLossFactor(1.0e-4);  // η of steel, Cremer, Heckl & Petersson
  m.restitution = 0.6;            // assumed
  m.source =
      "S355 structural steel (impactor): E = 210 GPa, nu = 0.3: EN 1993-1-1:2005 3.2.6; sigma_t = "
      "f_u = 510 MPa: EN 1993-1-1:2005 Table 3.1; rho = 7850 kg/m3: EN 1991-1-1:2002 Table A.4. "
      "K_Ic = 100 MPa*sqrt(m): order-of-magnitude placeholder, not a design value (the impactor "
      "never fractures). Loss factor eta = 1e-4 (order tabulated for steel in Cremer, Heckl & "
      "Petersson, Structure-Borne Sound, 3rd ed., Springer 2005), alpha = 0, beta = eta/(2 pi 1 "
      "kHz). Restitution 0.6: assumed.";
  return m;
}

// Sorted by name, built once: the presets are constants of the program.
const std::vector<Material>& presets() {
  static const std::vector<Material> kPresets = [] {
    std::vector<Material> all = {makeCeramic(), makeConcrete(), makeGlass(),
                                 makePorcelain(), makeSteel(), makeStone()};
    std::sort(all.begin(), all.end(), [](const Material& a, const Material& b) { return a.name < b.name; });
    return all;
  }();
  return kPresets;
}

// The keys of a custom material file, as documented in MaterialLibrary.h.
constexpr const char* kKeyName = "name";
constexpr const char* kKeyYoungs = "youngs_modulus_pa";
constexpr const char* kKeyPoisson = "poisson_ratio";
constexpr const char* kKeyDensity = "density_kg_per_m3";
constexpr const char* kKeyStrength = "tensile_strength_pa";
constexpr const char* kKeyEnergy = "fracture_energy_j_per_m2";
constexpr const char* kKeyToughness = "fracture_toughness_pa_sqrt_m";
constexpr const char* kKeyAlpha = "rayleigh_alpha_per_s";
constexpr const char* kKeyBeta = "rayleigh_beta_s";
constexpr const char* kKeyRestitution = "restitution";
constexpr const char* kKeySource = "source";

constexpr const char* kAllKeys[] = {kKeyName,     kKeyYoungs, kKeyPoisson,   kKeyDensity,
                                    kKeyStrength, kKeyEnergy, kKeyToughness, kKeyAlpha,
                                    kKeyBeta,     kKeyRestitution, kKeySource};

Error materialFileError(const std::filesystem::path& path, const std::string& what) {
  return parseError("material file " + path.string(), what);
}

Result<double> readNumber(const nlohmann::json& doc, const char* key, const std::filesystem::path& path) {
  const auto it = doc.find(key);
  if (it == doc.end()) return materialFileError(path, std::string("missing key \"") + key + "\"");
  // Booleans are not numbers in nlohmann::json, so `true` is rejected here as it should be.
  if (!it->is_number()) return materialFileError(path, std::string("key \"") + key + "\" must be a number");
  return it->get<double>();
}

Result<std::string> readString(const nlohmann::json& doc, const char* key, const std::filesystem::path& path) {
  const auto it = doc.find(key);
  if (it == doc.end()) return materialFileError(path, std::string("missing key \"") + key + "\"");
  if (!it->is_string()) return materialFileError(path, std::string("key \"") + key + "\" must be a string");
  return it->get<std::string>();
}

Result<Material> materialFromJson(const nlohmann::json& doc, const std::filesystem::path& path) {
  if (!doc.is_object()) return materialFileError(path, "the top level must be a JSON object");
  if (auto key = findUnknownKey(doc, kAllKeys)) return materialFileError(path, unknownKeyMessage(*key));

  Material m;
  struct NumberField {
    const char* key;
    double* target;
  };
  const NumberField fields[] = {
      {kKeyYoungs, &m.youngsModulusPa},     {kKeyPoisson, &m.poissonRatio},
      {kKeyDensity, &m.densityKgPerM3},     {kKeyStrength, &m.tensileStrengthPa},
      {kKeyAlpha, &m.rayleighAlphaPerS},    {kKeyBeta, &m.rayleighBetaS},
      {kKeyRestitution, &m.restitution},
  };
  auto name = readString(doc, kKeyName, path);
  if (!name) return name.error();
  m.name = std::move(name).value();
  for (const auto& f : fields) {
    auto v = readNumber(doc, f.key, path);
    if (!v) return v.error();
    *f.target = v.value();
  }
  auto source = readString(doc, kKeySource, path);
  if (!source) return source.error();
  m.source = std::move(source).value();

  const bool hasEnergy = doc.contains(kKeyEnergy);
  const bool hasToughness = doc.contains(kKeyToughness);
  if (hasEnergy == hasToughness) {
    return materialFileError(path, std::string(hasEnergy ? "both" : "neither") + " of \"" + kKeyEnergy + "\" and \"" +
                                kKeyToughness + "\" given (exactly one is required)");
  }
  if (hasEnergy) {
    auto g = readNumber(doc, kKeyEnergy, path);
    if (!g) return g.error();
    m.fractureEnergyJPerM2 = g.value();
  } else {
    auto k = readNumber(doc, kKeyToughness, path);
    if (!k) return k.error();
    // K enters squared, so a negative toughness would otherwise turn into a valid-looking G_c.
    if (!(k.value() > 0.0)) {
      return makeError(ErrorCode::InvalidMaterial, "material file " + path.string() + ": " + kKeyToughness +
                                                       " = " + std::to_string(k.value()) + " (must be > 0)");
    }
    m.fractureEnergyJPerM2 = fractureEnergyFromToughness(k.value(), m.youngsModulusPa, m.poissonRatio);
  }

  Status valid = validateMaterial(m);
  if (!valid) return makeError(ErrorCode::InvalidMaterial, "material file " + path.string() + ": " + valid.error().message);
  return m;
}

}  // namespace

Status saveMaterialFile(const Material& m, const std::filesystem::path& path) {
  if (Status valid = validateMaterial(m); !valid) return valid.error();
  // Insertion order as documented; %.17g round-trips every double.
  nlohmann::ordered_json doc = {{kKeyName, m.name},
                                {kKeyYoungs, m.youngsModulusPa},
                                {kKeyPoisson, m.poissonRatio},
                                {kKeyDensity, m.densityKgPerM3},
                                {kKeyStrength, m.tensileStrengthPa},
                                {kKeyEnergy, m.fractureEnergyJPerM2},
                                {kKeyAlpha, m.rayleighAlphaPerS},
                                {kKeyBeta, m.rayleighBetaS},
                                {kKeyRestitution, m.restitution},
                                {kKeySource, m.source}};
  return writeFileAtomically(path, doc.dump(2) + "\n");
}

std::vector<std::string> materialPresetNames() {
  std::vector<std::string> names;
  for (const auto& m : presets()) names.push_back(m.name);
  return names;
}

Result<Material> materialPreset(std::string_view name) {
  for (const auto& m : presets()) {
    if (m.name == name) return m;
  }
  std::string list;
  for (const auto& n : materialPresetNames()) list += (list.empty() ? "" : ", ") + n;
  return makeError(ErrorCode::UnknownMaterial,
                   "unknown material preset '" + std::string(name) + "' (presets: " + list + ")");
}

Result<Material> loadMaterialFile(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    return makeError(ErrorCode::FileNotFound, "material file not found: " + path.string());
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) return makeError(ErrorCode::FileNotFound, "material file cannot be opened: " + path.string());
  try {
    // Overflowing numbers such as 1e999 make the parser throw (out_of_range 406), so no
    // infinity ever reaches the material.
    const nlohmann::json doc = nlohmann::json::parse(in);
    return materialFromJson(doc, path);
  } catch (const nlohmann::json::exception& e) {
    return materialFileError(path, e.what());
  } catch (const std::exception& e) {
    return materialFileError(path, e.what());
  }
}

Result<Material> resolveMaterial(const std::string& nameOrPath) {
  const std::filesystem::path path(nameOrPath);
  std::error_code ec;
  if (path.extension() == ".json" || std::filesystem::is_regular_file(path, ec)) return loadMaterialFile(path);
  return materialPreset(nameOrPath);
}

}  // namespace brittle
