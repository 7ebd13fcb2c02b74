#include "reports/report.h"

#include <fstream>

#include "core/error.h"
#include "reports/html_report.h"
#include "reports/report_files.h"

namespace doasido::reports {
namespace {

void WriteText(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
  out.close();
  if (!out) throw Error("io", "cannot write report file", {.file = path.string()});
}

}  // namespace

ReportOutput WriteReport(Database& db, const std::filesystem::path& out_dir,
                         const ReportOptions& options) {
  std::error_code ec;
  std::filesystem::create_directories(out_dir, ec);
  if (ec) throw Error("io", "cannot create report folder: " + ec.message(),
                      {.file = out_dir.string()});
  ReportOutput out;
  out.data = CollectReport(db, options);
  if (options.thumbnails) AddThumbnails(db, out.data, options);
  out.html = out_dir / "report.html";
  out.json = out_dir / "report.json";
  WriteText(out.html, RenderHtml(out.data));
  WriteText(out.json, ReportToJson(out.data).dump(2) + "\n");
  out.csv = WriteCsvFiles(out.data, out_dir);
  return out;
}

}  // namespace doasido::reports
