// The image of a labelled photo where a package installed it (issue 54): the
// photos labelled by hand (bench/hand_labels/photos/*.json, field "video")
// are never committed, but named where scripts/setup.sh's test set puts them:
//   "/usr/share/.../x.jpg"          a file (a Debian package's)
//   "npm:<package>/<path>"          a file of a pinned npm package in NpmDir()
//   "<file>.rcc:/<path>"            an entry of a Qt resource file (GCompris
//                                   ships its pictures so, uncompressed)
#pragma once

#include <string>

#include <opencv2/core.hpp>

namespace doasido::hands {

// The image as BGR, an alpha channel composited over white (a cut-out hand
// as its program shows it). Empty when it cannot be read; then *why (when
// given) says why (missing file, no such entry, a compressed entry).
cv::Mat ReadPackagedImage(const std::string& where, std::string* why = nullptr);

}  // namespace doasido::hands
