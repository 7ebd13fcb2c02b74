// The style shared by the review and verify pages (pages.h).
#include "review/pages.h"

namespace doasido::review {

const char* const kDecisionPageStyle = R"css(
* { box-sizing: border-box; }
body { margin: 0; font: 14px/1.4 system-ui, sans-serif; background: #15171c; color: #e4e6eb; }
header { display: flex; gap: 16px; align-items: center; padding: 8px 16px; background: #1f232b;
         border-bottom: 1px solid #333a45; }
header h1 { font-size: 16px; margin: 0; }
header .grow { flex: 1; }
input, select, textarea, button { font: inherit; color: inherit; background: #262b35;
  border: 1px solid #3b4350; border-radius: 4px; padding: 4px 8px; }
button.accept { background: #1f6f3f; border-color: #2c9a58; }
button.reject { background: #7a2630; border-color: #a8394a; }
)css";

}  // namespace doasido::review
