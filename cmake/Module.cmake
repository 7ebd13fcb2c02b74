# doasido_module(NAME <name> [DEPS <targets...>] [PRIVATE_DEPS <targets...>]
#                [SUBDIRS <folders...>])
#
# One CMake library per top-level folder. Sources are the folder's *.cc
# files; headers sit beside them and are included from the repository root
# ("db/database.h"). A folder with no sources yet becomes an INTERFACE
# library so that the dependency graph is the same from the first commit.
# DEPS are what the folder's headers expose (PUBLIC: a user compiles
# against them); PRIVATE_DEPS only its sources use. A static library still
# hands its private dependencies to the final link, but a user's sources
# cannot include them by accident. SUBDIRS are sub-folders whose *.cc
# belong to the same library (headers "retarget/scene/scene_builder.h").
# Designated initialisers that leave members at their defaults are the
# intended style, and GCC 12's -Wrestrict misfires on std::string appends.
if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
  set(DOASIDO_WARNINGS -Wall -Wextra -Wpedantic -Wshadow=local -Wnon-virtual-dtor
      -Wno-missing-field-initializers -Wno-restrict)
else()  # clang (the fuzz build) knows neither -Wshadow=local nor -Wno-restrict
  set(DOASIDO_WARNINGS -Wall -Wextra -Wpedantic -Wnon-virtual-dtor -Wno-missing-field-initializers)
endif()
if(DOASIDO_WERROR)
  list(APPEND DOASIDO_WARNINGS -Werror)
  # GCC 12 with AddressSanitizer at -O2 warns -Wmaybe-uninitialized inside
  # libstdc++'s <regex> (a known false positive): kept a warning there.
  if(DOASIDO_SANITIZE AND CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
    list(APPEND DOASIDO_WARNINGS -Wno-error=maybe-uninitialized)
  endif()
endif()

function(doasido_apply_options target)
  target_compile_options(${target} PRIVATE ${DOASIDO_WARNINGS})
  if(DOASIDO_FUZZ)
    target_compile_options(${target} PRIVATE -fsanitize=fuzzer-no-link,address,undefined
                           -fno-sanitize-recover=undefined -fno-omit-frame-pointer -g)
    target_link_options(${target} PRIVATE -fsanitize=address,undefined)
  endif()
  if(DOASIDO_SANITIZE)
    target_compile_options(${target} PRIVATE -fsanitize=address,undefined -fno-omit-frame-pointer)
    target_link_options(${target} PRIVATE -fsanitize=address,undefined)
  endif()
endfunction()

function(doasido_module)
  cmake_parse_arguments(M "" "NAME" "DEPS;PRIVATE_DEPS;SUBDIRS" ${ARGN})
  file(GLOB sources CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/*.cc)
  foreach(sub ${M_SUBDIRS})
    file(GLOB sub_sources CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/${sub}/*.cc)
    list(APPEND sources ${sub_sources})
  endforeach()
  set(target doasido_${M_NAME})
  if(sources)
    add_library(${target} STATIC ${sources})
    target_include_directories(${target} PUBLIC ${PROJECT_SOURCE_DIR})
    target_link_libraries(${target} PUBLIC ${M_DEPS} PRIVATE ${M_PRIVATE_DEPS})
    doasido_apply_options(${target})
  else()
    add_library(${target} INTERFACE)
    target_include_directories(${target} INTERFACE ${PROJECT_SOURCE_DIR})
    target_link_libraries(${target} INTERFACE ${M_DEPS} ${M_PRIVATE_DEPS})
  endif()
  add_library(doasido::${M_NAME} ALIAS ${target})
endfunction()

# A test or benchmark of a module's queue stage (its source includes
# "stages/...") links the stages library too; the source is a configure
# dependency so that adding such an include takes effect.
function(doasido_link_stages_if_included target source)
  set_property(DIRECTORY APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS ${source})
  file(READ ${source} text)
  if(text MATCHES "#include \"stages/")
    target_link_libraries(${target} PRIVATE doasido::stages)
  endif()
endfunction()
