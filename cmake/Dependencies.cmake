# Every third-party library doasido uses, all from Debian 12 packages
# (scripts/setup.sh installs them). Nothing is downloaded at configure time.
find_package(PkgConfig REQUIRED)
find_package(Threads REQUIRED)
find_package(SQLite3 REQUIRED)
find_package(OpenCV 4 REQUIRED COMPONENTS core imgproc imgcodecs videoio video features2d calib3d)
find_package(Eigen3 3.4 REQUIRED NO_MODULE)
find_package(Ceres 2 REQUIRED)
find_package(mujoco 2.2 REQUIRED)
find_package(assimp REQUIRED)
find_package(embree 3 REQUIRED)
find_package(HDF5 REQUIRED COMPONENTS C CXX)
# libzip's CMake package also demands its command-line tools; pkg-config does not.
pkg_check_modules(LIBZIP REQUIRED IMPORTED_TARGET libzip)
find_package(OpenEXR REQUIRED)
find_package(CLI11 REQUIRED)
find_package(nlohmann_json 3.11 REQUIRED)
find_package(spdlog REQUIRED)
find_package(tomlplusplus REQUIRED)
pkg_check_modules(HTTPLIB REQUIRED IMPORTED_TARGET cpp-httplib)
pkg_check_modules(LCM REQUIRED IMPORTED_TARGET lcm)
pkg_check_modules(TINYXML2 REQUIRED IMPORTED_TARGET tinyxml2)
pkg_check_modules(QHULL REQUIRED IMPORTED_TARGET qhull_r)
pkg_check_modules(LIBAV REQUIRED IMPORTED_TARGET libavformat libavcodec libswscale libavutil)
# The download stage: HTTP(S) with range requests, and SHA-256 of what it fetched.
find_package(CURL REQUIRED)
find_package(OpenSSL REQUIRED COMPONENTS Crypto)

# OpenCV's CMake package has no imported target; give it one so modules
# link it like everything else.
add_library(doasido_opencv INTERFACE)
target_include_directories(doasido_opencv SYSTEM INTERFACE ${OpenCV_INCLUDE_DIRS})
target_link_libraries(doasido_opencv INTERFACE ${OpenCV_LIBS})
add_library(deps::opencv ALIAS doasido_opencv)

# Bullet's HACD (hierarchical approximate convex decomposition) ships as a
# plain shared library with headers under bullet/.
find_library(HACD_LIBRARY NAMES HACD REQUIRED)
find_path(HACD_INCLUDE_DIR NAMES hacdHACD.h PATH_SUFFIXES bullet/HACD REQUIRED)
add_library(doasido_hacd INTERFACE)
target_include_directories(doasido_hacd SYSTEM INTERFACE ${HACD_INCLUDE_DIR})
target_link_libraries(doasido_hacd INTERFACE ${HACD_LIBRARY})
add_library(deps::hacd ALIAS doasido_hacd)

add_library(doasido_hdf5 INTERFACE)
target_include_directories(doasido_hdf5 SYSTEM INTERFACE ${HDF5_INCLUDE_DIRS})
target_link_libraries(doasido_hdf5 INTERFACE ${HDF5_LIBRARIES})
add_library(deps::hdf5 ALIAS doasido_hdf5)

# XNNPACK (the engine TFLite uses on CPU) runs the MediaPipe hand models
# natively (filters/xnnpack_graph.h); its header includes pthreadpool's.
find_library(XNNPACK_LIBRARY NAMES XNNPACK REQUIRED)
find_path(XNNPACK_INCLUDE_DIR NAMES xnnpack.h REQUIRED)
find_path(PTHREADPOOL_INCLUDE_DIR NAMES pthreadpool.h REQUIRED)
add_library(doasido_xnnpack INTERFACE)
target_include_directories(doasido_xnnpack SYSTEM INTERFACE ${XNNPACK_INCLUDE_DIR}
                                                             ${PTHREADPOOL_INCLUDE_DIR})
target_link_libraries(doasido_xnnpack INTERFACE ${XNNPACK_LIBRARY})
add_library(deps::xnnpack ALIAS doasido_xnnpack)

# DuckDB's C library for Parquet (dataset/parquet_writer.h). Debian has no
# Parquet library; scripts/setup.sh installs the pinned npm package that
# ships libduckdb.so into the npm cache folder.
set(DOASIDO_NPM_DIR "$ENV{DOASIDO_NPM_DIR}")
if(NOT DOASIDO_NPM_DIR)
  set(DOASIDO_NPM_DIR "$ENV{HOME}/.cache/doasido/npm")
endif()
find_library(DUCKDB_LIBRARY duckdb
  HINTS ${DOASIDO_NPM_DIR}/node_modules/@duckdb/node-bindings-linux-x64 NO_DEFAULT_PATH)
if(NOT DUCKDB_LIBRARY)
  message(FATAL_ERROR "libduckdb.so not found under ${DOASIDO_NPM_DIR}: run scripts/setup.sh "
                      "(it installs @duckdb/node-bindings-linux-x64 with npm)")
endif()
get_filename_component(duckdb_dir ${DUCKDB_LIBRARY} DIRECTORY)
add_library(doasido_duckdb INTERFACE)
target_link_libraries(doasido_duckdb INTERFACE ${DUCKDB_LIBRARY} "-Wl,-rpath,${duckdb_dir}")
add_library(deps::duckdb ALIAS doasido_duckdb)

find_package(GTest REQUIRED)
find_package(benchmark REQUIRED)
