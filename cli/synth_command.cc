#include <cstdio>
#include <filesystem>

#include "cli/commands.h"
#include "cli/option_checks.h"
#include "cli/output_options.h"
#include "core/progress.h"
#include "synth/generator.h"

namespace doasido::cli {

void AddSynthCommand(CLI::App& app) {
  auto cfg = std::make_shared<synth::SynthConfig>();
  auto out = std::make_shared<std::string>();
  auto flags = std::make_shared<std::pair<bool, bool>>(false, false);
  auto force = std::make_shared<bool>(false);
  auto* cmd = app.add_subcommand(
      "synth",
      "Render synthetic hand-object clips with exact ground truth and injected defects\n"
      "(cuts, fades, camera pan/shake/zoom, out-of-frame, no contact, static): videos,\n"
      "a clip list for `doasido ingest`, 100DOH-style VOC boxes, clip bundles and a\n"
      "per-clip ground-truth JSON");
  cmd->add_option("--out", *out, "Output folder (created)")->required();
  cmd->add_option("--clips", cfg->clips, "Number of clips")->check(FiniteRange(1, 1000000.0))->capture_default_str();
  cmd->add_option("--seed", cfg->seed, "Random seed; same seed, same files")->capture_default_str();
  cmd->add_option("--mix", cfg->mix,
                  "Defect mix as kind=weight,... Kinds: clean, cut, fade, black, pan, shake, "
                  "zoom, out_of_frame, object_out, no_contact, static")
      ->capture_default_str();
  cmd->add_option("--width", cfg->width, "Frame width in pixels")->check(FiniteRange(64, 8192))->capture_default_str();
  cmd->add_option("--height", cfg->height, "Frame height in pixels")->check(FiniteRange(48, 8192))->capture_default_str();
  cmd->add_option("--frames", cfg->frames, "Frames per clip (>= 24)")->check(FiniteRange(24, 1000000.0))->capture_default_str();
  cmd->add_option("--fps", cfg->fps, "Frame rate of the videos")->capture_default_str();
  cmd->add_option("--meshes", cfg->mesh_dir,
                  "Folder of object meshes (.obj/.ply/.glb/.stl, metres) to draw objects from "
                  "besides the built-in box, cylinder, sphere and mug");
  cmd->add_option("--two-hand-task", cfg->two_hand_task,
                  "Every clip a task for both hands: handover, carry or hold_and_act (exact contact per hand)")
      ->check(CLI::IsMember({"none", "handover", "carry", "hold_and_act"}))
      ->capture_default_str();
  cmd->add_option("--grasp", cfg->grasp,
                  "How the hand holds the object: wrap (palm and fingers round it) or pinch (thumb against "
                  "index and middle, a grasp a robot hand can lift with)")
      ->check(CLI::IsMember({"wrap", "pinch"}))
      ->capture_default_str();
  cmd->add_option("--png-every", cfg->png_every,
                  "Also write every n-th frame as PNG under <out>/png (0: none)")->check(FiniteRange(0, 1000000.0))
      ->capture_default_str();
  AddForceFlag(*cmd, *force);
  cmd->add_flag("--no-bundles", flags->first, "Skip the clip bundles (ground truth folders)");
  cmd->add_flag("--no-annotations", flags->second, "Skip the VOC annotation folder");
  cmd->add_flag("--point-maps", cfg->point_maps,
                "Also write per-frame point maps (points/%06d.exr) into the bundles");
  cmd->add_flag("--model-bundles", cfg->model_bundles,
                "Also write <out>/model_bundles/: bundles with MoGe-like depth and HaWoR-like "
                "hand noise");
  cmd->footer(
      "Writes <out>/videos/*.mp4, <out>/clips.csv, <out>/Annotations/*.xml,\n"
      "<out>/bundles/<clip>/, <out>/gt/<clip>.json and <out>/summary.json.\n\n"
      "Example:\n"
      "  doasido synth --out work/synth --clips 20 --seed 7 \\\n"
      "      --mix clean=0.4,cut=0.1,fade=0.1,pan=0.1,out_of_frame=0.1,no_contact=0.1,static=0.1\n"
      "  doasido ingest --db work/doasido.db work/synth/clips.csv");
  cmd->callback([cfg, out, flags, force] {
    CheckOutputPath({.path = *out,
                     .kind = OutputRequest::Kind::kFolder,
                     .what = "the synthetic clips",
                     .is_own_output = FolderHolds({"summary.json", "clips.csv"}),
                     .force = *force});
    cfg->write_bundles = !flags->first;
    cfg->write_annotations = !flags->second;
    Progress progress("synth", static_cast<std::uint64_t>(std::max(cfg->clips, 0)));
    // Written whole: a killed synth leaves the earlier clips or none.
    synth::DatasetSummary summary;
    WriteWhole(*out, OutputKind::kFolder, [&](const std::filesystem::path& temp) {
      summary = synth::GenerateDataset(
          *cfg, temp, [&](int done) { progress.Set(static_cast<std::uint64_t>(done)); });
    });
    progress.Finish();
    std::string mix;
    for (const auto& [kind, n] : summary.defect_counts) {
      mix += (mix.empty() ? "" : ", ") + kind + " " + std::to_string(n);
    }
    std::printf("%s: %d clips (%s)\n", out->c_str(), summary.clips, mix.c_str());
  });
}

}  // namespace doasido::cli
