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
