// doasido hand import | check | mirror: bringing a new robot hand in (URDF
// or MJCF), checking a hand description before retargeting onto it, and
// making the other side's hand from it.
#include <cstdio>
#include <filesystem>
#include <memory>

#include "cli/commands.h"
#include "cli/hand_render.h"
#include "cli/output_options.h"
#include "core/error.h"
#include "stages/kinematic_stage.h"
#include "robot/hand_check.h"
#include "robot/hand_mirror.h"
#include "robot/urdf_import.h"

namespace doasido::cli {
namespace {

namespace fs = std::filesystem;
using retarget::HandCheck;
using retarget::HandChain;

std::string Body(const mjModel* m, int b) { return mj_id2name(m, mjOBJ_BODY, b) ? mj_id2name(m, mjOBJ_BODY, b) : "?"; }

void PrintChains(const HandCheck& c) {
  const mjModel* m = c.model.get();
  std::printf("palm: %s, wrist point at [%.4f %.4f %.4f] in its frame\n", Body(m, c.structure.palm).c_str(),
              c.structure.wrist_offset.x(), c.structure.wrist_offset.y(), c.structure.wrist_offset.z());
  std::printf("chains (found from the kinematic tree; thumb first):\n");
  for (const HandChain& ch : c.structure.chains) {
    std::string bodies;
    for (int b : ch.bodies) bodies += (bodies.empty() ? "" : " > ") + Body(m, b);
    std::printf("  %-7s %s\n          tip %s + [%.4f %.4f %.4f], knuckle joint %s\n", ch.finger.c_str(),
                bodies.c_str(), Body(m, ch.tip_body).c_str(), ch.tip_offset.x(), ch.tip_offset.y(),
                ch.tip_offset.z(), ch.flexion.empty() ? "-" : mj_id2name(m, mjOBJ_JOINT, ch.flexion.front()));
  }
  for (const std::string& note : c.structure.notes) std::printf("  (%s)\n", note.c_str());
}

std::string Interval(double lo, double hi) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "[%.3f, %.3f]", lo, hi);
  return buf;
}

void PrintJoints(const HandCheck& c) {
  std::printf("joints (range; actuator control range):\n");
  for (const retarget::JointReport& j : c.joints) {
    const std::string range = j.limited ? Interval(j.lo, j.hi) : "unlimited";
    const std::string act = j.actuator.empty() ? "no actuator"
                            : j.ctrl_limited   ? j.actuator + " " + Interval(j.ctrl_lo, j.ctrl_hi)
                                               : j.actuator + " (control unlimited)";
    std::printf("  %-7s %-22s %-18s %s\n", j.finger.empty() ? "-" : j.finger.c_str(), j.name.c_str(),
                range.c_str(), act.c_str());
  }
}

void PrintPoints(const HandCheck& c) {
  std::printf("description points (OpenPose keypoint -> body or site):\n");
  for (const retarget::EmbodimentPoint& p : c.embodiment.points) {
    std::printf("  %2d -> %-8s %-22s [%.4f %.4f %.4f] weight %.2f%s\n", p.keypoint,
                p.site.empty() ? "body" : "site", (p.site.empty() ? p.body : p.site).c_str(), p.pos[0],
                p.pos[1], p.pos[2], p.weight, p.fingertip ? " fingertip" : "");
  }
}

