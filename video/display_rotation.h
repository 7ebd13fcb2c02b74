// The display rotation a container asks for (a display matrix on the video
// stream): the matrix's counter-clockwise angle in [0, 360), the number
// OpenCV reports as CAP_PROP_ORIENTATION_META. Players, browsers and ffmpeg
// show the frames turned counter-clockwise by it, and so does the decoder
// here (checked against ffmpeg's own decode in tests/video_probe_test.cc).
#pragma once

struct AVStream;

namespace doasido {

// 0 without a display matrix.
int DisplayRotation(const AVStream* stream);

}  // namespace doasido
