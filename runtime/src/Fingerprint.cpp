#include "brittle/runtime/Fingerprint.h"

#include <cstdio>

namespace brittle {

uint64_t fingerprint(const ImpactResult& r) {
  Fingerprint f;
  f.add(r.broken);
  const HertzContact& c = r.contact;
  for (double v : {c.effectiveMassKg, c.effectiveRadiusM, c.effectiveModulusPa, c.maxIndentationM, c.hertzPeakForceN,
                   c.durationS, c.patchRadiusM, c.impulseNs, c.pulseAmplitudeN, r.bodyRadiusM, r.peakPrincipalStressPa,
                   r.peakWithoutCorrectionPa, r.peakTimeS, r.ringDownS}) {
    f.add(v);
  }
  f.add(r.peakElement);
  f.add(r.modesUsed);
  f.add(r.staticCorrectionUsed);
  f.add(r.stressEvaluations);
  f.add(static_cast<uint64_t>(r.loadWeights.size()));
  for (const auto& [node, weight] : r.loadWeights) {
    f.add(node);
    f.add(weight);
  }
  f.add(r.forceDirectionLocal);
  const FractureState& s = r.fracture;
  f.add(static_cast<uint64_t>(s.cutElements.size()));
  for (int32_t e : s.cutElements) f.add(e);
  for (const Eigen::Vector4d& p : s.cutPlanes) f.add(p);
  f.add(s.edgeCuts);
  f.add(s.nodeLabels);
  f.add(s.fragmentCount);
  f.add(s.crackCount);
  f.add(s.crackAreaM2);
  f.add(s.energyBudgetJ);
  f.add(s.energySpentJ);
  f.add(s.arrestedByEnergy);
  f.add(s.mergedCrumbs);
  f.add(static_cast<uint64_t>(r.fragments.size()));
  for (const FragmentResult& fr : r.fragments) {
    f.add(static_cast<int>(fr.path));
    f.add(fr.reason);
    f.add(fr.debris);
    f.add(fr.surface.vertices);
    f.add(fr.surface.faces);
    const MassProperties& m = fr.massProperties;
    f.add(m.volumeM3);
    f.add(m.massKg);
    f.add(m.centerOfMassM);
    f.add(m.inertiaKgM2);
    f.add(m.secondMomentM5);
    f.add(fr.matchedEntry);
    f.add(fr.exactModes);
    f.add(fr.matchDistance);
  }
  return f.value();
}

std::string fingerprintHex(uint64_t value) {
  char text[17];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(value));
  return text;
}

}  // namespace brittle
