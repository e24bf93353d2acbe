// libFuzzer entry for readMesh: the input bytes are written to a file whose extension is picked
// by the first byte (so that OBJ, PLY, .tris and structure detection are all reached) and read;
// only exa::Error may escape the reader.
#include "exabricks/core/error.h"
#include "exabricks/documents/mesh.h"

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <unistd.h>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const char* const extensions[] = {".obj", ".ply", ".tris", ".mesh"};
  const char* ext = extensions[size > 0 ? data[0] % 4 : 0];
  const std::string path =
      (std::filesystem::temp_directory_path() / ("exabricks-fuzz-mesh-" + std::to_string(::getpid()) + ext)).string();
  if (std::FILE* f = std::fopen(path.c_str(), "wb")) {
    const size_t written = size > 1 ? std::fwrite(data + 1, 1, size - 1, f) : 0;
    std::fclose(f);
    if (written == (size > 1 ? size - 1 : 0)) {
      try {
        const exa::TriangleMesh mesh = exa::readMesh(path);
        for (const exa::vec3i& t : mesh.triangles)
          for (int a = 0; a < 3; ++a)
            if (t[a] < 0 || size_t(t[a]) >= mesh.vertices.size()) __builtin_trap();
      } catch (const exa::Error&) {
      }
    }
    std::remove(path.c_str());
  }
  return 0;
}
