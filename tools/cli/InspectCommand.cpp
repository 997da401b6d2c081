#include <cmath>
#include <iomanip>
#include <iostream>
#include <map>

#include "CliSupport.h"
#include "Commands.h"

namespace brittle::cli {
namespace {

nlohmann::json vec3(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }
nlohmann::json mat3(const Eigen::Matrix3d& m) {
  return {{m(0, 0), m(0, 1), m(0, 2)}, {m(1, 0), m(1, 1), m(1, 2)}, {m(2, 0), m(2, 1), m(2, 2)}};
}
nlohmann::json vecX(const Eigen::VectorXd& v) { return std::vector<double>(v.data(), v.data() + v.size()); }

nlohmann::json materialJson(const Material& m) {
  return {{"name", m.name},
          {"youngs_modulus_pa", m.youngsModulusPa},
          {"poisson_ratio", m.poissonRatio},
          {"density_kg_per_m3", m.densityKgPerM3},
          {"tensile_strength_pa", m.tensileStrengthPa},
          {"fracture_energy_j_per_m2", m.fractureEnergyJPerM2},
          {"rayleigh_alpha_per_s", m.rayleighAlphaPerS},
          {"rayleigh_beta_s", m.rayleighBetaS},
          {"restitution", m.restitution},
          {"source", m.source}};
}

const Material* findMaterial(const Pack& pack, const std::string& name) {
  for (const auto& m : pack.materials)
    if (m.name == name) return &m;
  return nullptr;
}

nlohmann::json databaseJson(const FragmentDatabase& db) {
  std::map<std::string, int64_t> shapes;
  int64_t tets = 0;
  for (size_t i = 0; i < db.entries.size(); ++i) {
    const FragmentEntry& e = db.entries[i];
    ++shapes[e.baseShape];
    tets += db.entrySource ? db.entrySource->tetCount(static_cast<int64_t>(i)) : e.asset.tetMesh.tets.rows();
  }
  nlohmann::json j = {{"entries", db.entries.size()},
                      {"seed", db.seed},
                      {"physics", db.hasPhysics()},
                      {"total_tets", tets},
                      {"reference_material", materialJson(db.referenceMaterial)},
                      {"base_shapes", shapes}};
  const ShapeDescriptorSettings& d = db.descriptorSettings;
  for (DescriptorKind kind : kAllDescriptorKinds) {
    const DescriptorIndexSettings& index = db.indexSettings[static_cast<size_t>(kind)];
    nlohmann::json k = {{"dims", descriptorSize(kind, d)},
                        {"index", {{"backend", descriptorIndexKindName(index.kind)},
                                   {"trees", index.trees},
                                   {"checks", index.checks},
                                   {"target_precision", index.targetPrecision},
                                   {"seed", index.seed}}}};
    if (const MatchErrorModel& m = db.matchErrors[static_cast<size_t>(kind)]; !m.empty()) {
      k["match_errors"] = {{"samples", m.samples}, {"distance", m.distance}, {"median_error", m.medianError},
                           {"p90_error", m.p90Error}};
    }
    if (kind == DescriptorKind::Moment) k["max_order"] = d.moment.maxOrder;
    if (kind == DescriptorKind::Voxel) k["resolution"] = d.voxel.resolution;
    if (kind == DescriptorKind::VoxelImproved) {
      k["resolution"] = d.voxelImproved.resolution;
      k["clamp_voxels"] = d.voxelImproved.clampVoxels;
    }
    j["descriptors"][descriptorKindName(kind)] = k;
  }
  // The bodies' frequency-error models (brittle calibrate-errors), against their indicators.
  auto model = [](const MatchErrorModel& m) {
    return nlohmann::json{{"samples", m.samples}, {"indicator", m.distance}, {"median_error", m.medianError}, {"p90_error", m.p90Error}};
  };
  if (!db.frequencyErrors.ritz.empty()) j["frequency_errors"]["ritz"] = model(db.frequencyErrors.ritz);
  if (!db.frequencyErrors.checked.empty()) j["frequency_errors"]["checked"] = model(db.frequencyErrors.checked);
  if (!db.frequencyErrors.checkedP2.empty()) j["frequency_errors"]["checked_p2"] = model(db.frequencyErrors.checkedP2);
  if (!db.frequencyErrors.empty()) j["frequency_errors"]["degree"] = db.frequencyErrors.degree;
  return j;
}

}  // namespace

nlohmann::json inspectJson(const Pack& pack) {
  nlohmann::json doc;
  doc["format"] = kPackFormatName;
  doc["version"] = kPackVersion;
  doc["materials"] = nlohmann::json::array();
  for (const auto& m : pack.materials) doc["materials"].push_back(materialJson(m));
  doc["objects"] = nlohmann::json::array();
  for (const auto& o : pack.objects) {
    const auto& q = o.quality;
    const auto& mp = o.massProperties;
    const auto& b = o.bake;
    nlohmann::json j;
    j["name"] = o.name;
    const Material* material = findMaterial(pack, o.materialName);
    j["material"] = material ? materialJson(*material) : nlohmann::json{{"name", o.materialName}};
    j["mesh"] = {{"nodes", q.nodeCount},
                 {"tets", q.tetCount},
                 {"element", elementOrderName(o.elementOrder)},
                 {"fem_nodes", o.modal.modes.rows() / 3},
                 {"surface_faces", q.surfaceFaceCount},
                 {"min_dihedral_deg", q.minDihedralDeg},
                 {"max_dihedral_deg", q.maxDihedralDeg},
                 {"max_radius_edge_ratio", q.maxRadiusEdgeRatio},
                 {"mean_radius_edge_ratio", q.meanRadiusEdgeRatio},
                 {"min_tet_volume_m3", q.minTetVolumeM3},
                 // The factorisation's elimination order: baked (METIS, less fill) or the runtime's AMD.
                 {"elimination_order", o.eliminationOrder.size() > 0 ? "baked" : "amd"}};
    j["contact_spread_fraction"] = o.contactSpreadFraction;
    j["mass_properties"] = {{"mass_kg", mp.massKg},
                            {"volume_m3", mp.volumeM3},
                            {"center_of_mass_m", vec3(mp.centerOfMassM)},
                            {"inertia_kg_m2", mat3(mp.inertiaKgM2)}};
    const auto& m = o.modal;
    j["modes"] = {{"count", m.frequenciesHz.size()},
                  {"frequencies_hz", vecX(m.frequenciesHz)},
                  {"eigenvalues_rad2_per_s2", vecX(m.eigenvaluesRad2PerS2)},
                  {"residuals", vecX(m.residuals)},
                  {"max_residual", m.residuals.size() ? m.residuals.maxCoeff() : 0.0},
                  {"orthonormality_error", m.orthonormalityError}};
    j["bake"] = {{"source_mesh", b.sourceMesh},
                 {"target_tets", b.targetTets},
                 {"cell_size_m", b.cellSizeM},
                 {"thin_stretch", b.thinStretch},
                 {"requested_modes", b.requestedModes},
                 {"lumped_mass", b.lumpedMass},
                 {"repaired", b.repaired},
                 {"repair_volume_change", b.repairVolumeChange},
                 {"factorization", b.factorization},
                 {"shift_rad2_per_s2", b.shift},
                 {"seed", b.seed},
                 {"generator", b.generator},
                 {"timings_s",
                  {{"meshing", b.meshingS},
                   {"assembly", b.assemblyS},
                   {"modal", b.modalS},
                   {"stress_modes", b.stressModesS},
                   {"total", b.totalS}}}};
    doc["objects"].push_back(std::move(j));
  }
  if (!pack.database.empty()) doc["database"] = databaseJson(pack.database);
  return doc;
}

void printInspection(const Pack& pack, std::ostream& out) {
  out << std::setprecision(4);
  out << kPackFormatName << " v" << kPackVersion << ": " << pack.objects.size() << " object(s), "
      << pack.materials.size() << " material(s)\n";
  for (const auto& o : pack.objects) {
    const auto& q = o.quality;
    const auto& mp = o.massProperties;
    const auto& m = o.modal;
    const auto& b = o.bake;
    out << "\nobject " << o.name << "  (from " << b.sourceMesh << ")\n";
    if (const Material* mat = findMaterial(pack, o.materialName)) {
      out << "  material      " << mat->name << ": E " << mat->youngsModulusPa / 1e9 << " GPa, nu "
          << mat->poissonRatio << ", rho " << mat->densityKgPerM3 << " kg/m3, sigma_t "
          << mat->tensileStrengthPa / 1e6 << " MPa, G_c " << mat->fractureEnergyJPerM2 << " J/m2, Rayleigh ("
          << mat->rayleighAlphaPerS << " 1/s, " << mat->rayleighBetaS << " s)\n";
    }
    out << "  tet mesh      " << q.nodeCount << " nodes, " << q.tetCount << " " << elementOrderName(o.elementOrder)
        << " tets (" << o.modal.modes.rows() / 3 << " FEM nodes), " << q.surfaceFaceCount << " surface faces; dihedral " << q.minDihedralDeg << "-" << q.maxDihedralDeg << " deg, radius-edge max "
        << q.maxRadiusEdgeRatio << " (mean " << q.meanRadiusEdgeRatio << "); elimination order "
        << (o.eliminationOrder.size() > 0 ? "baked (METIS)" : "AMD at runtime") << "\n";
    if (o.contactSpreadFraction > 0.0) {
      out << "  contact       loads spread over at least " << o.contactSpreadFraction << " of the diagonal\n";
    }
    out << "  mass          " << mp.massKg << " kg, volume " << mp.volumeM3 << " m3, centre of mass ("
        << mp.centerOfMassM.x() << ", " << mp.centerOfMassM.y() << ", " << mp.centerOfMassM.z() << ") m\n";
    out << "  inertia       diag (" << mp.inertiaKgM2(0, 0) << ", " << mp.inertiaKgM2(1, 1) << ", "
        << mp.inertiaKgM2(2, 2) << "), off-diag (" << mp.inertiaKgM2(1, 2) << ", " << mp.inertiaKgM2(0, 2) << ", "
        << mp.inertiaKgM2(0, 1) << ") kg m2\n";
    out << "  modes         " << m.frequenciesHz.size() << ", orthonormality error " << m.orthonormalityError
        << ", max residual " << (m.residuals.size() ? m.residuals.maxCoeff() : 0.0) << "\n";
    for (Eigen::Index i = 0; i < m.frequenciesHz.size(); ++i) {
      out << "    " << std::setw(3) << i << "  " << std::setw(10) << std::fixed << std::setprecision(1)
          << m.frequenciesHz(i) << " Hz   residual " << std::scientific << std::setprecision(2) << m.residuals(i)
          << std::defaultfloat << std::setprecision(4) << "\n";
    }
    out << "  bake          target " << b.targetTets << " tets, ";
    if (b.thinStretch != 1.0) out << b.thinStretch << "x wider than thick, ";
    out << "cell size " << b.cellSizeM << " m, "
        << b.requestedModes << " modes, " << (b.lumpedMass ? "lumped" : "consistent") << " mass, "
        << b.factorization << ", shift " << b.shift << ", seed " << b.seed
        << (b.repaired ? ", repaired (volume change " + std::to_string(100.0 * b.repairVolumeChange) + "%)" : "")
        << "\n";
    out << "  timings       meshing " << b.meshingS << " s, assembly " << b.assemblyS << " s, modal " << b.modalS
        << " s, stress modes " << b.stressModesS << " s, total " << b.totalS << " s\n";
  }
  if (!pack.database.empty()) {
    const nlohmann::json db = databaseJson(pack.database);
    out << "\nfragment database  " << pack.database.entries.size() << " entries ("
        << (pack.database.hasPhysics() ? "tet meshes and modes, " + std::to_string(db["total_tets"].get<int64_t>()) + " tets"
                                       : std::string("descriptors only"))
        << "), reference material " << pack.database.referenceMaterial.name << ", seed " << pack.database.seed << "\n";
    out << "  base shapes  ";
    for (const auto& [shape, count] : db["base_shapes"].items()) out << " " << shape << " " << count.get<int64_t>();
    out << "\n  descriptors  ";
    for (const auto& [kind, k] : db["descriptors"].items()) {
      out << " " << kind << " (" << k["dims"].get<int>() << " values, " << k["index"]["backend"].get<std::string>()
          << ")";
    }
    out << "\n";
    const FrequencyErrorModels& f = pack.database.frequencyErrors;
    if (!f.empty()) {
      out << "  frequency errors  calibrated on " << f.ritz.samples << " runtime fragments; median (p90) from the lowest to the highest indicator:";
      auto range = [&](const char* what, const MatchErrorModel& m) {
        if (m.empty()) return;
        out << " " << what << " " << std::lround(100 * m.medianError.front()) << " (" << std::lround(100 * m.p90Error.front()) << ") to "
            << std::lround(100 * m.medianError.back()) << " (" << std::lround(100 * m.p90Error.back()) << ") %";
      };
      range("Ritz", f.ritz);
      range(", checked", f.checked);
      range(", checked in P2", f.checkedP2);
      out << "\n";
    }
  }
}

// The checks a whole read makes, in bounded memory: every descriptor matrix and every entry of a
// database read on demand, read and checked one at a time and dropped (a 10⁴-entry database:
// 16 s and 0.41 GB, where a whole read holds 12 GB). The first failure is the error.
Status checkDatabaseOnDemand(const FragmentDatabase& db, bool quiet) {
  if (!db.entrySource) return Ok{};
  for (DescriptorKind kind : kAllDescriptorKinds) {
    if (auto m = db.entrySource->descriptors(kind); !m) return m.error();
  }
  TerminalProgress progress(quiet);
  const auto count = static_cast<int64_t>(db.entries.size());
  for (int64_t i = 0; i < count; ++i) {
    if (auto e = db.entrySource->load(i); !e) return e.error();
    if (i % 64 == 0 || i + 1 == count) progress.report("checking database entries", static_cast<double>(i + 1) / count);
  }
  progress.finish();
  return Ok{};
}

Runner addInspectCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("inspect", "Print what a pack holds: objects, materials, mesh quality, modes");
  auto pack = std::make_shared<std::string>();
  auto json = std::make_shared<bool>(false);
  cmd->add_option("pack", *pack, "Pack file (.h5)")->required();
  cmd->add_flag("--json", *json, "Print the stable JSON document instead of text");
  return [pack, json]() -> int {
    // Read on demand, then checked entry by entry: the same checks as a whole read, in bounded
    // memory, so that a 3 GB database can be inspected on a small machine.
    auto loaded = readPack(*pack, EntryReading::OnDemand);
    Status checked = loaded ? checkDatabaseOnDemand(loaded.value().database, *json) : Status(Ok{});
    if (!loaded || !checked) {
      const Error& error = loaded ? checked.error() : loaded.error();
      // A missing pack is a pack problem here, not a mesh one.
      const int code = reportError(error);
      return error.code == ErrorCode::FileNotFound ? kExitPack : code;
    }
    if (*json) {
      std::cout << inspectJson(loaded.value()).dump(2) << "\n";
    } else {
      printInspection(loaded.value(), std::cout);
    }
    return kExitOk;
  };
}

}  // namespace brittle::cli
