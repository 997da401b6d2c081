// PlayReport.h — what `brittle play` prints: the JSON statistics document and the short summary.
//
// JSON (times in seconds, SI units):
//   { "scene", "frame_count", "time_step_s", "load_s",
//     "summary": { "impacts", "breaks", "deferred_impacts", "budget_deferred_impacts",
//                  "simplified_impacts", "failed_impacts", "bodies_at_end",
//                  "bodies_max", "pose_hash" (16 hex digits), "frequency_sources_at_end" ({"own": n,
//                  "entry", "ritz", "checked", "checked_p2"}: live breakable bodies by the source of
//                  their frequencies at the scene's end, World::frequencyError),
//                  "frame_time_s": { "median", "p99", "max" }, "bullet_s", "fracture_s",
//                  "fracture_share" (fracture / (bullet + fracture)) },
//     "events": [ { "time_s", "frame", "body", "object", "other_body" (−1: the floor), "speed_mps",
//                   "other_mass_kg" ("inf" if static), "broken", "fragments", "debris",
//                   "peak_principal_stress_pa", "waited_steps", "simplified", "static_correction",
//                   "modes_used",
//                   "times_s": { "contact", "prepare", "modal",
//                   "stress", "propagation", "surfaces", "matching", "total" }, "error"? } ],
//     "frames": [ { "frame", "time_s", "bodies", "bullet_s", "fracture_s", "energy_j", "kinetic_j",
//                   "fractured" } ]   // every N-th frame and every frame with a break
//     "bodies": [ { "index", "name", "kind", "parent", "first_sample", "last_sample", "mass_kg",
//                   "lowest_point_m" } ] }
#pragma once

#include <nlohmann/json.hpp>
#include <ostream>

#include "brittle/player/Player.h"

namespace brittle {

/// The statistics document; framesEvery ≥ 1 selects which frames are listed (0: none).
nlohmann::json playReportJson(const PlayResult& result, int framesEvery = 1);

/// A few lines: counts, bodies, frame times, the share of fracture.
void printPlaySummary(const PlayResult& result, std::ostream& out);

}  // namespace brittle