void AddImport(CLI::App& hand) {
  struct Options {
    std::string urdf, mjcf, out;
    bool force = false;
    retarget::HandImportOptions import;
  };
  auto opt = std::make_shared<Options>();
  auto* cmd = hand.add_subcommand(
      "import",
      "Make a robot hand usable: a URDF becomes an MJCF model (MuJoCo 2.2.2, no fused bodies, meshes\n"
      "copied or converted to OBJ, a position actuator per joint) plus a generated description; an\n"
      "MJCF hand gets the description");
  auto* urdf = cmd->add_option("--urdf", opt->urdf, "The hand's URDF (meshes: OBJ, STL; others converted)");
  auto* mjcf = cmd->add_option("--mjcf", opt->mjcf, "Or an MJCF hand (only the description is written)");
  urdf->excludes(mjcf);
  cmd->add_option("--out", opt->out, "Output folder (created)")->required();
  cmd->add_option("--side", opt->import.side, "right or left")
      ->check(CLI::IsMember({"right", "left"}))
      ->capture_default_str();
  cmd->add_option("--name", opt->import.name, "Name of the hand and its files (default: the file's stem)");
  AddForceFlag(*cmd, opt->force);
  cmd->footer(
      "Writes <out>/<name>.xml (MJCF), <out>/meshes/, <out>/<name>.json (the description: fingertips\n"
      "on the distal bodies, knuckles on the first flexion joints, the thumb as the chain opposing\n"
      "the others; edit it freely) and <out>/<name>.urdf (the URDF as MuJoCo read it).\n\n"
      "Examples:\n"
      "  doasido hand import --urdf robots/my_hand/urdf/my_hand.urdf --out robots/my_hand_mj\n"
      "  doasido hand check robots/my_hand_mj/my_hand.json\n"
      "  doasido retarget-kinematic --hand robots/my_hand_mj/my_hand.json \\\n"
      "      --keypoints ../shared/data/retarget/human_hand_keypoints_right.csv --out work/my_hand");
  cmd->callback([opt] {
    if (opt->urdf.empty() == opt->mjcf.empty()) {
      throw Error("bad_option", "give --urdf F or --mjcf F", {.field = "--urdf"});
    }
    const fs::path input = opt->urdf.empty() ? opt->mjcf : opt->urdf;
    CheckOutputPath({.path = opt->out,
                     .kind = OutputRequest::Kind::kFolder,
                     .what = "the imported hand",
                     .is_own_output = HoldsHandModel,
                     .force = opt->force,
                     .inputs = {input}});
    // Written whole: a killed import leaves the earlier hand or none.
    retarget::ImportedHand h;
    WriteWhole(opt->out, OutputKind::kFolder, [&](const fs::path& temp) {
      h = opt->urdf.empty() ? retarget::DescribeMjcf(opt->mjcf, temp, opt->import)
                            : retarget::ImportUrdf(opt->urdf, temp, opt->import);
    });
    h.description = fs::path(opt->out) / h.description.filename();
    if (!opt->urdf.empty()) h.mjcf = fs::path(opt->out) / h.mjcf.filename();
    for (const std::string& line : h.meshes) std::printf("mesh: %s\n", line.c_str());
    for (const std::string& line : h.warnings) std::printf("warning: %s\n", line.c_str());
    std::printf("model: %s\ndescription: %s (%zu points, %zu fingers)\n", h.mjcf.c_str(),
                h.description.c_str(), h.described.embodiment.points.size(), h.structure.chains.size());
    for (const HandChain& ch : h.structure.chains) {
      std::printf("  %-7s %zu joints, %zu flexing\n", ch.finger.c_str(), ch.joints.size(), ch.flexion.size());
    }
    std::printf("next: doasido hand check %s\n", h.description.c_str());
  });
}

struct CheckOptions {
  std::string hand, robots_dir, out;
  bool no_pictures = false;
  bool force = false;
};

// Where `hand check` draws one picture of `hand`: checked like every
// output (an earlier picture is replaced only with --force).
fs::path PicturePath(const CheckOptions& o, const retarget::Embodiment& hand, const std::string& suffix) {
  const fs::path dir = o.out.empty() ? fs::current_path() : fs::path(o.out);
  const std::string option = o.out.empty() ? "the current folder" : "--out";
  // The folder may hold anything else; it must not be a protected place.
  CheckOutputPath({.path = dir,
                   .kind = OutputRequest::Kind::kFolder,
                   .option = option,
                   .what = "the hand's pictures",
                   .is_own_output = [](const fs::path&) { return true; },
                   .force = true});
  const fs::path file = dir / (hand.name + suffix);
  CheckOutputPath({.path = file,
                   .kind = OutputRequest::Kind::kFile,
                   .option = option,
                   .what = "the hand's picture",
                   .is_own_output = [](const fs::path& p) { return FileStartsWith(p, "\x89PNG"); },
                   .force = o.force,
                   .inputs = {hand.model_path}});
  fs::create_directories(dir);
  return file;
}

void AddCheck(CLI::App& hand) {
  using Options = CheckOptions;
  auto opt = std::make_shared<Options>();
  auto* cmd = hand.add_subcommand(
      "check",
      "Check a hand description: print the chains found in its model, every joint's range and\n"
      "actuator, the description's points, draw the hand at rest and with all fingers flexed, and\n"
      "name every problem (body missing, joint without limits, actuator out of range, fingertip\n"
      "off a chain's end, thumb on the wrong chain). Exits 1 when there is a problem");
  cmd->add_option("hand", opt->hand, "Description .json, or a built-in name (sharpa_right, shadow, allegro)")
      ->required();
  cmd->add_option("--robots-dir", opt->robots_dir, "Folder of robot models descriptions refer to");
  cmd->add_option("--out", opt->out, "Folder for <name>_rest.png and <name>_flexed.png (default: the current one)");
  cmd->add_flag("--no-pictures", opt->no_pictures, "Skip the pictures");
  AddForceFlag(*cmd, opt->force);
  cmd->footer("Examples:\n"
              "  doasido hand check robots/my_hand_mj/my_hand.json --out work/pictures\n"
              "  doasido hand check allegro");
  cmd->callback([opt] {
    const std::string robots = opt->robots_dir.empty() ? retarget::DefaultRobotsDir() : opt->robots_dir;
    const HandCheck c = retarget::CheckHand(retarget::FindEmbodiment(opt->hand, robots));
    std::printf("hand %s (%s), model %s\n", c.embodiment.name.c_str(), c.embodiment.side.c_str(),
                c.embodiment.model_path.c_str());
    PrintChains(c);
    PrintJoints(c);
    PrintPoints(c);
    if (!opt->no_pictures) {
      const mjModel* m = c.model.get();
      const fs::path rest = PicturePath(*opt, c.embodiment, "_rest.png");
      const fs::path flexed = PicturePath(*opt, c.embodiment, "_flexed.png");
      RenderHandPng(c, Eigen::Map<const Eigen::VectorXd>(m->qpos0, m->nq), rest);
      RenderHandPng(c, retarget::FlexedPose(m, c.structure, 0.8), flexed);
      std::printf("pictures: %s %s\n", rest.c_str(), flexed.c_str());
    }
    if (c.problems.empty()) {
      std::printf("problems: none\n");
      return;
    }
    std::printf("problems:\n");
    for (const retarget::HandProblem& p : c.problems) std::printf("  %s: %s\n", p.code.c_str(), p.message.c_str());
    throw Error("hand_problems", std::to_string(c.problems.size()) + " problem(s) in the hand description; "
                "see above", {.file = c.embodiment.model_path.string()});
  });
}

