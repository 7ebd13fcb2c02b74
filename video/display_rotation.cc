#include "video/display_rotation.h"

#include <cmath>

extern "C" {
#include <libavformat/avformat.h>
#include <libavutil/display.h>
}

namespace doasido {

int DisplayRotation(const AVStream* stream) {
  const uint8_t* matrix = av_stream_get_side_data(stream, AV_PKT_DATA_DISPLAYMATRIX, nullptr);
  if (!matrix) return 0;
  const double theta = av_display_rotation_get(reinterpret_cast<const int32_t*>(matrix));
  if (!std::isfinite(theta)) return 0;
  int deg = static_cast<int>(std::lround(theta)) % 360;
  return deg < 0 ? deg + 360 : deg;
}

}  // namespace doasido
