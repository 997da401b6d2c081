// PlayReport.cpp — JSON and text views of a PlayResult.
#include "brittle/player/PlayReport.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iomanip>

#include "brittle/runtime/Fingerprint.h"

namespace brittle {
namespace {

nlohmann::json number(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(v > 0 ? "inf" : "-inf"); }

int32_t maxBodies(const PlayResult& r) {
  int32_t m = 0;
  for (const FrameStats& f : r.frameStats) m = std::max(m, f.bodies);
  return m;
}


}  // namespace

nlohmann::json playReportJson(const PlayResult& r, int framesEvery) {
  const FrameTimeSummary t = summarizeFrameTimes(r.frameStats);
  nlohmann::json doc;
  doc["scene"] = r.scene;
  doc["seed"] = r.seed;
  doc["frame_count"] = r.frames;
  doc["time_step_s"] = r.timeStepS;
  doc["load_s"] = r.loadS;
  const double total = t.bulletS + t.fractureS;
  doc["summary"] = {{"impacts", r.impacts},
                    {"breaks", r.breaks},
                    {"deferred_impacts", r.deferredImpacts},
                    {"budget_deferred_impacts", r.budgetDeferredImpacts},
                    {"simplified_impacts", r.simplifiedImpacts},
                    {"failed_impacts", r.failedImpacts},
                    {"bodies_at_end", r.bodiesAtEnd},
                    {"bodies_max", maxBodies(r)},
                    {"pose_hash", fingerprintHex(r.poseHash)},
                    {"frequency_sources_at_end", r.frequencySourcesAtEnd},
                    {"frame_time_s", {{"median", t.medianS}, {"p99", t.p99S}, {"max", t.maxS}}},
                    {"bullet_s", t.bulletS},
                    {"fracture_s", t.fractureS},
                    {"fracture_share", total > 0.0 ? t.fractureS / total : 0.0}};
  doc["events"] = nlohmann::json::array();
  for (const ImpactEvent& e : r.events) {
    nlohmann::json j = {{"time_s", e.timeS},
                        {"frame", e.frame},
                        {"body", e.body},
                        {"object", e.object},
                        {"other_body", e.otherBody},
                        {"speed_mps", e.speedMps},
                        {"other_mass_kg", number(e.otherMassKg)},
                        {"broken", e.broken},
                        {"fragments", e.fragments},
                        {"debris", e.debris},
                        {"peak_principal_stress_pa", e.peakPrincipalStressPa},
                        {"waited_steps", e.waitedSteps},
                        {"applied_frame", e.appliedFrame},
                        {"latency_frames", e.appliedFrame >= 0 ? nlohmann::json(e.appliedFrame - e.frame) : nlohmann::json(nullptr)},
                        {"wait_s", e.waitS},
                        {"simplified", e.simplified},
                        {"static_correction", e.staticCorrection},
                        {"modes_used", e.modesUsed},
                        {"times_s",
                         {{"contact", e.times.contactS},
                          {"prepare", e.times.prepareS},
                          {"modal", e.times.modalS},
                          {"stress", e.times.stressS},
                          {"propagation", e.times.propagationS},
                          {"surfaces", e.times.surfacesS},
                          {"matching", e.times.matchingS},
                          {"total", e.times.totalS()}}}};
    if (!e.error.empty()) j["error"] = e.error;
    doc["events"].push_back(std::move(j));
  }
  doc["frames"] = nlohmann::json::array();
  for (const FrameStats& f : r.frameStats) {
    if (framesEvery <= 0 || (f.frame % framesEvery != 0 && !f.fractured)) continue;
    doc["frames"].push_back({{"frame", f.frame},
                             {"time_s", f.timeS},
                             {"bodies", f.bodies},
                             {"bullet_s", f.bulletS},
                             {"fracture_s", f.fractureS},
                             {"energy_j", f.energyJ},
                             {"kinetic_j", f.kineticJ},
                             {"fractured", f.fractured}});
  }
  doc["bodies"] = nlohmann::json::array();
  for (const BodyState& b : r.bodies) {
    doc["bodies"].push_back({{"index", b.index},
                             {"name", b.name},
                             {"kind", bodyKindName(b.kind)},
                             {"parent", b.parent},
                             {"first_sample", b.firstFrame},
                             {"last_sample", b.lastFrame},
                             {"mass_kg", b.massKg},
                             {"lowest_point_m", b.lowestPointM}});
  }
  return doc;
}

void printPlaySummary(const PlayResult& r, std::ostream& out) {
  const FrameTimeSummary t = summarizeFrameTimes(r.frameStats);
  const double total = t.bulletS + t.fractureS;
  out << std::setprecision(4) << r.scene << " (seed " << r.seed << "): " << r.frames << " frames of " << 1e3 * r.timeStepS << " ms, "
      << r.impacts << " impacts (" << r.failedImpacts << " refused, " << r.deferredImpacts << " deferred), "
      << r.breaks << " breaks\n";
  {
    int64_t latencyMax = -1, applied = 0;
    double waitMax = 0.0;
    for (const ImpactEvent& e : r.events) {
      if (e.appliedFrame < 0) continue;
      ++applied;
      latencyMax = std::max(latencyMax, e.appliedFrame - e.frame);
      waitMax = std::max(waitMax, e.waitS);
    }
    if (applied > 0) {
      out << "  contact to fracture: " << latencyMax << " frames at most; longest wait for a result " << 1e3 * waitMax
          << " ms\n";
    }
  }
  if (r.budgetDeferredImpacts > 0 || r.simplifiedImpacts > 0) {
    out << "  frame budget: " << r.budgetDeferredImpacts << " step waits, " << r.simplifiedImpacts
        << " impacts simplified (no factorisation of K) after waiting\n";
  }
  out << "  bodies: " << (r.frameStats.empty() ? 0 : r.frameStats.front().bodies) << " at start, " << maxBodies(r)
      << " at most, " << r.bodiesAtEnd << " at end";
  if (!r.frequencySourcesAtEnd.empty()) {
    out << "; breakable ones' frequencies at the end:";
    for (const auto& [source, count] : r.frequencySourcesAtEnd)
      if (count > 0) out << " " << source << " " << count;
  }
  out << "\n";
  out << "  frame time (ms): median " << 1e3 * t.medianS << ", p99 " << 1e3 * t.p99S << ", max " << 1e3 * t.maxS
      << "; Bullet " << t.bulletS << " s, fracture " << t.fractureS << " s ("
      << (total > 0.0 ? 100.0 * t.fractureS / total : 0.0) << " % fracture); load " << r.loadS << " s\n";
  for (const ImpactEvent& e : r.events) {
    if (!e.broken && e.error.empty()) continue;
    out << "  t=" << std::setw(6) << e.timeS << " s  " << e.object << " at " << e.speedMps << " m/s: ";
    if (!e.error.empty()) out << "refused (" << e.error << ")\n";
    else out << e.fragments << " fragments (" << e.debris << " debris), " << 1e3 * e.times.totalS() << " ms\n";
  }
  out << "  pose hash " << fingerprintHex(r.poseHash) << "\n";
}

}  // namespace brittle
