// Writes a reader fixture for the command-line tests: write_fixture chombo OUT.3d.hdf5
#include "chombo_fixture.h"

#include <cstdio>
#include <exception>
#include <string>

int main(int argc, char** argv) {
  if (argc != 3 || std::string(argv[1]) != "chombo") {
    std::fprintf(stderr, "usage: %s chombo OUT.3d.hdf5\n", argv[0]);
    return 2;
  }
  try {
    chombo_fixture::ChomboFixture f;
    f.file = argv[2];
    f.write();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "write_fixture: %s\n", e.what());
    return 1;
  }
  return 0;
}