void AddMirror(CLI::App& hand) {
  struct Options {
    std::string hand, robots_dir, out, name;
    char axis = 'y';
    bool force = false;
  };
  auto opt = std::make_shared<Options>();
  auto* cmd = hand.add_subcommand(
      "mirror",
      "Make the other side's hand: the model reflected through a plane (positions, orientations,\n"
      "joint axes so that flexion stays positive, inertias, mesh scales) and the description with it\n"
      "(points' offsets reflected, side swapped), then checked like `doasido hand check`. Exits 1\n"
      "when the mirrored hand has a problem");
  cmd->add_option("hand", opt->hand, "Description .json, or a built-in name (sharpa_right, shadow, allegro)")
      ->required();
  cmd->add_option("--out", opt->out, "Output folder (created)")->required();
  cmd->add_option("--name", opt->name, "Name of the mirrored hand and its files (default: right and left swapped)");
  cmd->add_option("--axis", opt->axis, "The axis the reflection flips, in the model's frame")
      ->check(CLI::IsMember({'x', 'y', 'z'}))
      ->capture_default_str();
  cmd->add_option("--robots-dir", opt->robots_dir, "Folder of robot models descriptions refer to");
  AddForceFlag(*cmd, opt->force);
  cmd->footer("Writes <out>/<name>.xml (one self-contained MJCF; meshes stay where they are, scaled by -1\n"
              "along the axis) and <out>/<name>.json. Mirroring the result again gives the original.\n\n"
              "Examples:\n"
              "  doasido hand mirror shadow --out robots/shadow_left\n"
              "  doasido hand mirror robots/my_hand_mj/my_hand.json --out robots/my_hand_left --name my_hand_left\n"
              "  doasido hand check robots/shadow_left/shadow_left.json");
  cmd->callback([opt] {
    const std::string robots = opt->robots_dir.empty() ? retarget::DefaultRobotsDir() : opt->robots_dir;
    const retarget::Embodiment source = retarget::FindEmbodiment(opt->hand, robots);
    CheckOutputPath({.path = opt->out,
                     .kind = OutputRequest::Kind::kFolder,
                     .what = "the mirrored hand",
                     .is_own_output = HoldsHandModel,
                     .force = opt->force,
                     .inputs = {source.model_path}});
    // Written whole: a killed mirror leaves the earlier hand or none.
    retarget::MirroredHand m;
    WriteWhole(opt->out, OutputKind::kFolder, [&](const fs::path& temp) {
      m = retarget::MirrorHand(source, temp, {.axis = opt->axis, .name = opt->name});
    });
    m.model = fs::path(opt->out) / m.model.filename();
    m.description = fs::path(opt->out) / m.description.filename();
    m.embodiment.model_path = fs::absolute(m.model);
    std::printf("%s (%s) mirrored through %c = 0: %s (%s)\nmodel: %s\ndescription: %s (%zu points)\n",
                source.name.c_str(), source.side.c_str(), opt->axis, m.embodiment.name.c_str(),
                m.embodiment.side.c_str(), m.model.c_str(), m.description.c_str(), m.embodiment.points.size());
    const HandCheck c = retarget::CheckHand(m.description);
    PrintChains(c);
    if (c.problems.empty()) {
      std::printf("problems: none\n");
      return;
    }
    for (const retarget::HandProblem& p : c.problems) std::printf("  %s: %s\n", p.code.c_str(), p.message.c_str());
    throw Error("hand_problems", std::to_string(c.problems.size()) + " problem(s) in the mirrored hand; see above",
                {.file = m.description.string()});
  });
}

}  // namespace

void AddHandCommand(CLI::App& app) {
  auto* hand = app.add_subcommand(
      "hand", "Bring your own robot hand: import a URDF or MJCF, check a description, mirror it to the other side");
  hand->require_subcommand(1);
  hand->footer("Run `doasido hand import --help`, `doasido hand check --help` and `doasido hand mirror --help`.");
  AddImport(*hand);
  AddCheck(*hand);
  AddMirror(*hand);
}

}  // namespace doasido::cli
