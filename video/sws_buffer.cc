#include "video/sws_buffer.h"

#include <cstddef>

namespace doasido {

void EnsureSwsOutput(cv::Mat* m, int rows, int cols) {
  constexpr std::ptrdiff_t kSpare = 256;
  // A view of whole rows stays continuous (its dataend is the buffer's, so
  // the room is measured from the last row).
  if (m->rows == rows && m->cols == cols && m->type() == CV_8UC3 && m->isContinuous() &&
      m->datalimit - (m->data + m->total() * 3) >= kSpare) {
    return;
  }
  const int spare_rows = static_cast<int>(kSpare / (3 * cols)) + 1;
  *m = cv::Mat(rows + spare_rows, cols, CV_8UC3).rowRange(0, rows);
}

}  // namespace doasido
