# Conventions every auv-inspect package shares; find_package(auv_interfaces) brings them.

# C++17, and an optimised build with debug information unless a build type is given (OctoMap,
# OMPL and the reconstruction are ~10x slower unoptimised; colcon.meta passes the same).
macro(auv_package_defaults)
  set(CMAKE_CXX_STANDARD 17)
  set(CMAKE_CXX_STANDARD_REQUIRED ON)
  if(NOT CMAKE_BUILD_TYPE)
    set(CMAKE_BUILD_TYPE RelWithDebInfo)
  endif()
endmacro()

# GoogleTest for the package's tests, listed when ctest runs rather than after each build: at
# build time the merged install/lib (on LD_LIBRARY_PATH) may still hold this package's
# previous library.
macro(auv_enable_gtest)
  find_package(GTest REQUIRED)
  include(GoogleTest)
  set(CMAKE_GTEST_DISCOVER_TESTS_DISCOVERY_MODE PRE_TEST)
endmacro()

# The replay main of every fuzz harness (auv_add_fuzzer), beside this file here and installed.
set(AUV_FUZZ_REPLAY_MAIN ${CMAKE_CURRENT_LIST_DIR}/fuzz_replay_main.cc)

# A fuzz harness (docs/reliability.md, "Fuzzing"): one LLVMFuzzerTestOneInput per parser
# family, in the package's fuzz/<name>.cc. In every build with tests it is linked with a replay
# main (fuzz_replay_main.cc) and ctest runs it over its seeds: the files named by SEEDS (globs,
# relative to the package), the seeds it makes itself (auvFuzzSeeds()) and fuzz/regressions/<name>/
# (inputs that once crashed it, kept as regression tests). With -DAUV_FUZZ=ON (clang,
# scripts/fuzz.sh) it is also linked with libFuzzer; both binaries and the seeds are installed
# into lib/auv_fuzz and share/auv_fuzz/<name>.
#
#   auv_add_fuzzer(mission_yaml SOURCES fuzz/mission_yaml.cc LIBRARIES auv_mission_core
#                  SEEDS "missions/*.yaml")
#
# NAME must be unique in the workspace: every package installs its harnesses into lib/auv_fuzz.
function(auv_add_fuzzer name)
  cmake_parse_arguments(ARG "" "" "SOURCES;LIBRARIES;SEEDS" ${ARGN})
  set(seeds)
  foreach(pattern IN LISTS ARG_SEEDS)
    file(GLOB_RECURSE matched CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/${pattern})
    list(APPEND seeds ${matched})
  endforeach()
  set(regressions ${CMAKE_CURRENT_SOURCE_DIR}/fuzz/regressions/${name})
  if(BUILD_TESTING)
    add_executable(fuzz_${name}_replay ${ARG_SOURCES} ${AUV_FUZZ_REPLAY_MAIN})
    target_link_libraries(fuzz_${name}_replay PRIVATE ${ARG_LIBRARIES})
    add_test(NAME ${PROJECT_NAME}.fuzz_${name}
             COMMAND fuzz_${name}_replay ${seeds} ${regressions})
    set_tests_properties(${PROJECT_NAME}.fuzz_${name} PROPERTIES TIMEOUT 300 LABELS fuzz)
  endif()
  if(AUV_FUZZ)
    add_executable(fuzz_${name} ${ARG_SOURCES})
    target_link_libraries(fuzz_${name} PRIVATE ${ARG_LIBRARIES})
    target_link_options(fuzz_${name} PRIVATE -fsanitize=fuzzer)
    # Refused at install time, before anything is copied: another package's harness of this
    # name (its binary would be overwritten and never fuzzed).
    install(CODE "
      set(owner \"\${CMAKE_INSTALL_PREFIX}/share/auv_fuzz/${name}/package\")
      if(EXISTS \"\${owner}\")
        file(READ \"\${owner}\" other)
        if(NOT other STREQUAL \"${PROJECT_NAME}\")
          message(FATAL_ERROR \"fuzz harness '${name}' of ${PROJECT_NAME} is also one of \${other}: harness names must be unique in the workspace\")
        endif()
      endif()
      file(WRITE \"\${owner}\" \"${PROJECT_NAME}\")")
    install(TARGETS fuzz_${name} fuzz_${name}_replay RUNTIME DESTINATION lib/auv_fuzz)
    if(seeds)
      install(FILES ${seeds} DESTINATION share/auv_fuzz/${name}/seeds)
    endif()
    if(EXISTS ${regressions})
      install(DIRECTORY ${regressions}/ DESTINATION share/auv_fuzz/${name}/regressions)
    endif()
  endif()
endfunction()
