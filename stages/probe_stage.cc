#include "stages/probe_stage.h"

#include "core/error.h"

namespace doasido::stages {

using namespace video;  // the algorithms this stage runs

StageResult ProbeStage::Run(const ClipContext& context) {
  VideoInfo info;
  try {
    info = ProbeVideo(context.video.path, config_);
  } catch (const Error& e) {
    ErrorSite site = e.site();
    site.clip = context.clip.external_id.empty() ? std::to_string(context.clip.id)
                                                 : context.clip.external_id;
    throw Error(e.code(), e.message(), site);
  }
  StageResult result;
  result.video_info = info;
  result.measurements = {{"width", info.width},
                         {"height", info.height},
                         {"fps", info.fps},
                         {"frame_count", info.frame_count},
                         {"duration_s", info.duration_s},
                         {"variable_frame_rate", info.variable_frame_rate},
                         {"rotation_deg", info.rotation_deg},
                         {"codec", info.codec}};
  const auto& clip = context.clip;
  if (clip.end_frame && *clip.end_frame >= info.frame_count) {
    result.verdict = Verdict::kReject;
    result.reason = kReasonSpanOutsideVideo;
    result.measurements["note"] = "end_frame " + std::to_string(*clip.end_frame) +
                                  " is past the last frame " +
                                  std::to_string(info.frame_count - 1);
  } else if (clip.end_s && *clip.end_s > info.duration_s + 1.0 / info.fps) {
    result.verdict = Verdict::kReject;
    result.reason = kReasonSpanOutsideVideo;
  }
  return result;
}

}  // namespace doasido::stages
