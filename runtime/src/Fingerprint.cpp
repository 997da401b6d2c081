#include "brittle/runtime/Fingerprint.h"

#include <cstdio>

namespace brittle {

uint64_t fingerprint(const ImpactResult& r) {
  Fingerprint f;
  const HertzContact& c = r.contact;
  f.add(r.broken, c.effectiveMassKg, c.effectiveRadiusM, c.effectiveModulusPa, c.maxIndentationM, c.hertzPeakForceN,
        c.durationS, c.patchRadiusM, c.impulseNs, c.pulseAmplitudeN, r.bodyRadiusM, r.peakPrincipalStressPa,
        r.peakWithoutCorrectionPa, r.peakTimeS, r.ringDownS);
  f.add(r.peakElement, r.modesUsed, r.staticCorrectionUsed, r.stressEvaluations);
  f.add(static_cast<uint64_t>(r.loadWeights.size()));
  for (const auto& [node, weight] : r.loadWeights) f.add(node, weight);
  f.add(r.forceDirectionLocal);
  const FractureState& s = r.fracture;
  f.add(static_cast<uint64_t>(s.cutElements.size()));
  for (int32_t e : s.cutElements) f.add(e);
  for (const Eigen::Vector4d& p : s.cutPlanes) f.add(p);
  f.add(s.edgeCuts, s.nodeLabels);
  f.add(s.fragmentCount, s.crackCount, s.crackAreaM2, s.energyBudgetJ, s.energySpentJ, s.arrestedByEnergy, s.mergedCrumbs);
  f.add(static_cast<uint64_t>(r.fragments.size()));
  for (const FragmentResult& fr : r.fragments) {
    const MassProperties& m = fr.massProperties;
    f.add(static_cast<int>(fr.path), fr.reason, fr.debris, fr.surface.vertices, fr.surface.faces);
    f.add(m.volumeM3, m.massKg, m.centerOfMassM, m.inertiaKgM2, m.secondMomentM5);
    f.add(fr.matchedEntry, fr.exactModes, fr.matchDistance);
  }
  return f.value();
}

std::string fingerprintHex(uint64_t value) {
  char text[17];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(value));
  return text;
}

}  // namespace brittle
