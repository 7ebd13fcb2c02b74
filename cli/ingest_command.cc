#include <filesystem>

#include "cli/commands.h"
#include "cli/option_checks.h"
#include "cli/ingest_options.h"
#include "stages/stage_registry.h"
#include "db/database.h"
#include "pipeline/ingest.h"

namespace doasido::cli {

void AddIngestOptions(CLI::App& cmd, IngestOptions& opt) {
  cmd.add_option("lists", opt.lists,
                 "Clip lists: CSV/TSV/JSONL files, EPIC-KITCHENS CSVs, 100DOH VOC folders or "
                 "text files of 100DOH frame names");
  cmd.add_option("--video-info", opt.list.epic_video_info,
                 "EPIC: EPIC_100_video_info.csv (default: beside the list)");
  cmd.add_option("--video-root", opt.list.epic_video_root,
                 "EPIC: folder with <participant>/videos/<video>.MP4 (default: videos/ beside "
                 "the list)");
  cmd.add_option("--video-dir", opt.list.voc_video_dir,
                 "VOC / frame names: folder with <video id>.mp4 (default: videos/ beside "
                 "Annotations)");
  cmd.add_option("--frame-scale", opt.list.voc_frame_scale,
                 "VOC / frame names: multiply annotated frame numbers by this to get video "
                 "frames")->check(FiniteRange(1e-06, 1000000.0))
      ->capture_default_str();
  cmd.add_option("--video-url-template", opt.list.video_url_template,
                 "VOC / frame names / JSON id maps: URL of a video id, {id} replaced, for "
                 "videos not in the video folder (JSON id maps default to "
                 "https://www.youtube.com/watch?v={id}); the download stage fetches them");
  cmd.add_flag("!--no-check-files", opt.list.check_files,
               "Accept CSV/TSV/JSONL rows whose local video file does not exist");
}

bool IngestLists(Database& db, const IngestOptions& opt) {
  if (db.Pipeline().empty()) {
    const auto stages = stages::DefaultPipeline();
    db.SetPipeline(stages, stages::FlagContinuingStages(stages));
  }
  Json all = Json::array();
  bool ok = true;
  for (const auto& list : opt.lists) {
    try {
      const auto s = pipeline::IngestList(db, list, opt.list);
      if (opt.json) {
        all.push_back(s.ToJson());
        continue;
      }
      std::printf("%s (%s): %lld rows, %lld new clips, %lld already present, %zu bad rows",
                  list.c_str(), s.format.c_str(), static_cast<long long>(s.rows),
                  static_cast<long long>(s.inserted), static_cast<long long>(s.already_present),
                  s.errors.size());
      if (!s.errors.empty()) {
        std::string fields;
        for (const auto& [field, n] : s.RefusedByField()) {
          fields += (fields.empty() ? "" : ", ") + field + " " + std::to_string(n);
        }
        std::printf(" (%s)", fields.c_str());
      }
      if (s.detections > 0) std::printf(", %lld detections", static_cast<long long>(s.detections));
      std::printf(" (%.1fs)\n", s.seconds);
      for (size_t i = 0; i < s.errors.size(); ++i) {
        if (static_cast<int>(i) == opt.max_errors_shown) {
          std::printf("  ... %zu more bad rows (use --json for all)\n", s.errors.size() - i);
          break;
        }
        std::printf("  bad row: %s\n", s.errors[i].Format().c_str());
      }
    } catch (const Error& e) {
      ok = false;
      std::fprintf(stderr, "error: %s\n", e.what());
      if (opt.json) all.push_back({{"list", list}, {"error", e.what()}});
    }
  }
  if (opt.json) std::printf("%s\n", all.dump(2).c_str());
  return ok;
}

void AddIngestCommand(CLI::App& app) {
  struct Options {
    DbOptions db;
    IngestOptions ingest;
  };
  auto opt = std::make_shared<Options>();
  auto* cmd = app.add_subcommand(
      "ingest", "Add the clips of one or more lists to the queue (idempotent: the same video and "
                "span is the same clip)");
  AddDbOptions(*cmd, opt->db);
  AddIngestOptions(*cmd, opt->ingest);
  cmd->add_flag("--json", opt->ingest.json, "Print the summary, with every bad row, as JSON");
  cmd->footer(
      "A bad row (missing column, bad timestamp, end before start, missing file, duplicate, "
      "...) is reported with its file, line and field; the other rows are ingested. "
      "A file that is not a clip list at all is refused whole (exit code 1), saying what was "
      "expected.\n\n"
      "Videos named by URL are fetched by the `download` stage (first in the default pipeline) "
      "into <db folder>/media; YouTube and other sites go through its command template "
      "(e.g. yt-dlp; see README).\n\n"
      "Examples:\n"
      "  doasido ingest --db work/doasido.db clips.csv\n"
      "  doasido ingest --db work/doasido.db EPIC_100_validation.csv --video-root /data/EPIC\n"
      "  doasido ingest --db work/doasido.db 100doh/ --video-dir 100doh/videos --frame-scale 60\n"
      "  doasido ingest --db work/doasido.db frames.txt "
      "--video-url-template 'https://www.youtube.com/watch?v={id}'\n"
      "  doasido ingest --db work/doasido.db whim_train.json   # {\"<youtubeId>\": {...}, ...}");
  cmd->callback([opt] {
    if (opt->ingest.lists.empty()) throw Error("usage", "give at least one list to ingest");
    Database db(opt->db.db);
    if (!IngestLists(db, opt->ingest)) throw Error("ingest", "some lists could not be read");
  });
}

}  // namespace doasido::cli
