# One precompiled header for the whole build (DOASIDO_PCH, GCC only): the
# third-party and standard headers most sources include, parsed once into
# doasido_pch's .gch and reused by every library, test and benchmark
# (doasido_apply_options calls doasido_use_pch). A source must still include
# what it uses: the PCH only saves parsing, and a build with
# -DDOASIDO_PCH=OFF (CI's check) compiles each source on its own includes.
# Clang (the fuzz build) rejects a PCH whose -D flags differ from the
# target's, so it compiles without one.
option(DOASIDO_PCH "Precompile the common heavy headers once for every target" ON)
if(DOASIDO_PCH AND NOT CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
  set(DOASIDO_PCH OFF)
endif()

function(doasido_use_pch target)
  if(DOASIDO_PCH AND NOT target STREQUAL "doasido_pch")
    target_precompile_headers(${target} REUSE_FROM doasido_pch)
  endif()
endfunction()

if(DOASIDO_PCH)
  # Headers included by about a tenth of the sources or more (grep -c), and
  # the json, log, vector and image headers nearly every source reaches
  # through core/config.h, core/log.h, core/geometry.h and video/.
  set(DOASIDO_PCH_HEADERS
      <algorithm> <array> <chrono> <cmath> <cstdint> <cstdio> <filesystem> <fstream>
      <functional> <limits> <map> <memory> <optional> <random> <set> <sstream> <string>
      <utility> <vector>
      <nlohmann/json.hpp> <spdlog/spdlog.h> <Eigen/Core> <Eigen/Geometry>
      <opencv2/core.hpp> <opencv2/imgproc.hpp>)
  file(WRITE ${PROJECT_BINARY_DIR}/doasido_pch.cc "// The source doasido_pch compiles its header for.\n")
  add_library(doasido_pch STATIC ${PROJECT_BINARY_DIR}/doasido_pch.cc)
  target_link_libraries(doasido_pch PRIVATE Eigen3::Eigen nlohmann_json::nlohmann_json spdlog::spdlog
                        deps::opencv)
  target_precompile_headers(doasido_pch PRIVATE ${DOASIDO_PCH_HEADERS})
  doasido_apply_options(doasido_pch)  # the same flags as its users, or GCC ignores the .gch
endif()
