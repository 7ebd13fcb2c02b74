// The rendered synthetic clip the reconstruction-side stage tests share:
// 240 x 180, 24 frames, seed 3, no defect, so its bundle is exact (object
// poses, masks, point tracks) beside pose candidates with flips and
// outliers, and its frames are the video's.
#pragma once

#include "synth/generator.h"

namespace doasido::testing {

inline const synth::RenderedClip& SmallClip() {
  static const synth::RenderedClip clip = [] {
    synth::SynthConfig cfg;
    cfg.width = 240;
    cfg.height = 180;
    cfg.frames = 24;
    cfg.seed = 3;
    return synth::RenderClip(cfg, 0, synth::DefectKind::kClean);
  }();
  return clip;
}

}  // namespace doasido::testing
