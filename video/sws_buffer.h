// A BGR image libswscale may write into.
#pragma once

#include <opencv2/core.hpp>

namespace doasido {

// Makes `m` a CV_8UC3 image of `rows` x `cols` that libswscale can write:
// its vector code may store past the end of the last output row (24 bytes
// behind 568-pixel BGR rows, found as heap corruption on yoga.mp4), so the
// image is a view of the first rows of a buffer with spare bytes behind
// it. Keeps `m` when it already is one.
void EnsureSwsOutput(cv::Mat* m, int rows, int cols);

}  // namespace doasido
