// brittle play — play a scene with a pack's objects in Bullet; print and write the statistics.
#include <fstream>
#include <iostream>
#include <limits>
#include <nlohmann/json.hpp>

#include "CliSupport.h"
#include "Commands.h"
#include "brittle/database/Pack.h"
#include "brittle/player/GltfReplay.h"
#include "brittle/player/PlayReport.h"
#include "brittle/player/Player.h"
#include "brittle/player/Scene.h"

namespace brittle::cli {

// play --frames: the play frame by frame, every N-th frame drawn into a PNG (ViewCommand.cpp).
Result<PlayResult> playWithFrames(Pack pack, const Scene& scene, const PlayerSettings& settings,
                                  const std::string& dir, int every, const std::string& size);
namespace {

struct PlayOptions {
  std::string pack, scene, outStats, outReplay;
  PlayerSettings settings;
  int framesEvery = 10;
  int modes = 0;
  std::string runtimeSettings;
  double frameBudgetMs = 0.0;
  std::string framesDir, frameSize = "960x540";
  int frameEvery = 1;
  int64_t seed = -1;  // the scene's
  bool json = false;
};

}  // namespace

Runner addPlayCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("play", "Play a scene: a Bullet simulation whose hard contacts break the pack's objects");
  auto o = std::make_shared<PlayOptions>();
  cmd->add_option("pack", o->pack, "Pack (.h5)")->required();
  cmd->add_option("scene", o->scene, "Scene (.json, see assets/scenes/)")->required();
  cmd->add_flag("--json", o->json, "Print the statistics as JSON");
  cmd->add_option("--out-stats", o->outStats, "Also write the JSON statistics to this file");
  cmd->add_option("--out", o->outReplay, "Write a glTF 2.0 binary replay (.glb): one node per body, animated per frame");
  cmd->add_option("--frames-every", o->framesEvery, "List every N-th frame in the JSON (frames with a break always; 0: none)")
      ->capture_default_str()->check(CLI::NonNegativeNumber);
  cmd->add_option("--threshold", o->settings.impactThresholdMps, "Normal approach speed that makes a contact an impact (m/s)")
      ->capture_default_str()->check(CLI::PositiveNumber);
  cmd->add_option("--cooldown", o->settings.cooldownS, "A body ignores contacts this long after an impact (s)")
      ->capture_default_str()->check(CLI::NonNegativeNumber);
  cmd->add_option("--max-impacts", o->settings.maxImpactsPerStep, "Impacts computed per step; the others wait")
      ->capture_default_str()->check(CLI::Range(1, 1000000));
  cmd->add_option("--modes", o->modes, "Modes used per impact (0: all stored)")->capture_default_str()->check(CLI::NonNegativeNumber);
  cmd->add_option("--debris", o->settings.world.fracture.debrisVolumeFraction, "Fragments below this volume fraction are rigid debris")
      ->capture_default_str()->check(CLI::Range(0.0, 0.99));
  cmd->add_option("--frame-budget-ms", o->frameBudgetMs,
                  "Wall-clock fracture time per frame; impacts beyond it wait, and run simplified after --max-budget-waits "
                  "steps (0: no budget; a budget makes the play depend on the machine's speed)")
      ->capture_default_str()->check(CLI::NonNegativeNumber);
  cmd->add_option("--max-budget-waits", o->settings.maxBudgetWaits, "Steps an impact may wait for the frame budget")
      ->capture_default_str()->check(CLI::NonNegativeNumber);
  cmd->add_flag("--real-time", o->settings.realTime,
               "Pace the frames in wall time, as a host would (workers get the time between an impact and its frame)");
  cmd->add_option("--latency-frames", o->settings.fractureLatencyFrames,
                  "Frames from a contact to its fracture, computed on worker threads meanwhile (0: at once, on the "
                  "player's thread; -1: the frames nearest to 33 ms)")
      ->capture_default_str()->check(CLI::Range(-1, 600));
  cmd->add_option("--prepare-entries", o->settings.world.prepareEntryCorrections,
                  "Database entries whose static corrections are factorised when an object is placed, so that matched "
                  "pieces need none (about 6 ms of background work and 1.8 MB each; 0: each on first use)")
      ->capture_default_str()->check(CLI::NonNegativeNumber);
  cmd->add_option("--kept-entries", o->settings.world.entryCacheCapacity,
                  "Matched database entries whose shared data (connectivity, basis, static correction) the World "
                  "keeps, the least recently matched dropped first (0: no bound); at least --prepare-entries")
      ->capture_default_str()->check(CLI::NonNegativeNumber);
  cmd->add_option("--hull-vertices", o->settings.hullMaxVertices,
                  "Most vertices of a fragment's collision hull: its extreme vertices in this many directions (0: the exact hull)")
      ->capture_default_str()->check(CLI::Range(0, 4096));
  cmd->add_option("--seed", o->seed,
                  "The World's seed in place of the scene's: the cracks draw from it, so the same scene plays another "
                  "fracture history, itself bit-identical from run to run (default: the scene's \"seed\")")
      ->check(CLI::Range(int64_t{0}, std::numeric_limits<int64_t>::max()));
  cmd->add_option("--settings", o->runtimeSettings, "Runtime settings (JSON, as brittle size writes them); flags given here win");
  cmd->add_option("--frames", o->framesDir, "Also draw frames into this directory (frame_NNNNNN.png; needs a display: xvfb-run)");
  cmd->add_option("--frame-every", o->frameEvery, "Draw every N-th frame")->capture_default_str()->check(CLI::PositiveNumber);
  cmd->add_option("--frame-size", o->frameSize, "Size of the drawn frames, WxH")->capture_default_str();

  return [o, cmd]() -> int {
    auto scene = loadScene(o->scene);
    if (!scene) return reportError(scene.error());
    if (o->seed >= 0) scene.value().seed = static_cast<uint64_t>(o->seed);
    auto pack = readPack(o->pack, EntryReading::OnDemand);  // a World reads entries as it matches them
    if (!pack) return reportError(pack.error());
    o->settings.world.fracture.modeCount = o->modes;
    o->settings.fractureBudgetS = 1e-3 * o->frameBudgetMs;
    if (!o->runtimeSettings.empty()) {
      if (Status st = applyRuntimeSettingsFile(o->runtimeSettings, *cmd, o->settings.world.fracture); !st) return reportError(st.error());
    }
    o->settings.recordTracks = !o->outReplay.empty();
    Result<PlayResult> played = makeError(ErrorCode::InvalidArgument, "not played");
    if (o->framesDir.empty()) {
      played = playScene(std::move(pack).value(), scene.value(), o->settings);
    } else {
      auto frames = playWithFrames(std::move(pack).value(), scene.value(), o->settings, o->framesDir, o->frameEvery, o->frameSize);
      if (!frames) return reportError(frames.error());
      played = std::move(frames).value();
    }
    if (!played) return reportError(played.error());
    const nlohmann::json doc = playReportJson(played.value(), o->framesEvery);
    if (!o->outStats.empty()) {
      std::ofstream file(o->outStats);
      file << doc.dump(2) << "\n";
      if (!file) return reportError(makeError(ErrorCode::PackIoError, "cannot write " + o->outStats));
    }
    if (!o->outReplay.empty()) {
      if (Status st = writeGltfReplay(played.value(), o->outReplay); !st) return reportError(st.error());
    }
    if (o->json) std::cout << doc.dump(2) << "\n";
    else printPlaySummary(played.value(), std::cout);
    return kExitOk;
  };
}

}  // namespace brittle::cli
