// view_bench_model <survey> [triangles]: the benchmark's textured terrain (bench/README.md),
// for when the demo's textured model is not at hand.
#include <cstdlib>
#include <iostream>

#include "../test/fixtures.h"

int main(int argc, char** argv) {
  if (argc < 2) {
    std::cerr << "usage: view_bench_model <survey> [triangles (default 1500000)]\n";
    return 2;
  }
  const size_t triangles = argc > 2 ? std::strtoull(argv[2], nullptr, 10) : 1500000;
  auv::view::test::writeTerrainSurvey(argv[1], triangles);
  std::cout << argv[1] << "/textured/model.obj\n";
  return 0;
}
