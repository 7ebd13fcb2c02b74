// Valid ranges of the report's options (the [report] config table).
#include "core/config_check.h"
#include "reports/report_data.h"
#include "reports/thumbnails.h"

namespace doasido::reports {

void CheckConfig(const ThumbnailOptions& c, const std::string& section) {
  RequireInRange(section, "max_per_reason", c.max_per_reason, 0, 1000);
  RequireInRange(section, "panel_height", c.panel_height, 16, 4096);  // pixels
  RequireInRange(section, "jpeg_quality", c.jpeg_quality, 0, 100);
  RequireInRange(section, "analysis_size", c.analysis_size, 0, 8192);  // 0: full size
  RequireInRange(section, "box_search_frames", c.box_search_frames, 0, 1e6);
}

void CheckConfig(const ReportOptions& c, const std::string& section) {
  RequireInRange(section, "histogram_bins", c.histogram_bins, 1, 1000);
  RequireInRange(section, "max_failures", c.max_failures, 0, 1e6);
  CheckConfig(c.thumbnail, section + ".thumbnail");
}

}  // namespace doasido::reports
